"""amlip_qp: angular-momentum (ALIP) foot placement with whole-body QP tracking.

Walk a robot on your own MuJoCo model (the README's quickstart)::

    import mujoco
    import amlip_qp

    robot = amlip_qp.load_robot("cassie")
    model, data = robot.mj_model, robot.new_mj_data("stand")
    loop = amlip_qp.MujocoLoop(robot, amlip_qp.QPTracker(robot), model, data)
    for _ in range(4000):
        loop.step(loop.command(vx_mps=0.5))
        mujoco.mj_step(model, data)

The names here are imported on first use, so ``import amlip_qp`` loads neither
MuJoCo nor Pinocchio:

- :func:`load_robot`, :class:`Robot` (:mod:`amlip_qp.robots`): one MJCF file
  compiled by MuJoCo and Pinocchio, described from its profile.
- :class:`WalkingController` (:mod:`amlip_qp.control.walking`), fed a
  :class:`Measurement` and a :class:`Command` each tick, around a tracker:
  :class:`QPTracker` (:mod:`amlip_qp.control.wbc`) or :class:`PBCTracker`
  (:mod:`amlip_qp.control.pbc`).
- :class:`MujocoLoop` (:mod:`amlip_qp.sim.loop.mujoco_loop`): that controller on a
  ``mujoco.MjModel`` and ``mujoco.MjData`` you step.
- The typed errors of :mod:`amlip_qp.exceptions`.

The layers below: :mod:`amlip_qp.alip` (the pure ALIP planner math),
:mod:`amlip_qp.codegen` (its generated C), :mod:`amlip_qp.robots`,
:mod:`amlip_qp.control`, :mod:`amlip_qp.sim` (the MuJoCo harness); see
docs/ARCHITECTURE.md.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING

from amlip_qp.exceptions import (
    AmlipError,
    CodegenError,
    InputError,
    InvalidQPError,
    MJCFError,
    ModelFileError,
    QPError,
    UnknownRobotError,
)

if TYPE_CHECKING:  # pragma: no cover - typing only
    from amlip_qp.control.pbc.tracker import PBCTracker
    from amlip_qp.control.walking.controller import WalkingController
    from amlip_qp.control.wbc.tracker import QPTracker
    from amlip_qp.messages import Command, Measurement
    from amlip_qp.robots.loader import load_robot
    from amlip_qp.robots.robot import Robot
    from amlip_qp.sim.loop.mujoco_loop import MujocoLoop

__version__ = "0.1.0"

__all__ = [
    "AmlipError",
    "CodegenError",
    "Command",
    "InputError",
    "InvalidQPError",
    "MJCFError",
    "Measurement",
    "ModelFileError",
    "MujocoLoop",
    "PBCTracker",
    "QPError",
    "QPTracker",
    "Robot",
    "UnknownRobotError",
    "WalkingController",
    "__version__",
    "load_robot",
]


#: Each lazy export -> the module that defines it (imported on first use).
_LAZY: dict[str, str] = {
    "Command": "amlip_qp.messages",
    "Measurement": "amlip_qp.control.walking.estimator",
    "MujocoLoop": "amlip_qp.sim.loop.mujoco_loop",
    "PBCTracker": "amlip_qp.control.pbc.tracker",
    "QPTracker": "amlip_qp.control.wbc.tracker",
    "Robot": "amlip_qp.robots.robot",
    "WalkingController": "amlip_qp.control.walking.controller",
    "load_robot": "amlip_qp.robots.loader",
}


def __getattr__(name: str):
    """Lazy re-exports, so ``import amlip_qp`` does not import MuJoCo or Pinocchio."""
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module 'amlip_qp' has no attribute {name!r}")
    return getattr(importlib.import_module(module), name)


def __dir__() -> list[str]:
    return sorted(__all__)
