"""The comparison's experiments: their settings, scenarios and searches.

:mod:`~amlip_qp.experiments.compare` runs, per robot and tracker, a nominal walk, a
speed ramp and pushes. This module defines what those runs are
(:class:`CompareSettings`, :func:`nominal_scenario`, :func:`ramp_scenario`,
:func:`push_scenario`) and the robustness measures taken from them
(:func:`highest_steady_speed`, :func:`max_survived_impulse`). The per-robot
search ranges are the robot profiles' (:class:`amlip_qp.profiles.CompareRanges`).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from amlip_qp.exceptions import InputError
from amlip_qp.profiles import CompareRanges, get_profile
from amlip_qp.sim.loop.run_types import Push, RunResult
from amlip_qp.sim.reports.summary import heading_frame_xy
from amlip_qp.sim.scenarios.named import get_scenario
from amlip_qp.sim.scenarios.scenarios import Scenario, SpeedProfile

#: Push duration of the bisection, s.
PUSH_DURATION_S = 0.2
#: Push start time of the bisection runs, s.
PUSH_TIME_S = 3.0
#: Time a pushed robot must stay up after the push ends to count as surviving, s.
PUSH_SURVIVE_S = 2.0
#: Most iterations of a bisection (:func:`largest_surviving`): 20. Each halves the interval (20 leave
#: 1e-6 of it: 57 uN s of Cassie's 60 N s push search) and is one more walk of several seconds.
MAX_BISECTION_ITERATIONS = 20


@dataclass(frozen=True)
class CompareSettings:
    """Durations of a comparison (SI units); the per-robot search ranges are the
    robot profiles' (:class:`amlip_qp.profiles.CompareRanges`).

    Attributes:
        nominal_duration_s: Cap on the nominal run's simulated time, s (``None``: the scenario's).
        ramp_duration_s: Ramp time from 0 to the profile's ``ramp_end_mps`` (starting at 1 s), s.
        ramp_hold_s: Time the final speed is held, s.
        push_time_s: When the push starts, s.
        push_survive_s: Time after the push's end the robot must stay up, s.
        push_iterations: Bisection iterations per direction.
        window_s: Moving-mean window of the highest-steady-speed test, s.
        tolerance: Relative tolerance of the highest-steady-speed test.
    """

    nominal_duration_s: float | None = 10.0
    ramp_duration_s: float = 7.0
    ramp_hold_s: float = 1.5
    push_time_s: float = PUSH_TIME_S
    push_survive_s: float = PUSH_SURVIVE_S
    push_iterations: int = 3
    window_s: float = 2.0
    tolerance: float = 0.10


#: The ``--quick`` settings: short runs, one bisection iteration (a coarse smoke test of the comparison).
QUICK = CompareSettings(
    nominal_duration_s=4.0,
    ramp_duration_s=3.0,
    ramp_hold_s=1.0,
    push_time_s=2.0,
    push_survive_s=1.0,
    push_iterations=1,
)


# --------------------------------------------------------------- metrics
def highest_steady_speed(
    result: RunResult, window_s: float = 2.0, tolerance: float = 0.10, min_speed_mps: float = 0.1
) -> float:
    """The highest speed (m/s) held within ``tolerance`` of the command on a ramp.

    For every window of ``window_s`` seconds of the run (ending at each tick,
    up to the fall or the end), compare the moving mean of the measured
    forward CoM velocity (heading frame) with the moving mean of the commanded
    ``vx``. The result is the largest commanded window mean ``>= min_speed_mps``
    whose measured mean is within ``tolerance`` (relative) of it; 0 if none.
    """
    log = result.log
    t = log["t"]
    if t.size < 2:
        return 0.0
    dt = float(np.median(np.diff(t)))
    n = int(round(window_s / dt))
    if n < 1 or t.size < n:
        return 0.0
    v = heading_frame_xy(log["com_vel"], log["heading"])[:, 0]
    cmd = np.asarray(log["cmd_vx"], dtype=float)
    kernel = np.ones(n) / n
    v_mean = np.convolve(v, kernel, mode="valid")
    c_mean = np.convolve(cmd, kernel, mode="valid")
    ok = (c_mean >= min_speed_mps) & (np.abs(v_mean - c_mean) <= tolerance * c_mean)
    return float(np.max(c_mean[ok])) if np.any(ok) else 0.0


def largest_surviving(
    survives: Callable[[float], bool], low: float, high: float, iterations: int
) -> tuple[float, bool, list[tuple[float, bool]]]:
    """The largest value in ``[low, high]`` that ``survives``, by bisection.

    ``high`` is tried first: if it survives the answer is ``high`` and capped
    (at least that much). Otherwise ``iterations`` halvings keep ``lo``
    surviving and ``hi`` failing, and the answer is ``lo`` (the true edge lies
    in ``[lo, lo + (high - low) / 2**iterations)`` for a monotone outcome).
    ``survives(low)`` is assumed true and not run (for a push impulse, ``low = 0``
    is the unpushed walk).

    Returns:
        ``(value, capped, trials)`` with ``trials`` the ``(value, survived)`` pairs in the order run.

    Raises:
        InputError: ``low >= high``, a non-finite bound, or ``iterations`` outside
            ``[0, MAX_BISECTION_ITERATIONS]``.
    """
    if not (math.isfinite(low) and math.isfinite(high) and low < high) or not (
        0 <= iterations <= MAX_BISECTION_ITERATIONS
    ):
        raise InputError(
            f"a bisection needs finite low < high and 0 <= iterations <= {MAX_BISECTION_ITERATIONS}, "
            f"got {low!r}, {high!r}, {iterations!r}"
        )
    trials: list[tuple[float, bool]] = []

    def attempt(value: float) -> bool:
        ok = bool(survives(value))
        trials.append((value, ok))
        return ok

    if attempt(float(high)):
        return float(high), True, trials
    lo, hi = float(low), float(high)
    for _ in range(iterations):
        mid = 0.5 * (lo + hi)
        if attempt(mid):
            lo = mid
        else:
            hi = mid
    return lo, False, trials


def max_survived_impulse(
    survives: Callable[[float], bool], max_impulse_Ns: float, iterations: int
) -> tuple[float, bool]:
    """Largest impulse (N s) that ``survives``, by bisection on ``[0, max_impulse_Ns]`` (:func:`largest_surviving`).

    Returns ``(max_impulse_Ns, True)`` if the upper end survives (at least that
    much), else ``(lo, False)``. ``survives(0)`` is assumed true (it is the unpushed walk).
    """
    if not (max_impulse_Ns > 0 and math.isfinite(max_impulse_Ns)) or iterations < 0:
        raise InputError(f"need max_impulse_Ns > 0 and iterations >= 0, got {max_impulse_Ns!r}, {iterations!r}")
    value, capped, _ = largest_surviving(survives, 0.0, float(max_impulse_Ns), iterations)
    return value, capped


# ------------------------------------------------------------ scenarios
def compare_ranges(robot: str) -> CompareRanges:
    """The robot profile's comparison ranges.

    Raises:
        UnknownRobotError: Not a bundled robot.
        InputError: Its profile has no comparison ranges.
    """
    ranges = get_profile(robot).compare
    if ranges is None:
        raise InputError(f"robot {robot!r} has no comparison ranges in its profile (amlip_qp.profiles)")
    return ranges


def ramp_scenario(robot: str, settings: CompareSettings) -> Scenario:
    """0 m/s for 1 s, a linear ramp to the robot's ramp speed, then hold."""
    v_end = compare_ranges(robot).ramp_end_mps
    t1 = 1.0 + settings.ramp_duration_s
    return Scenario(
        f"{robot}-ramp-{v_end:g}",
        robot,
        t1 + settings.ramp_hold_s,
        vx=SpeedProfile((0.0, 1.0, t1), (0.0, 0.0, v_end)),
        description=f"{robot} ramps to {v_end:g} m/s",
    )


def push_scenario(nominal: Scenario, impulse_Ns: float, axis: int, settings: CompareSettings) -> Scenario:
    """``nominal`` with one push of ``impulse_Ns`` along world ``axis`` (0 = x, 1 = y), cut short after it."""
    force = [0.0, 0.0, 0.0]
    force[axis] = impulse_Ns / PUSH_DURATION_S
    duration = settings.push_time_s + PUSH_DURATION_S + settings.push_survive_s
    pushes = (Push(settings.push_time_s, (force[0], force[1], force[2]), PUSH_DURATION_S),) if impulse_Ns > 0 else ()
    return nominal.with_(name=f"{nominal.name}-push", duration_s=duration, pushes=pushes)


def nominal_scenario(robot: str, names: list[str], settings: CompareSettings) -> Scenario:
    """The robot's nominal scenario: the one in ``names`` for this robot, else its profile's."""
    chosen = [get_scenario(n) for n in names]
    mine = [s for s in chosen if s.robot == robot]
    if len(mine) > 1:
        raise InputError(f"give at most one --scenario per robot; got {', '.join(s.name for s in mine)} for {robot}")
    sc = mine[0] if mine else get_scenario(compare_ranges(robot).nominal_scenario)
    if settings.nominal_duration_s is not None:
        sc = sc.with_(duration_s=min(sc.duration_s, settings.nominal_duration_s))
    return sc
