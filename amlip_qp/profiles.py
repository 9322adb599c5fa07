"""The robot profile registry: one place for everything that depends on the robot's name.

A :class:`RobotProfile` says, for one bundled robot:

- which MJCF file of the package describes it (``model_file``);
- its output layout (``output_layout``: the key of
  :data:`amlip_qp.alip.outputs.ROBOT_OUTPUTS`, also the planner's robot name)
  and whether it is planar;
- its default gait (:class:`GaitSettings`);
- the physical bounds of the commands a user may give it (:class:`CommandBounds`);
- how the velocity command is shaped before it reaches the planner
  (:class:`CommandShaping`, a rate limit as on the robot's radio);
- where each tracker's tuned configuration lives (``tracker_configs``,
  ``"module:ATTRIBUTE"``, imported only when asked for, so this module stays
  importable from every layer);
- the ranges ``amlip-qp compare`` searches (:class:`CompareRanges`).

This module imports nothing but :mod:`amlip_qp.exceptions`, so every layer may
use it (``docs/ARCHITECTURE.md``).
"""

from __future__ import annotations

import importlib
import math
from dataclasses import dataclass, field
from typing import Any, Mapping

from amlip_qp.exceptions import InputError, UnknownRobotError


@dataclass(frozen=True)
class GaitSettings:
    """The fixed gait parameters of a robot (SI units).

    Attributes:
        step_time_s: Step duration ``T``, s.
        com_height_m: CoM height over the stance contact ``H``, m.
        clearance_m: Swing clearance ``z_cl``, m.
        step_width_m: Step width ``W`` for walking in place, m (0 for planar robots).
    """

    step_time_s: float
    com_height_m: float
    clearance_m: float
    step_width_m: float


@dataclass(frozen=True)
class CommandBounds:
    """The physical bounds of a robot's commands (SI units; the CLI names the bound it rejects).

    Attributes:
        vx_mps: ``(min, max)`` forward speed in the heading frame, m/s.
        vy_max_mps: Largest lateral speed magnitude, m/s (0 for planar robots).
        turn_rate_max_radps: Largest turn-rate magnitude, rad/s (0 for planar robots).
        duration_max_s: Longest simulated run, s (the per-tick log grows with it).
        push_impulse_max_Ns: Largest impulse of one push (force magnitude times duration), N s.
        push_force_max_N: Largest force magnitude of one push, N.
    """

    vx_mps: tuple[float, float]
    vy_max_mps: float
    turn_rate_max_radps: float
    duration_max_s: float = 600.0
    push_impulse_max_Ns: float = 200.0
    push_force_max_N: float = 2000.0


@dataclass(frozen=True)
class CommandShaping:
    """How the command is shaped before it reaches the planner (as on the robot's radio).

    Rate limits: a step of a velocity command becomes a ramp at these rates; a
    command that already changes no faster passes through unchanged, bit for
    bit (:mod:`amlip_qp.alip.command_shaping`). ``inf``: no limit on that axis.

    Step-length cap: where the command's step time ``T`` would make steps
    longer than ``max_step_length_m`` at the shaped forward speed ``vx``
    (mean step length ``|vx| T``), ``T`` is shortened to
    ``max_step_length_m / |vx|``: fast walking with a higher step frequency,
    as the paper did at 2.1 m/s. ``inf``: ``T`` is never changed.

    Attributes:
        vx_accel_mps2: Largest rate of change of the forward-speed command, m/s².
        vy_accel_mps2: Largest rate of change of the lateral-speed command, m/s².
        turn_accel_radps2: Largest rate of change of the turn-rate command, rad/s².
        max_step_length_m: Longest mean step length ``|vx| T``, m.
    """

    vx_accel_mps2: float
    vy_accel_mps2: float
    turn_accel_radps2: float
    max_step_length_m: float = math.inf

    def __post_init__(self) -> None:
        for name in ("vx_accel_mps2", "vy_accel_mps2", "turn_accel_radps2", "max_step_length_m"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not value > 0:
                raise InputError(f"CommandShaping.{name} must be a positive number (inf: no limit), got {value!r}")


#: Command shaping that changes nothing (no rate limit, no step-length cap).
NO_SHAPING = CommandShaping(vx_accel_mps2=math.inf, vy_accel_mps2=math.inf, turn_accel_radps2=math.inf)


@dataclass(frozen=True)
class CompareRanges:
    """What ``amlip-qp compare`` runs for a robot.

    Attributes:
        nominal_scenario: Name of the nominal scenario (``amlip_qp.sim.scenarios``).
        ramp_end_mps: Speed the ramp test reaches, m/s.
        push_max_impulse_Ns: Upper end of the push bisection, N s.
        relative_cost: Relative wall-time cost of one simulated second (schedules the longest first).
    """

    nominal_scenario: str
    ramp_end_mps: float
    push_max_impulse_Ns: float
    relative_cost: float = 1.0


@dataclass(frozen=True)
class RobotProfile:
    """Everything that depends on a bundled robot's name (see the module doc).

    Attributes:
        name: The robot's name (``load_robot(name)``).
        model_file: File name of its MJCF model among the package's models.
        output_layout: Output layout and planner robot name (``"cassie"`` or ``"rabbit"``).
        planar: True for a robot that walks in the sagittal plane only.
        gait: Default gait.
        bounds: Command bounds.
        shaping: Command shaping (rate limits).
        tracker_configs: Tracker name -> ``"module:ATTRIBUTE"`` of its tuned configuration.
        compare: ``amlip-qp compare`` ranges.
    """

    name: str
    model_file: str
    output_layout: str
    planar: bool
    gait: GaitSettings
    bounds: CommandBounds
    shaping: CommandShaping
    tracker_configs: Mapping[str, str] = field(default_factory=dict)
    compare: CompareRanges | None = None

    def tracker_config(self, tracker: str) -> Any:
        """The tuned configuration of ``tracker`` for this robot (imported on demand).

        Raises:
            InputError: No configuration is registered for that tracker.
        """
        try:
            path = self.tracker_configs[tracker]
        except KeyError:
            known = ", ".join(self.tracker_configs) or "none"
            raise InputError(f"robot {self.name!r} has no {tracker!r} tracker configuration; known: {known}") from None
        module_name, attr = path.split(":")
        return getattr(importlib.import_module(module_name), attr)


#: The bundled robots, by name.
PROFILES: dict[str, RobotProfile] = {
    "cassie": RobotProfile(
        name="cassie",
        model_file="cassie.xml",
        output_layout="cassie",
        planar=False,
        # H is the CoM height over the foot ("toe") joint, the paper's contact point.
        gait=GaitSettings(step_time_s=0.3, com_height_m=0.80, clearance_m=0.10, step_width_m=0.25),
        bounds=CommandBounds(vx_mps=(-1.0, 2.5), vy_max_mps=0.5, turn_rate_max_radps=math.radians(60.0)),
        # vx: the steepest named ramp (cassie-1mps); vy, turn rate: no limit
        # (cassie-diagonal and cassie-turn-90 step them). Steps at most as long
        # as cassie-ramp-2.1's (2.1 m/s x 0.3 s): T = 0.252 s at 2.5 m/s.
        shaping=CommandShaping(
            vx_accel_mps2=0.5, vy_accel_mps2=math.inf, turn_accel_radps2=math.inf, max_step_length_m=0.63
        ),
        compare=CompareRanges(
            nominal_scenario="cassie-1mps", ramp_end_mps=2.1, push_max_impulse_Ns=60.0, relative_cost=3.0
        ),
    ),
    "rabbit": RobotProfile(
        name="rabbit",
        model_file="rabbit.xml",
        output_layout="rabbit",
        planar=True,
        gait=GaitSettings(step_time_s=0.35, com_height_m=0.68, clearance_m=0.06, step_width_m=0.0),
        bounds=CommandBounds(vx_mps=(-0.5, 1.5), vy_max_mps=0.0, turn_rate_max_radps=0.0),
        # vx: just above the steepest named ramp (rabbit-1mps, 1 m/s in 3 s).
        shaping=CommandShaping(vx_accel_mps2=0.35, vy_accel_mps2=math.inf, turn_accel_radps2=math.inf),
        compare=CompareRanges(nominal_scenario="rabbit-0.5mps", ramp_end_mps=1.5, push_max_impulse_Ns=40.0),
    ),
}

#: Names of the bundled robots, in registry order.
ROBOT_NAMES: tuple[str, ...] = tuple(PROFILES)


def get_profile(name: str) -> RobotProfile:
    """The profile of the bundled robot ``name``.

    Raises:
        UnknownRobotError: Not a bundled robot (the message lists them).
    """
    try:
        return PROFILES[name]
    except KeyError:
        raise UnknownRobotError(f"unknown robot {name!r}; known robots: {', '.join(PROFILES)}") from None
