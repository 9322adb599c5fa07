"""Closed-loop acceptance of the step-timing MPC planner on Cassie with the QP tracker in MuJoCo.

A forward push of 70 N s (350 N for 0.2 s at 3 s, walking at 1 m/s): the one-step law at its
fixed step time falls, the MPC shortens the steps after the push and walks on
(docs/RESULTS.md, "The step-timing MPC against the one-step law"). Lateral pushes of 50 N s
either way: the MPC walks on with crossover steps (with the feet kept apart it fell from 30 N s;
docs/TUNING.md, "The lateral limits").
"""

from __future__ import annotations

from concurrent.futures import ProcessPoolExecutor

import pytest

pytestmark = pytest.mark.slow

PUSH_N, PUSH_T_S, DURATION_S = 350.0, 3.0, 6.0


def _run(planner: str, force_N: tuple[float, float, float] = (PUSH_N, 0.0, 0.0)) -> dict:
    """The cassie-1mps walk pushed by ``force_N`` at 3 s with ``planner``; summary numbers only (picklable)."""
    from amlip_qp.sim.loop.run_types import Push
    from amlip_qp.sim.scenarios.factory import build_simulation
    from amlip_qp.sim.scenarios.named import SCENARIOS

    sc = SCENARIOS["cassie-1mps"].with_(duration_s=DURATION_S, pushes=(Push(PUSH_T_S, force_N, 0.2),))
    sim = build_simulation(sc, "qp", planner=planner)
    res = sim.run(sc.duration_s, log="summary")
    steps = sim.controller.steps
    return {
        "fell": bool(res.fell),
        "after_push_s": [s.t_end_s - s.t_start_s for s in steps if s.t_start_s > PUSH_T_S],
        "vx_end_mps": [float(s.com_vel_end_mps[0]) for s in steps if s.t_start_s > PUSH_T_S],
        "failures": int(getattr(sim.controller.planner, "failures", 0)),
        "crossed_m": _largest_crossing(steps, PUSH_T_S),
    }


def _largest_crossing(steps, after_s: float) -> float:
    """How far (m) a landing foot came down past the stance foot across the heading, at most, after ``after_s``."""
    import math

    out = 0.0
    for prev, step in zip(steps, steps[1:]):
        if step.t_start_s <= after_s:
            continue
        s = 1.0 if step.stance == "right" else -1.0  # +1: the left foot lands
        left = (-math.sin(step.heading_rad), math.cos(step.heading_rad))
        d = step.swing_actual_m[:2] - prev.swing_actual_m[:2]
        out = max(out, -s * (d[0] * left[0] + d[1] * left[1]))
    return out


@pytest.fixture(scope="module")
def results() -> dict:
    with ProcessPoolExecutor(max_workers=2) as pool:
        return dict(zip(("one-step", "mpc"), pool.map(_run, ("one-step", "mpc"))))


LATERAL_N = 250.0  # 50 N s in 0.2 s


@pytest.fixture(scope="module")
def lateral() -> dict:
    with ProcessPoolExecutor(max_workers=2) as pool:
        runs = pool.map(_run, ("mpc", "mpc"), ((0.0, LATERAL_N, 0.0), (0.0, -LATERAL_N, 0.0)))
        return dict(zip(("left", "right"), runs))


def test_the_one_step_law_falls_from_the_push(results):
    assert results["one-step"]["fell"]


def test_the_mpc_recovers_from_it_with_shorter_steps(results):
    mpc = results["mpc"]
    assert not mpc["fell"] and mpc["failures"] == 0
    durations, vx = mpc["after_push_s"], mpc["vx_end_mps"]
    assert max(vx) > 3.0  # the push took the CoM past 3 m/s
    assert max(durations[:6]) < 0.25  # the steps after it shortened from 0.3 s (bound 0.18 s)
    assert vx[-1] < 1.5 and durations[-1] == pytest.approx(0.3, abs=0.01)  # back near 1 m/s at the nominal step


@pytest.mark.parametrize("side", ["left", "right"])
def test_the_mpc_recovers_from_a_lateral_push_with_crossover_steps(lateral, side):
    run = lateral[side]
    assert not run["fell"] and run["failures"] == 0
    assert run["crossed_m"] > 0.05  # a landing foot came down past the stance foot
    assert run["after_push_s"][-1] == pytest.approx(0.3, abs=0.01)  # back at the nominal step
