"""Closed-loop acceptance of the robots beyond Cassie and Rabbit, from their profiles alone.

Each bundled humanoid walks its named scenarios (its profile's ``[scenarios]``) with the
thresholds of Cassie's acceptance (``tests/test_walk_qp.py``): no fall and no fallback tick,
the commanded speed over the last 3 s within 0.15 m/s (0.1 m/s on the diagonal), walking in
place with less than 0.3 m of drift, a 90 degree turn travelled along the new heading, still
walking forward after a push. Every run happens once (module-scoped fixture, two worker
processes) and the tests read its summary numbers.
"""

from __future__ import annotations

import math
from concurrent.futures import ProcessPoolExecutor

import numpy as np
import pytest

pytestmark = pytest.mark.slow

#: key -> (scenario name, tracker, duration s or None for the scenario's own)
RUNS: dict[str, tuple[str, str, float | None]] = {
    "h1-in-place/qp": ("h1-in-place", "qp", None),  # 20 s
    "h1-ramp-1.5/qp": ("h1-ramp-1.5", "qp", None),  # 15 s: 1.5 m/s from 10 s
    "h1-turn-90/qp": ("h1-turn-90", "qp", None),  # 12 s: 90 deg done at 8 s
    "h1-1mps-ekf/qp": ("h1-1mps-ekf", "qp", None),  # 10 s, robot sensors and the EKF
    "h1-push/qp": ("h1-push", "qp", 8.5),  # push 6.0-6.2 s, then 2.3 s
    "h1-diagonal/qp": ("h1-diagonal", "qp", 8.0),  # command reached at 2.5 s
    "h1-1mps/qp": ("h1-1mps", "qp", None),  # 10 s
    "h1-in-place/pbc": ("h1-in-place", "pbc", None),
    "h1-ramp-1.5/pbc": ("h1-ramp-1.5", "pbc", None),
    "h1-turn-90/pbc": ("h1-turn-90", "pbc", None),
    "h1-1mps-ekf/pbc": ("h1-1mps-ekf", "pbc", None),
    "h1-push/pbc": ("h1-push", "pbc", 8.5),
    "h1-diagonal/pbc": ("h1-diagonal", "pbc", 8.0),
    "h1-1mps/pbc": ("h1-1mps", "pbc", None),
    # G1: the QP tracker, and the PBC on the scenarios it walks (docs/RESULTS.md, "Unitree G1")
    "g1-in-place/pbc": ("g1-in-place", "pbc", None),
    "g1-1mps/pbc": ("g1-1mps", "pbc", None),
    "g1-turn-90/pbc": ("g1-turn-90", "pbc", None),
    "g1-diagonal/pbc": ("g1-diagonal", "pbc", None),
    "g1-in-place/qp": ("g1-in-place", "qp", None),
    "g1-ramp-1.2/qp": ("g1-ramp-1.2", "qp", None),
    "g1-turn-90/qp": ("g1-turn-90", "qp", None),
    "g1-1mps-ekf/qp": ("g1-1mps-ekf", "qp", None),
    "g1-1mps-ekf-torso-imu/qp": ("g1-1mps-ekf-torso-imu", "qp", None),  # the same, the IMU on the torso
    "g1-push/qp": ("g1-push", "qp", 8.5),
    "g1-diagonal/qp": ("g1-diagonal", "qp", 8.0),
    "g1-1mps/qp": ("g1-1mps", "qp", None),
}


def _run(key: str) -> dict:
    """Run one entry of RUNS; summary numbers only (picklable)."""
    from amlip_qp.control.registry import tracker_class
    from amlip_qp.sim.scenarios.factory import build_simulation, load
    from amlip_qp.sim.scenarios.named import SCENARIOS
    from walk_numbers import walk_numbers

    name, tracker_name, duration = RUNS[key]
    sc = SCENARIOS[name]
    if duration is not None:
        sc = sc.with_(duration_s=duration)
    tracker = tracker_class(tracker_name)(load(sc.robot))
    sim = build_simulation(sc, tracker)
    res = sim.run(sc.duration_s)
    limits = np.max(np.abs(tracker.robot.actuated.torque_limit_Nm), axis=1)
    return walk_numbers(sc, res) | {"tau_within_limits": bool(np.all(np.abs(res.log["tau"]) <= limits + 1e-9))}


@pytest.fixture(scope="module")
def results() -> dict:
    keys = list(RUNS)
    with ProcessPoolExecutor(max_workers=2) as pool:
        return dict(zip(keys, pool.map(_run, keys)))


def _walked(r: dict) -> None:
    assert not r["fell"], f"fell at t = {r['sim_time_s']:.2f} s"
    assert r["sim_time_s"] >= r["duration_s"] - 1e-6
    assert r["tau_finite"] and r["tau_within_limits"]
    assert r["fallback_ticks"] == 0


def _speed_ok(r: dict, tol: float = 0.15) -> None:
    assert abs(r["vx_mps"] - r["final_vx_mps"]) < tol, f"forward {r['vx_mps']:.3f} m/s, commanded {r['final_vx_mps']}"
    assert abs(r["vy_mps"] - r["cmd_vy_mps"]) < tol, f"lateral {r['vy_mps']:.3f} m/s, commanded {r['cmd_vy_mps']}"


#: (robot, tracker) pairs judged on every scenario: H1 with both trackers, G1 with the QP.
PAIRS = [("h1", "qp"), ("h1", "pbc"), ("g1", "qp")]
#: G1 with the PBC, judged in place, at 1 m/s, on the diagonal and the turn (it falls on the ramp to
#: 1.2 m/s, after the push and with the EKF: docs/RESULTS.md).
G1_PBC = [("g1", "pbc")]
SPEEDS = [(robot, tracker, key) for robot, tracker in PAIRS for key in ("1mps", "ramp", "1mps-ekf")]


@pytest.mark.parametrize("robot, tracker", PAIRS + G1_PBC)
def test_walks_in_place_20s_with_small_drift(results, robot, tracker):
    r = results[f"{robot}-in-place/{tracker}"]
    _walked(r)
    assert r["duration_s"] == 20.0
    assert r["drift_m"] < 0.3, f"drift {r['drift_m']:.3f} m"
    assert abs(math.degrees(r["yaw_end_rad"])) < 10.0, f"pelvis yaw {math.degrees(r['yaw_end_rad']):.1f} deg"


@pytest.mark.parametrize("robot, tracker, key", SPEEDS + [("g1", "pbc", "1mps")])
def test_walks_at_the_commanded_speed(results, robot, tracker, key):
    """1.0 m/s for 10 s (also with the robot's sensors and the EKF); the ramp over 10 s to 1.5 m/s
    (H1) or 1.2 m/s (G1), held 5 s."""
    key = {"ramp": {"h1": "ramp-1.5", "g1": "ramp-1.2"}[robot]}.get(key, key)
    r = results[f"{robot}-{key}/{tracker}"]
    _walked(r)
    _speed_ok(r)


def test_g1_walks_on_the_ekf_with_the_imu_on_its_torso(results):
    """1.0 m/s for 10 s with the robot's sensors and the EKF fed by the torso's IMU, turned to the pelvis
    (docs/EQUATIONS.md, "The IMU's mounting"; measured: a mean 0.991 m/s)."""
    r = results["g1-1mps-ekf-torso-imu/qp"]
    _walked(r)
    _speed_ok(r)


@pytest.mark.parametrize("robot, tracker", PAIRS + G1_PBC)
def test_walks_diagonally(results, robot, tracker):
    r = results[f"{robot}-diagonal/{tracker}"]
    _walked(r)
    _speed_ok(r, tol=0.1)


@pytest.mark.parametrize("robot, tracker", PAIRS + G1_PBC)
def test_turns_90_degrees_at_walking_speed(results, robot, tracker):
    r = results[f"{robot}-turn-90/{tracker}"]
    _walked(r)
    assert abs(math.degrees(r["heading_end_rad"]) - 90.0) < 0.5
    err = r["travel_dir_rad"] - r["heading_end_rad"]
    assert abs(err) < math.radians(5.0), f"travel {math.degrees(r['travel_dir_rad']):.1f} deg"
    _speed_ok(r)
    yaw_err = math.degrees(r["yaw_end_rad"] - r["heading_end_rad"])
    assert abs(yaw_err) < 10.0, f"pelvis yaw {yaw_err:.1f} deg off the heading"


@pytest.mark.parametrize("robot, tracker", PAIRS)
def test_survives_a_sagittal_push_at_1mps(results, robot, tracker):
    """H1 (51 kg): 150 N for 0.2 s; G1 (33 kg): 60 N for 0.2 s."""
    r = results[f"{robot}-push/{tracker}"]
    _walked(r)
    assert r["vx_last_1_5s_mps"] > 0.5
