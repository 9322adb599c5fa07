"""Closed-loop acceptance of the step-timing MPC planner on Cassie with the QP tracker in MuJoCo.

A forward push of 70 N s (350 N for 0.2 s at 3 s, walking at 1 m/s): the one-step law at its
fixed step time falls, the MPC shortens the steps after the push and walks on
(docs/RESULTS.md, "The step-timing MPC against the one-step law").
"""

from __future__ import annotations

from concurrent.futures import ProcessPoolExecutor

import pytest

pytestmark = pytest.mark.slow

PUSH_N, PUSH_T_S, DURATION_S = 350.0, 3.0, 6.0


def _run(planner: str) -> dict:
    """The pushed cassie-1mps walk with ``planner``; summary numbers only (picklable)."""
    from amlip_qp.sim.loop.run_types import Push
    from amlip_qp.sim.scenarios.factory import build_simulation
    from amlip_qp.sim.scenarios.named import SCENARIOS

    sc = SCENARIOS["cassie-1mps"].with_(duration_s=DURATION_S, pushes=(Push(PUSH_T_S, (PUSH_N, 0.0, 0.0), 0.2),))
    sim = build_simulation(sc, "qp", planner=planner)
    res = sim.run(sc.duration_s, log="summary")
    steps = sim.controller.steps
    return {
        "fell": bool(res.fell),
        "after_push_s": [s.t_end_s - s.t_start_s for s in steps if s.t_start_s > PUSH_T_S],
        "vx_end_mps": [float(s.com_vel_end_mps[0]) for s in steps if s.t_start_s > PUSH_T_S],
        "failures": int(getattr(sim.controller.planner, "failures", 0)),
    }


@pytest.fixture(scope="module")
def results() -> dict:
    with ProcessPoolExecutor(max_workers=2) as pool:
        return dict(zip(("one-step", "mpc"), pool.map(_run, ("one-step", "mpc"))))


def test_the_one_step_law_falls_from_the_push(results):
    assert results["one-step"]["fell"]


def test_the_mpc_recovers_from_it_with_shorter_steps(results):
    mpc = results["mpc"]
    assert not mpc["fell"] and mpc["failures"] == 0
    durations, vx = mpc["after_push_s"], mpc["vx_end_mps"]
    assert max(vx) > 3.0  # the push took the CoM past 3 m/s
    assert max(durations[:6]) < 0.25  # the steps after it shortened from 0.3 s (bound 0.18 s)
    assert vx[-1] < 1.5 and durations[-1] == pytest.approx(0.3, abs=0.01)  # back near 1 m/s at the nominal step
