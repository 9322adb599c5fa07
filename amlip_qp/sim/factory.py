"""Assemble a closed loop (robot, tracker, controller, plant) from names.

The trackers live in their own modules (:data:`TRACKER_MODULES`) and are
imported only when asked for, so the CLI and the tests do not pay for (or
depend on) a tracker they do not use.
A tracker class is found in its module as the :class:`~amlip_qp.control.tracker.Tracker`
subclass whose ``name`` attribute is the requested name.
"""

from __future__ import annotations

import functools
import importlib
import inspect
from collections.abc import Callable
from typing import TYPE_CHECKING, cast

from amlip_qp.control.tracker import Tracker
from amlip_qp.exceptions import InputError
from amlip_qp.sim.harness import Simulation
from amlip_qp.sim.run_types import RunResult, SensorNoise, TickCallback
from amlip_qp.sim.scenarios import Scenario

if TYPE_CHECKING:  # pragma: no cover - typing only
    from amlip_qp.robots.robot import Robot

#: Tracker name -> module that defines it.
TRACKER_MODULES: dict[str, str] = {
    "pbc": "amlip_qp.control.pbc.tracker",
    "qp": "amlip_qp.control.wbc.tracker",
}


@functools.cache
def load(robot_name: str) -> Robot:
    """The :class:`~amlip_qp.robots.robot.Robot` named ``robot_name`` (loaded once per process)."""
    from amlip_qp.robots import load_robot

    return load_robot(robot_name)


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


def build_simulation(
    scenario: Scenario,
    tracker: str | Tracker,
    seed: int = 0,
    noise: SensorNoise | None = None,
    planner_backend: str = "c",
) -> Simulation:
    """The :class:`Simulation` of ``scenario`` with ``tracker`` (a name or an instance).

    Args:
        scenario: Robot, commands, pushes, duration and command shaping.
        tracker: ``"pbc"``, ``"qp"``, or a ready :class:`Tracker` instance
            (e.g. a test stand-in; it must be built for the scenario's robot).
        seed: Seed of the sensor-noise generator.
        noise: Sensor noise, or ``None`` for exact measurements.
        planner_backend: ``"c"`` (generated kernels) or ``"numpy"``.
    """
    from amlip_qp.control.walking.controller import WalkingController
    from amlip_qp.robots import RobotKinematics

    robot = load(scenario.robot)
    trk = make_tracker(tracker, robot) if isinstance(tracker, str) else tracker
    if not isinstance(trk, Tracker):
        raise InputError(f"tracker must be a name or a Tracker instance, got {type(trk).__name__}")
    kin = RobotKinematics(robot)
    controller = WalkingController(robot, trk, kin, planner_backend=planner_backend, command_shaping=scenario.shaping)
    return Simulation(robot, controller, scenario.command, pushes=scenario.pushes, noise=noise, seed=seed)


def run_scenario(
    scenario: Scenario,
    tracker: str | Tracker,
    seed: int = 0,
    noise: SensorNoise | None = None,
    progress: bool = False,
    on_tick: TickCallback | None = None,
) -> RunResult:
    """Build and run ``scenario`` for its full duration (see :func:`build_simulation`)."""
    sim = build_simulation(scenario, tracker, seed=seed, noise=noise)
    result = sim.run(scenario.duration_s, progress=progress, on_tick=on_tick)
    result.info["scenario"] = scenario.name
    return result
