"""The commands a robot may be given: their physical bounds, what is verified, and how they are shaped.

All are data of a robot's profile (:mod:`amlip_qp.profiles`), tables
``[bounds]``, ``[verified]`` and ``[shaping]`` of its profile file. Three zones:
a command inside the verified envelope (:class:`VerifiedEnvelope`) is what the
acceptance scenarios walk; between it and the physical bounds
(:class:`CommandBounds`) it runs with one
:class:`~amlip_qp.exceptions.UnverifiedCommandWarning`; outside the physical
bounds it is refused (:class:`~amlip_qp.exceptions.InputError`).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

from amlip_qp.exceptions import InputError


@dataclass(frozen=True)
class CommandBounds:
    """The physical bounds of a robot's commands (SI units; :meth:`check` names the bound it rejects).

    A command outside these bounds is out of the robot's physical reach or
    certainly a typo, so it is refused before anything is simulated. Inside
    them a walk is not guaranteed: :class:`VerifiedEnvelope` says what is
    verified.

    The speed and turn-rate bounds are derived from the robot's legs
    (:func:`amlip_qp.robots.reach.derive_command_bounds`: reach at the CoM
    height, the widest foot spread and the hip-yaw range, at the shortest
    step time ``step_time_min_s``); each robot's values, and how they were
    derived, are in its profile file (``[bounds]``), and a test holds them to
    the derivation.

    Attributes:
        vx_mps: ``(min, max)`` forward speed in the heading frame, m/s.
        vy_max_mps: Largest lateral speed magnitude, m/s (0 for planar robots).
        turn_rate_max_radps: Largest turn-rate magnitude, rad/s (0 for planar robots).
        duration_max_s: Longest simulated run, s. The per-tick log is
            preallocated: about 1 MB per simulated second at the 2 kHz
            control rate for a 20-joint robot, so 600 s stay under 0.7 GB of
            memory (and take tens of minutes of wall time).
        push_impulse_max_Ns: Largest impulse of one push (force magnitude
            times duration), N s. 100 N s changes the speed of a 32-33 kg
            robot by about 3 m/s, beyond every speed it can walk at; a heavier
            robot's profile raises it.
        push_force_max_N: Largest force magnitude of one push, N. 3000 N is
            about ten body weights of a 32-33 kg robot: above it a force is an
            impact, not a push.
        step_time_min_s: The shortest step time the speed bounds are derived at, s
            (the robot's fastest stepping); ``None``: the profile gait's step time.
    """

    vx_mps: tuple[float, float]
    vy_max_mps: float
    turn_rate_max_radps: float
    duration_max_s: float = 600.0
    push_impulse_max_Ns: float = 100.0
    push_force_max_N: float = 3000.0
    step_time_min_s: float | None = None

    def __post_init__(self) -> None:
        t = self.step_time_min_s
        if t is not None and not (math.isfinite(t) and t > 0.0):
            raise InputError(f"CommandBounds.step_time_min_s must be a positive number of seconds, got {t!r}")
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
class VerifiedEnvelope:
    """The commands a robot's acceptance scenarios verify (SI units), inside its :class:`CommandBounds`.

    A command between this envelope and the physical bounds runs, with one
    :class:`~amlip_qp.exceptions.UnverifiedCommandWarning` (:meth:`unverified`
    says why). The default, of a profile without ``[verified]``, verifies
    standing in place only.

    Attributes:
        vx_mps: ``(min, max)`` forward speed the acceptance walks, m/s.
        vy_max_mps: Largest lateral speed magnitude it walks, m/s.
        turn_rate_max_radps: Largest turn-rate magnitude it walks, rad/s.
    """

    vx_mps: tuple[float, float] = (0.0, 0.0)
    vy_max_mps: float = 0.0
    turn_rate_max_radps: float = 0.0

    def __post_init__(self) -> None:
        lo, hi = self.vx_mps
        if not (math.isfinite(lo) and math.isfinite(hi) and lo <= 0.0 <= hi):
            raise InputError(
                f"VerifiedEnvelope.vx_mps must be finite (min, max) with min <= 0 <= max, got {self.vx_mps!r}"
            )
        for name in ("vy_max_mps", "turn_rate_max_radps"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0.0):
                raise InputError(f"VerifiedEnvelope.{name} must be a finite number >= 0, got {value!r}")

    def within(self, bounds: CommandBounds) -> bool:
        """Whether the envelope lies inside ``bounds`` (a profile's must)."""
        lo, hi = self.vx_mps
        blo, bhi = bounds.vx_mps
        return (
            blo <= lo
            and hi <= bhi
            and self.vy_max_mps <= bounds.vy_max_mps
            and self.turn_rate_max_radps <= bounds.turn_rate_max_radps
        )

    def unverified(
        self, robot: str, *, vx_mps: Iterable[float] = (), vy_mps: float = 0.0, turn_rate_radps: float = 0.0
    ) -> str | None:
        """One line naming every command outside the envelope, or ``None`` when all are inside.

        Args:
            robot: The robot's name (for the message).
            vx_mps: Every forward speed commanded, m/s (a profile's knots).
            vy_mps: Lateral speed, m/s.
            turn_rate_radps: Turn rate, rad/s.
        """
        out = []
        lo, hi = self.vx_mps
        speeds = list(vx_mps)
        fast = [v for v in speeds if not lo <= v <= hi]
        if fast:
            worst = max(fast, key=lambda v: max(v - hi, lo - v))
            out.append(f"forward speed {worst:g} m/s (verified {lo:g} to {hi:g} m/s)")
        if abs(vy_mps) > self.vy_max_mps:
            out.append(f"lateral speed {vy_mps:g} m/s (verified |vy| <= {self.vy_max_mps:g} m/s)")
        if abs(turn_rate_radps) > self.turn_rate_max_radps:
            out.append(
                f"turn rate {math.degrees(turn_rate_radps):g} deg/s "
                f"(verified <= {math.degrees(self.turn_rate_max_radps):g} deg/s)"
            )
        if not out:
            return None
        return (
            f"{', '.join(out)}: inside {robot}'s physical bounds but not verified by its acceptance "
            "(profile [verified]); running it anyway"
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

    Gait schedule: rows ``(speed, T scale, H scale, z_cl scale)`` with the
    shaped forward speed ``|vx|``; the command's step time ``T``, CoM height
    ``H`` and clearance ``z_cl`` are multiplied by the scales, linear between
    the rows and held after the last. The first row's scales are 1 and at or
    below its speed the command passes unchanged. Why a robot may want one: at
    a fixed ``T`` the steps ``|vx| T`` grow with the speed and straighten the
    legs (a lower ``H`` gives them the reach), and the swing foot's travel
    ``2 |vx| T`` in ``T`` asks the swing hip for a torque that grows as
    ``|vx| / T`` (a longer ``T`` lowers it). ``()``: no schedule.

    Attributes:
        vx_accel_mps2: Largest rate of change of the forward-speed command, m/s².
        vy_accel_mps2: Largest rate of change of the lateral-speed command, m/s².
        turn_accel_radps2: Largest rate of change of the turn-rate command, rad/s².
        max_step_length_m: Longest mean step length ``|vx| T``, m.
        gait_scale_by_speed: Rows ``(|vx| m/s, T scale, H scale, z_cl scale)``, speeds
            increasing, the first row's scales 1, every scale positive (dimensionless).
    """

    vx_accel_mps2: float
    vy_accel_mps2: float
    turn_accel_radps2: float
    max_step_length_m: float = math.inf
    gait_scale_by_speed: tuple[tuple[float, float, float, float], ...] = ()

    def __post_init__(self) -> None:
        for name in ("vx_accel_mps2", "vy_accel_mps2", "turn_accel_radps2", "max_step_length_m"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not value > 0:
                raise InputError(f"CommandShaping.{name} must be a positive number (inf: no limit), got {value!r}")
        check_gait_schedule(self.gait_scale_by_speed)


def check_gait_schedule(rows: object) -> None:
    """Raise :class:`InputError` unless ``rows`` is a valid :attr:`CommandShaping.gait_scale_by_speed`."""

    def number(v: object) -> bool:
        return not isinstance(v, bool) and isinstance(v, (int, float)) and math.isfinite(v)

    def bad(why: str) -> InputError:
        return InputError(f"CommandShaping.gait_scale_by_speed: {why}, got {rows!r}")

    if not isinstance(rows, tuple):
        raise bad("must be a tuple of (speed m/s, T scale, H scale, clearance scale) rows")
    if not rows:
        return
    if len(rows) < 2 or not all(isinstance(r, tuple) and len(r) == 4 and all(map(number, r)) for r in rows):
        raise bad("needs at least two rows of 4 finite numbers (speed m/s, T scale, H scale, clearance scale)")
    speeds = [r[0] for r in rows]
    if speeds[0] < 0.0 or any(b <= a for a, b in zip(speeds, speeds[1:])):
        raise bad("the speeds must be >= 0 and increasing")
    if rows[0][1:] != (1.0, 1.0, 1.0):
        raise bad("the first row's scales must be 1 (the gait's own up to its speed)")
    if not all(min(r[1:]) > 0.0 for r in rows):
        raise bad("every scale must be positive")


#: Command shaping that changes nothing (no rate limit, no step-length cap).
NO_SHAPING = CommandShaping(vx_accel_mps2=math.inf, vy_accel_mps2=math.inf, turn_accel_radps2=math.inf)
