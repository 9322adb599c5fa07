"""The step-timing MPC with the PBC tracker on Cassie in MuJoCo: it plans no step shorter than the PBC follows.

A forward push of 45 N s (225 N for 0.2 s at 3 s, walking at 1 m/s): with the MPC's own shortest step
(0.6 T = 0.18 s, the QP's) the PBC's swing leg lagged its targets and Cassie fell at 3.80 s; with the
PBC's shortest step (its profile's ``shortest_step_s``, 0.21 s) the steps after the push last 0.24-0.28 s
and it walks on, as with the one-step law, though faster than commanded: 2.2 s after the push it still
walks at about 3 m/s, where the one-step law is back at 1 m/s (docs/TUNING.md, "The PBC's shortest step").
"""

from __future__ import annotations

from concurrent.futures import ProcessPoolExecutor

import pytest

pytestmark = pytest.mark.slow

PUSH_N, PUSH_T_S, DURATION_S = 225.0, 3.0, 5.2


def _run(shortest_step_s: float | None) -> dict:
    """The pushed cassie-1mps walk with the PBC and the MPC; ``shortest_step_s`` replaces the profile's."""
    from dataclasses import replace

    from amlip_qp.control.pbc.gains import default_gains
    from amlip_qp.control.pbc.tracker import PBCTracker
    from amlip_qp.sim.loop.run_types import Push
    from amlip_qp.sim.scenarios.factory import build_simulation, load
    from amlip_qp.sim.scenarios.named import SCENARIOS

    sc = SCENARIOS["cassie-1mps"].with_(duration_s=DURATION_S, pushes=(Push(PUSH_T_S, (PUSH_N, 0.0, 0.0), 0.2),))
    robot = load("cassie")
    gains = default_gains(robot)
    if shortest_step_s is not None:
        gains = replace(gains, shortest_step_s=shortest_step_s)
    sim = build_simulation(sc, PBCTracker(robot, gains), planner="mpc")
    res = sim.run(sc.duration_s, log="summary")
    return {
        "fell": bool(res.fell),
        "shortest_step_s": sim.controller.planner.settings.step_time_min_s,
        "after_push_s": [s.t_end_s - s.t_start_s for s in sim.controller.steps if s.t_start_s > PUSH_T_S - 0.3],
    }


@pytest.fixture(scope="module")
def results() -> dict:
    with ProcessPoolExecutor(max_workers=2) as pool:
        return dict(zip(("profile", "none"), pool.map(_run, (None, 0.0))))


def test_with_the_mpcs_own_shortest_step_the_pbc_falls(results):
    assert results["none"]["shortest_step_s"] == 0.0
    assert results["none"]["fell"]
    assert min(results["none"]["after_push_s"]) < 0.22  # the steps it planned down to 0.18 s


def test_with_the_pbcs_shortest_step_it_walks_on(results):
    run = results["profile"]
    assert run["shortest_step_s"] == 0.21  # the profile's [trackers.pbc] shortest_step_s
    assert not run["fell"]
    assert min(run["after_push_s"]) >= 0.21  # no step shorter than the PBC follows
