"""amlip_qp: angular-momentum (ALIP) foot placement with whole-body QP tracking.

The layers, from the bottom up:

- :mod:`amlip_qp.alip`: the pure ALIP planner math (numpy only, no robot model).
- :mod:`amlip_qp.codegen`: CasADi definitions of the planner functions, the
  generated C in ``amlip_qp/codegen/generated/`` (package data), and a fast caller.
- :mod:`amlip_qp.robots`: the MJCF models loaded into MuJoCo (plant) and
  Pinocchio (controller model), state conversion and model-side kinematics.
"""

from amlip_qp.exceptions import (
    AmlipError,
    CodegenError,
    InputError,
    MJCFError,
    ModelFileError,
    QPError,
    UnknownRobotError,
)

__version__ = "0.1.0"

__all__ = [
    "AmlipError",
    "CodegenError",
    "InputError",
    "MJCFError",
    "ModelFileError",
    "QPError",
    "UnknownRobotError",
    "__version__",
    "load_robot",
]


def __getattr__(name: str):
    """Lazy re-exports, so ``import amlip_qp`` does not import MuJoCo or Pinocchio."""
    if name == "load_robot":
        from amlip_qp.robots.loader import load_robot

        return load_robot
    raise AttributeError(f"module 'amlip_qp' has no attribute {name!r}")
