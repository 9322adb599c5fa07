"""The trackers by name: each lives in its own module, imported only when asked for.

The CLI and the tests do not pay for (or depend on) a tracker they do not
use. A tracker class is found in its module (:data:`TRACKER_MODULES`) as the
:class:`~amlip_qp.control.tracker.Tracker` subclass whose ``name`` attribute
is the requested name.
"""

from __future__ import annotations

import importlib
import inspect
from collections.abc import Callable
from typing import cast

from amlip_qp.control.tracker import Tracker
from amlip_qp.exceptions import InputError
from amlip_qp.robots.robot import Robot

#: Tracker name -> module that defines it.
TRACKER_MODULES: dict[str, str] = {
    "pbc": "amlip_qp.control.pbc.tracker",
    "qp": "amlip_qp.control.wbc.tracker",
}


def tracker_class(name: str) -> type[Tracker]:
    """The tracker class called ``name`` (``"pbc"`` or ``"qp"``).

    Raises:
        InputError: Unknown name, or its module is not available (yet).
    """
    if name not in TRACKER_MODULES:
        raise InputError(f"unknown tracker {name!r}; known: {', '.join(TRACKER_MODULES)}")
    module_name = TRACKER_MODULES[name]
    try:
        module = importlib.import_module(module_name)
    except ModuleNotFoundError as exc:
        if exc.name == module_name:
            raise InputError(f"the {name!r} tracker is not available: module {module_name} is missing") from None
        raise
    for _, obj in inspect.getmembers(module, inspect.isclass):
        if issubclass(obj, Tracker) and obj is not Tracker and getattr(obj, "name", None) == name:
            return obj
    raise InputError(f"the {name!r} tracker is not available: {module_name} defines no Tracker named {name!r}")


def make_tracker(name: str, robot: Robot) -> Tracker:
    """A new tracker ``name`` for ``robot`` (constructed as ``cls(robot)``)."""
    # The abstract base declares no constructor; every registered tracker takes the robot
    # as its only required argument (TRACKER_MODULES' classes, checked by the tests).
    cls = cast("Callable[[Robot], Tracker]", tracker_class(name))
    return cls(robot)
