"""Command shaping: a rate limit on the velocity command (as on a radio), a step-length cap, a gait schedule.

A user's ``--vx 2`` is a step from rest; the ALIP planner turns a step of the
commanded speed into one large foot placement that the legs cannot follow (the
robot falls within a few steps). A radio does not send steps: its sticks go
through a rate limiter. :class:`CommandShaper` is that limiter: it moves each
of ``vx_mps``, ``vy_mps`` and ``turn_rate_radps`` towards the raw command by
at most ``rate * dt`` per call (rates from
:class:`~amlip_qp.profiles.CommandShaping`, per robot in
:mod:`amlip_qp.profiles`; ``inf`` = no limit on that axis). The step time
may be shortened (the step-length cap, below); the other gait fields pass through.

Exact pass-through: whenever every axis of the raw command is within reach
(it changes no faster than the limit, up to a relative slack
:data:`RATE_RTOL` for the rounding of a ramp sampled at the tick times) and
its steps are not longer than the cap, the raw
:class:`~amlip_qp.messages.Command` object itself is returned, so a
command that is already a slow enough ramp reaches the planner bit for bit.
Only an axis that is out of reach is replaced, by ``previous ± rate * dt``.

Step-length cap: where the command's step time ``T`` would make the mean
step ``|vx| T`` (``vx`` shaped) longer than ``max_step_length_m``, ``T``
becomes ``max_step_length_m / |vx|`` (faster walking with a higher step
frequency). A command whose steps are not longer than the cap (up to the same
relative slack) keeps its ``T``.

Gait schedule: above the first row's speed of
:attr:`~amlip_qp.profiles.CommandShaping.gait_scale_by_speed`, the command's
step time ``T``, CoM height ``H`` and clearance ``z_cl`` are scaled with the
shaped ``|vx|`` (:func:`gait_scales`), before the step-length cap. At a fixed
``T`` the steps grow with the speed and straighten the legs, and the swing
hip's torque grows as ``|vx| / T``; a schedule trades them (the numbers behind
a robot's schedule: ``docs/TUNING.md``). At or below the first row's speed
the command's gait is kept, so the walks there are unchanged bit for bit.

The shaped command starts at rest (zero velocities) at the first
:meth:`CommandShaper.update` after :meth:`CommandShaper.reset`: the robot
starts standing, so a first command of 2 m/s becomes a ramp from 0.
"""

from __future__ import annotations

import math
from dataclasses import replace

from amlip_qp.exceptions import InputError
from amlip_qp.messages import Command
from amlip_qp.profiles import CommandShaping

#: Relative slack of the reach test: a raw change up to ``rate * dt * (1 + RATE_RTOL)``
#: passes unchanged. A ramp of exactly the limiting rate, sampled at MuJoCo's
#: accumulated tick times, differs from ``rate * dt`` by about 1e-12 relative.
RATE_RTOL = 1e-9

#: The shaped fields of :class:`Command`, in the order of :attr:`CommandShaper.value`.
SHAPED_FIELDS = ("vx_mps", "vy_mps", "turn_rate_radps")


class CommandShaper:
    """Rate limiter of the velocity command and step-length cap of the step time (module doc).

    Args:
        shaping: The rate limits and the cap (:class:`~amlip_qp.profiles.CommandShaping`).

    Raises:
        InputError: ``shaping`` is not a :class:`CommandShaping`.
    """

    def __init__(self, shaping: CommandShaping):
        if not isinstance(shaping, CommandShaping):
            raise InputError(f"CommandShaper needs a CommandShaping (rate limits), got {type(shaping).__name__}")
        self.shaping = shaping
        self._rates = (shaping.vx_accel_mps2, shaping.vy_accel_mps2, shaping.turn_accel_radps2)
        # the axes without a limit (passed through) and those with one, with their rates
        self._free = tuple(i for i, rate in enumerate(self._rates) if rate == math.inf)
        self._limited = tuple((i, rate) for i, rate in enumerate(self._rates) if rate != math.inf)
        self._value = [0.0, 0.0, 0.0]
        self._t_s: float | None = None

    @property
    def value(self) -> tuple[float, float, float]:
        """The last shaped ``(vx_mps, vy_mps, turn_rate_radps)`` (m/s, m/s, rad/s); zeros after :meth:`reset`."""
        v = self._value
        return (v[0], v[1], v[2])

    def reset(self) -> None:
        """Back to rest: the next :meth:`update` starts from zero velocities."""
        self._value = [0.0, 0.0, 0.0]
        self._t_s = None

    def update(self, command: Command, t_s: float) -> Command:
        """The shaped command at time ``t_s`` (s).

        The first call after :meth:`reset` starts from rest with ``dt = 0``:
        an axis with a finite rate passes only if its raw value is 0.

        Returns:
            ``command`` itself when every axis is within reach and the steps
            are not longer than the cap, else a copy with the out-of-reach
            axes moved by ``rate * dt`` towards the raw values and ``T`` capped.

        Raises:
            InputError: ``command`` is not a :class:`Command`, ``t_s`` is not
                finite, or it is earlier than the previous call's (call
                :meth:`reset` for a new run).
        """
        if not isinstance(command, Command):
            raise InputError(f"CommandShaper.update needs a Command, got {type(command).__name__}")
        if isinstance(t_s, bool) or not isinstance(t_s, (int, float)) or not math.isfinite(t_s):
            raise InputError(f"CommandShaper.update needs a finite time t_s, got {t_s!r}")
        t_s = float(t_s)
        dt = 0.0 if self._t_s is None else t_s - self._t_s
        if dt < 0.0:
            raise InputError(
                f"CommandShaper.update: time went back from {self._t_s!r} s to {t_s!r} s; call reset() for a new run"
            )
        self._t_s = t_s
        raw = (command.vx_mps, command.vy_mps, command.turn_rate_radps)
        value = self._value
        changes: dict[str, float] = {}
        for i in self._free:
            value[i] = raw[i]
        for i, rate in self._limited:
            target = raw[i]
            step = rate * dt
            diff = target - value[i]
            if abs(diff) <= step * (1.0 + RATE_RTOL):
                value[i] = target
            else:
                value[i] = value[i] + math.copysign(step, diff)
                changes[SHAPED_FIELDS[i]] = value[i]
        speed = abs(value[0])
        rows = self.shaping.gait_scale_by_speed
        T = command.step_time_s
        if rows and speed > rows[0][0]:
            T_scale, H_scale, cl_scale = gait_scales(rows, speed)
            T = T * T_scale
            changes["step_time_s"] = T
            changes["com_height_m"] = command.com_height_m * H_scale
            changes["clearance_m"] = command.clearance_m * cl_scale
        L_max = self.shaping.max_step_length_m
        if speed * T > L_max * (1.0 + RATE_RTOL):
            changes["step_time_s"] = L_max / speed
        if not changes:
            return command
        return replace(command, **changes)


def gait_scales(rows: tuple[tuple[float, float, float, float], ...], speed_mps: float) -> tuple[float, float, float]:
    """The ``(T, H, z_cl)`` scales of a gait schedule at the forward speed ``speed_mps`` (m/s) (module doc).

    ``rows``: ``(speed m/s, T scale, H scale, z_cl scale)``, speeds increasing
    (:attr:`~amlip_qp.profiles.CommandShaping.gait_scale_by_speed`); the first
    row's scales below its speed, linear between the rows, the last row's after it.
    """
    v0, *s0 = rows[0]
    if speed_mps <= v0:
        return s0[0], s0[1], s0[2]
    for v1, *s1 in rows[1:]:
        if speed_mps <= v1:
            w = (speed_mps - v0) / (v1 - v0)
            return s0[0] + (s1[0] - s0[0]) * w, s0[1] + (s1[1] - s0[1]) * w, s0[2] + (s1[2] - s0[2]) * w
        v0, s0 = v1, s1
    return s0[0], s0[1], s0[2]
