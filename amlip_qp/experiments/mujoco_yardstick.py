"""MuJoCo's step time alone on a fixed walking state: the machine-speed yardstick of the speed goals.

The speed goals compare this code with older code (``examples/speed_against.py``,
``amlip-qp bench harness``) on a shared machine whose speed drifts, so each
walk's wall time is also divided by a yardstick measured in the same process:
the time of one ``mujoco.mj_step`` replayed alone, on copies of the state at
the end of a short walk (:func:`snapshot_walk`, :func:`step_time_us`). It
does not depend on the code under test, unlike MuJoCo's time inside the
walking loop, where the rest of the tick evicts MuJoCo's data from the caches
(the step costs about twice as much there, and a leaner loop leaves it
faster). But it lasts about 25 ms, so it swings with the machine's load
(10-35 µs a step seen on the loaded 2-core machine, up to 180 µs with four
times as many busy processes as cores), where the step inside the loop
follows the walk's own conditions. :func:`step_median_us` times every step
on its own and takes the median, as the controller's tick medians do: a
step preempted by another process is an outlier there, not part of a mean.

This file uses only ``copy``, ``statistics``, ``time`` and ``mujoco``, and
``examples/speed_against.py`` runs this file's source inside the walks of
the older code too, so every version is measured with the same recipe.
"""

from __future__ import annotations

import copy
import statistics
import time

import mujoco

#: Default replays: ``ROUNDS`` rounds of ``STEPS`` steps, each from a fresh copy of the state.
STEPS, ROUNDS = 200, 9


def snapshot_walk(walk) -> tuple:
    """Call ``walk()`` (one closed-loop walk) and return ``(model, data)``: MuJoCo's model and a
    copy of its data after the walk's last step, caught by wrapping ``mujoco.mj_step`` meanwhile."""
    step = mujoco.mj_step
    seen: list[tuple] = []

    def catching(m, d):
        step(m, d)
        if not seen:
            seen.append((m, d))

    mujoco.mj_step = catching
    try:
        walk()
    finally:
        mujoco.mj_step = step
    if not seen:
        raise RuntimeError("the walk made no MuJoCo step")
    m, d = seen[0]
    return m, copy.copy(d)


def step_time_us(model, data, steps: int = STEPS, rounds: int = ROUNDS) -> float:
    """Median over ``rounds`` of the mean wall time of one ``mj_step`` (µs), each round replaying
    ``steps`` steps from a fresh copy of ``data`` (which stays unchanged), controls held."""
    step, clock, per_round = mujoco.mj_step, time.perf_counter_ns, []
    for _ in range(rounds):
        d = copy.copy(data)
        t0 = clock()
        for _ in range(steps):
            step(model, d)
        per_round.append((clock() - t0) * 1e-3 / steps)
    return statistics.median(per_round)


def step_median_us(model, data, steps: int = STEPS, rounds: int = ROUNDS) -> float:
    """Median wall time of one ``mj_step`` (µs) over ``rounds`` x ``steps`` steps, each timed on its
    own, each round replaying ``steps`` steps from a fresh copy of ``data`` (which stays unchanged)."""
    step, clock, times = mujoco.mj_step, time.perf_counter_ns, []
    for _ in range(rounds):
        d = copy.copy(data)
        for _ in range(steps):
            t0 = clock()
            step(model, d)
            times.append(clock() - t0)
    return statistics.median(times) * 1e-3
