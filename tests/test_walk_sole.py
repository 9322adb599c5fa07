"""Closed-loop walks of the humanoids with four-point soles (tests/sole_cases.py): the bundled
scenario run on the four-point variant of the robot's profile, judged with the thresholds of
tests/test_walk_robots.py (no fall, no fallback tick, torques finite and within the motor
limits, the commanded speed over the last 3 s within 0.15 m/s)."""

from __future__ import annotations

import numpy as np
import pytest

pytestmark = pytest.mark.slow


def _walk(name: str, scenario: str, folder) -> dict:
    from amlip_qp.control.registry import tracker_class
    from amlip_qp.sim.scenarios.factory import build_simulation, load
    from amlip_qp.sim.scenarios.named import SCENARIOS
    from sole_cases import sole_profile
    from walk_numbers import walk_numbers

    sc = SCENARIOS[scenario].with_(robot=str(sole_profile(name, folder)))
    tracker = tracker_class("qp")(load(sc.robot))
    assert tracker.builder.layout.n_points == 4
    res = build_simulation(sc, tracker).run(sc.duration_s)
    limits = np.max(np.abs(tracker.robot.actuated.torque_limit_Nm), axis=1)
    return walk_numbers(sc, res) | {"tau_within_limits": bool(np.all(np.abs(res.log["tau"]) <= limits + 1e-9))}


def test_g1_with_four_point_soles_walks_at_1mps(tmp_path):
    """G1's four foot spheres as its force points, 1.0 m/s for 10 s (measured: docs/RESULTS.md,
    "Four-point feet")."""
    r = _walk("g1", "g1-1mps", tmp_path)
    assert not r["fell"], f"fell at t = {r['sim_time_s']:.2f} s"
    assert r["sim_time_s"] >= r["duration_s"] - 1e-6
    assert r["tau_finite"] and r["tau_within_limits"] and r["fallback_ticks"] == 0
    assert abs(r["vx_mps"] - r["final_vx_mps"]) < 0.15, f"forward {r['vx_mps']:.3f} m/s"
    assert abs(r["vy_mps"]) < 0.15, f"lateral {r['vy_mps']:.3f} m/s"
