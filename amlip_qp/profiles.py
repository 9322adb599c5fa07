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
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

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
    """The physical bounds of a robot's commands (SI units; :meth:`check` names the bound it rejects).

    A command outside these bounds is out of the robot's physical reach or
    certainly a typo, so it is refused before anything is simulated. Inside
    them a walk is not guaranteed: the step-command and acceptance tests say
    what is verified.

    The bundled robots' values and why:

    - Cassie, ``vx_mps = (-1.0, 2.5)``: 2.5 m/s is the fastest walk the
      acceptance verifies (``cassie-2.5mps``, T = 0.25 s), above the paper's
      2.1 m/s on hardware, whose faster walking was limited by joint limits of
      the hand-designed swing trajectories. Backward, 1.0 m/s asks for 0.3 m
      steps behind the hip at T = 0.3 s, well within the leg's reach (the
      step-command tests verify -0.5 m/s).
    - Cassie, ``vy_max_mps = 0.5``: with the 0.25 m step width and T = 0.3 s,
      the narrow step of a lateral walk leaves the feet ``W - vy T`` = 0.10 m
      apart; faster, the legs would cross (leg collisions are not simulated).
    - Cassie, ``turn_rate_max_radps`` = 60 deg/s: the heading changes by
      18 deg per 0.3 s step, half of which each hip-yaw joint takes (the
      paper's turning rule), 9 deg of their +-22.5 deg range.
    - Rabbit, ``vx_mps = (-0.5, 1.5)``: 1.5 m/s is the top of the ``compare``
      ramp, a Froude number ``v^2 / (g l)`` of 0.29 for its 0.8 m legs, under
      the walk-run transition near 0.5. Backward, 0.5 m/s asks for 0.18 m
      steps behind the hip at T = 0.35 s (backward walking is not verified).
    - Rabbit is planar: ``vy_max_mps`` and ``turn_rate_max_radps`` are 0.
    - Both robots weigh 32-33 kg and share the duration and push bounds below.

    Attributes:
        vx_mps: ``(min, max)`` forward speed in the heading frame, m/s.
        vy_max_mps: Largest lateral speed magnitude, m/s (0 for planar robots).
        turn_rate_max_radps: Largest turn-rate magnitude, rad/s (0 for planar robots).
        duration_max_s: Longest simulated run, s. The per-tick log is
            preallocated: about 0.9 MB (Rabbit) to 1.1 MB (Cassie) per
            simulated second at the 2 kHz control rate, so 600 s stay under
            0.7 GB of memory (and take tens of minutes of wall time).
        push_impulse_max_Ns: Largest impulse of one push (force magnitude
            times duration), N s. 100 N s changes the speed of a 32-33 kg
            robot by about 3 m/s, beyond every speed it can walk at; the
            ``compare`` push search stops at 60 N s (Cassie) and 40 N s (Rabbit).
        push_force_max_N: Largest force magnitude of one push, N. 3000 N is
            about ten body weights of a 32-33 kg robot: above it a force is an
            impact, not a push.
    """

    vx_mps: tuple[float, float]
    vy_max_mps: float
    turn_rate_max_radps: float
    duration_max_s: float = 600.0
    push_impulse_max_Ns: float = 100.0
    push_force_max_N: float = 3000.0

    def __post_init__(self) -> None:
        lo, hi = self.vx_mps
        if not (math.isfinite(lo) and math.isfinite(hi) and lo <= 0.0 <= hi):
            raise InputError(
                f"CommandBounds.vx_mps must be finite (min, max) with min <= 0 <= max, got {self.vx_mps!r}"
            )
        for name in ("vy_max_mps", "turn_rate_max_radps", "duration_max_s", "push_impulse_max_Ns", "push_force_max_N"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0.0):
                raise InputError(f"CommandBounds.{name} must be a finite number >= 0, got {value!r}")

    def check(
        self,
        robot: str,
        *,
        vx_mps: Iterable[float] = (),
        vy_mps: float = 0.0,
        turn_rate_radps: float = 0.0,
        duration_s: float | None = None,
        pushes: Iterable[tuple[float, Sequence[float], float]] = (),
    ) -> None:
        """Raise :class:`InputError` naming the first bound a command breaks.

        Args:
            robot: The robot's name (for the message).
            vx_mps: Every forward speed commanded, m/s (for a piecewise-linear
                profile, its knots: the extremes are among them).
            vy_mps: Lateral speed, m/s.
            turn_rate_radps: Turn rate, rad/s.
            duration_s: Simulated time, s (``None``: not checked; pushes are then
                not checked against it).
            pushes: ``(t_s, (fx, fy, fz) N, duration_s)`` of each push; each
                must start and end within ``duration_s``.
        """
        where = "in amlip_qp.profiles"
        lo, hi = self.vx_mps
        for v in vx_mps:
            if not lo <= v <= hi:
                raise InputError(
                    f"forward speed {v:g} m/s is outside {robot}'s bounds [{lo:g}, {hi:g}] m/s "
                    f"(CommandBounds.vx_mps {where})"
                )
        if not abs(vy_mps) <= self.vy_max_mps:
            raise InputError(
                f"lateral speed {vy_mps:g} m/s is outside {robot}'s bound |vy| <= {self.vy_max_mps:g} m/s "
                f"(CommandBounds.vy_max_mps {where})"
            )
        if not abs(turn_rate_radps) <= self.turn_rate_max_radps:
            raise InputError(
                f"turn rate {math.degrees(turn_rate_radps):g} deg/s is outside {robot}'s bound "
                f"|turn rate| <= {math.degrees(self.turn_rate_max_radps):g} deg/s "
                f"(CommandBounds.turn_rate_max_radps = {self.turn_rate_max_radps:.4g} rad/s {where})"
            )
        if duration_s is not None and not duration_s <= self.duration_max_s:
            raise InputError(
                f"duration {duration_s:g} s is above {robot}'s bound {self.duration_max_s:g} s "
                f"(CommandBounds.duration_max_s {where}: the per-tick log is kept in memory)"
            )
        for t_s, force_N, push_s in pushes:
            magnitude = math.sqrt(sum(f * f for f in force_N))
            if not magnitude <= self.push_force_max_N:
                raise InputError(
                    f"push at {t_s:g} s: force {magnitude:g} N is above {robot}'s bound {self.push_force_max_N:g} N "
                    f"(CommandBounds.push_force_max_N {where})"
                )
            if not magnitude * push_s <= self.push_impulse_max_Ns:
                raise InputError(
                    f"push at {t_s:g} s: impulse {magnitude * push_s:g} N s (force x duration) "
                    f"is above {robot}'s bound {self.push_impulse_max_Ns:g} N s "
                    f"(CommandBounds.push_impulse_max_Ns {where})"
                )
            if duration_s is not None and not t_s + push_s <= duration_s + 1e-9:  # 1 ns: rounding of t + dur
                raise InputError(
                    f"push at {t_s:g} s lasting {push_s:g} s ends after the run's {duration_s:g} s; "
                    "lengthen the run or push earlier"
                )


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
        plants: Plant name -> MJCF file name among the package's models: the
            plants ``--plant`` may name (:func:`amlip_qp.sim.plant.load_plant`);
            the robot's own model is one of them, under the robot's name.
        imu_pos_in_base_m: Where the IMU sits in the base body's frame, m (its
            axes are the base body's).
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
    plants: Mapping[str, str] = field(default_factory=dict)
    imu_pos_in_base_m: tuple[float, float, float] = (0.0, 0.0, 0.0)

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
        tracker_configs={
            "pbc": "amlip_qp.control.pbc.gains:CASSIE_GAINS",
            "qp": "amlip_qp.control.wbc.config:CASSIE_CONFIG",
        },
        compare=CompareRanges(
            nominal_scenario="cassie-1mps", ramp_end_mps=2.1, push_max_impulse_Ns=60.0, relative_cost=3.0
        ),
        plants={"cassie": "cassie.xml", "cassie-closed-chain": "cassie-closed-chain.xml"},
        # The VectorNav VN-100's place in the pelvis as recalled from Agility Robotics' cassie-mujoco-sim
        # model (<site name='imu' pos='0.03155 0 -0.07996'/>, pelvis axes). It is not in the parameter
        # sheet and was not checked against that file here; the EKF takes any position.
        imu_pos_in_base_m=(0.03155, 0.0, -0.07996),
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
        tracker_configs={
            "pbc": "amlip_qp.control.pbc.gains:RABBIT_GAINS",
            "qp": "amlip_qp.control.wbc.config:RABBIT_CONFIG",
        },
        compare=CompareRanges(nominal_scenario="rabbit-0.5mps", ramp_end_mps=1.5, push_max_impulse_Ns=40.0),
        plants={"rabbit": "rabbit.xml"},
        # Rabbit has no documented IMU: one at the torso body's origin, torso axes.
        imu_pos_in_base_m=(0.0, 0.0, 0.0),
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
