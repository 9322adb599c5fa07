"""Closed-loop acceptance of the baseline tracker (IK + PBC) in MuJoCo.

Each scenario of :data:`amlip_qp.sim.scenarios.SCENARIOS` listed below runs
once (two worker processes, one per core) and the tests check its numbers.
Mean speed = mean CoM velocity over the last 3 s, in the heading frame.
"""

from __future__ import annotations

from concurrent.futures import ProcessPoolExecutor

import numpy as np
import pytest

pytestmark = pytest.mark.slow

#: The scenarios this file checks (see the tests for the thresholds).
RUNS = ("cassie-in-place", "cassie-1mps", "rabbit-0.5mps", "rabbit-1mps")


def _run(name: str) -> dict:
    """Run one scenario with the PBC tracker; summary numbers only (picklable)."""
    from amlip_qp.control.controller import WalkingController
    from amlip_qp.control.pbc import PBCTracker
    from amlip_qp.robots import load_robot
    from amlip_qp.robots.kinematics import RobotKinematics
    from amlip_qp.sim.harness import Simulation
    from amlip_qp.sim.scenarios import SCENARIOS

    sc = SCENARIOS[name]
    robot = load_robot(sc.robot)
    kin = RobotKinematics(robot)
    ctrl = WalkingController(robot, PBCTracker(robot), kin)
    res = Simulation(robot, ctrl, sc.command, pushes=sc.pushes).run(sc.duration_s)
    log = res.log
    last = log["t"] > log["t"][-1] - 3.0
    D = log["heading"][last]
    vel = log["com_vel"][last]
    return {
        "fell": bool(res.fell),
        "sim_time_s": float(res.sim_time_s),
        "vx_mps": float(np.mean(vel[:, 0] * np.cos(D) + vel[:, 1] * np.sin(D))),
        "vy_mps": float(np.mean(-vel[:, 0] * np.sin(D) + vel[:, 1] * np.cos(D))),
        "world_vel_mps": np.mean(vel[:, :2], axis=0),
        "drift_m": float(np.linalg.norm(log["com"][-1, :2] - log["com"][0, :2])),
        "heading_end_rad": float(log["heading"][-1]),
        "heading": log["heading"].copy(),
        "t": log["t"].copy(),
        "tracker_ok_fraction": float(np.mean(log["tracker_ok"])),
        "tick_median_us": float(np.median(res.tick_time_us)),
        "tick_p99_us": float(np.percentile(res.tick_time_us, 99)),
    }


@pytest.fixture(scope="module")
def results() -> dict:
    with ProcessPoolExecutor(max_workers=2) as pool:
        return dict(zip(RUNS, pool.map(_run, RUNS)))


def _walked(r: dict) -> None:
    assert not r["fell"], f"fell at t = {r['sim_time_s']:.2f} s"
    assert r["tracker_ok_fraction"] > 0.99


def test_cassie_walks_in_place_20s_with_small_drift(results):
    r = results["cassie-in-place"]
    _walked(r)
    assert r["sim_time_s"] >= 20.0 - 1e-6
    assert r["drift_m"] < 0.3


def test_cassie_walks_at_1mps(results):
    r = results["cassie-1mps"]
    _walked(r)
    assert abs(r["vx_mps"] - 1.0) < 0.15
    assert abs(r["vy_mps"]) < 0.15


@pytest.mark.parametrize("name, speed", [("rabbit-0.5mps", 0.5), ("rabbit-1mps", 1.0)])
def test_rabbit_walks_20s_at_speed(results, name, speed):
    r = results[name]
    _walked(r)
    assert r["sim_time_s"] >= 20.0 - 1e-6
    assert abs(r["vx_mps"] - speed) < 0.15

