"""Acceptance on a plant the controller was not built from.

Every Cassie acceptance scenario runs on the hardware-like setting
Cassie's ``cc-ekf`` setting (its profile's ``[settings.cc-ekf]``) -- the closed-chain plant
(achilles and plantar rods closed by equality constraints), the robot's own
sensors (IMU with noise and drifting biases, quantised encoders, noisy contact
switches; no base state) and the contact-aided invariant EKF -- with both
trackers, and the QP tracker also walks ``cassie-1mps-cc-ekf`` for 10 s under
each model mismatch of its profile's ``[mismatches]``. The
thresholds are those of the ideal acceptance (tests/test_walk_pbc.py and
tests/test_walk_qp.py). Mean speed = mean CoM velocity over the last 3 s in
the heading frame, from the simulator's truth.

Each run happens once (module-scoped fixture, two worker processes, longest
first).
"""

from __future__ import annotations

import math
from concurrent.futures import ProcessPoolExecutor

import numpy as np
import pytest

pytestmark = pytest.mark.slow

#: Scenario -> duration in s (``None``: the scenario's own), shortened where the check allows.
DURATIONS: dict[str, float | None] = {
    "cassie-in-place": None,  # 20 s
    "cassie-2.5mps": None,  # 16 s: 2.5 m/s from 13 s
    "cassie-ramp-2.1": None,  # 15 s: 2.1 m/s from 10 s
    "cassie-turn-90": None,  # 12 s: 90 deg done at 8 s
    "cassie-push": None,  # 10 s: push 6.0-6.2 s
    "cassie-1mps": None,  # 10 s
    "cassie-diagonal": 8.0,  # command reached at 2.5 s
}

#: (scenario, tracker) -> duration in s (``None``: the scenario's own).
RUNS: dict[tuple[str, str], float | None] = {
    **{(f"{name}-cc-ekf", "qp"): duration for name, duration in DURATIONS.items()},
    **{(f"{name}-cc-ekf", "pbc"): duration for name, duration in DURATIONS.items()},
    **{(f"cassie-1mps-cc-ekf-{key}", "qp"): None for key in ("mass-0.8", "mass-1.2", "payload-5kg", "friction-0.5")},
    ("cassie-1mps-cc-ekf-delay-1", "qp"): None,
}

SPEED_TOL_MPS = 0.15


def _run(job: tuple[str, str]) -> dict:
    """One run of RUNS; its numbers only (picklable)."""
    from amlip_qp.sim.reports.summary import summarize
    from amlip_qp.sim.scenarios.factory import run_scenario
    from amlip_qp.sim.scenarios.named import SCENARIOS

    name, tracker = job
    sc = SCENARIOS[name]
    duration = RUNS[job]
    if duration is not None:
        sc = sc.with_(duration_s=duration)
    res = run_scenario(sc, tracker)
    s = summarize(res)
    log = res.log
    last = log["t"] > log["t"][-1] - 3.0
    D = log["heading"][last]
    vel = log["com_vel"][last]
    yaw = np.unwrap(log["base_yaw"])
    k10 = min(int(round(10.0 / 0.0005)), len(yaw) - 1)
    return {
        "setting": (s["plant"], s["sensors"], s["estimator"]),
        "duration_s": float(sc.duration_s),
        "final_vx_mps": float(sc.vx.final_mps),
        "cmd_vy_mps": float(sc.vy_mps),
        "fell": bool(res.fell),
        "sim_time_s": float(res.sim_time_s),
        "vx_mps": float(np.mean(vel[:, 0] * np.cos(D) + vel[:, 1] * np.sin(D))),
        "vy_mps": float(np.mean(-vel[:, 0] * np.sin(D) + vel[:, 1] * np.cos(D))),
        "drift_m": float(np.linalg.norm(log["com"][-1, :2] - log["com"][0, :2])),
        "heading_end_rad": float(log["heading"][-1]),
        "yaw_change_10s_rad": float(yaw[k10] - yaw[0]),
        "tau_finite": bool(np.all(np.isfinite(log["tau"]))),
        "fallback_ticks": int(res.fallback_ticks),
        "safe_mode_ticks": int(s["safe_mode_ticks"]),
        "estimator_divergences": int(s["estimator_divergences"]),
        "tracker_ok_fraction": float(np.mean(log["tracker_ok"])),
        "base_velocity_error_rms_mps": s["base_velocity_error_rms_mps"],
    }


@pytest.fixture(scope="module")
def results() -> dict:
    from amlip_qp.sim.scenarios.named import SCENARIOS

    jobs = sorted(RUNS, key=lambda j: -(RUNS[j] or SCENARIOS[j[0]].duration_s))
    with ProcessPoolExecutor(max_workers=2) as pool:
        return dict(zip(jobs, pool.map(_run, jobs)))


def _walked(r: dict) -> None:
    """On the hardware-like setting, no fall over the whole run, finite torques, no fallback, no safe mode."""
    assert r["setting"] == ("cassie-closed-chain", "robot", "ekf")
    assert not r["fell"], f"fell at t = {r['sim_time_s']:.2f} s"
    assert r["sim_time_s"] >= r["duration_s"] - 1e-6
    assert r["tau_finite"]
    assert r["fallback_ticks"] == 0
    assert r["safe_mode_ticks"] == 0 and r["estimator_divergences"] == 0
    assert r["tracker_ok_fraction"] > 0.99


def _speed_ok(r: dict) -> None:
    assert abs(r["vx_mps"] - r["final_vx_mps"]) < SPEED_TOL_MPS, (
        f"forward {r['vx_mps']:.3f} m/s, commanded {r['final_vx_mps']}"
    )
    assert abs(r["vy_mps"] - r["cmd_vy_mps"]) < SPEED_TOL_MPS, (
        f"lateral {r['vy_mps']:.3f} m/s, commanded {r['cmd_vy_mps']}"
    )


@pytest.mark.parametrize("tracker", ["qp", "pbc"])
def test_walks_in_place_20s_with_small_drift(results, tracker):
    r = results[("cassie-in-place-cc-ekf", tracker)]
    _walked(r)
    assert r["duration_s"] == 20.0
    assert r["drift_m"] < 0.3, f"drift {r['drift_m']:.3f} m"


@pytest.mark.parametrize("tracker", ["qp", "pbc"])
@pytest.mark.parametrize("name", ["cassie-1mps", "cassie-diagonal"])
def test_walks_at_the_commanded_velocity(results, tracker, name):
    r = results[(f"{name}-cc-ekf", tracker)]
    _walked(r)
    _speed_ok(r)


@pytest.mark.parametrize("tracker", ["qp", "pbc"])
@pytest.mark.parametrize("name", ["cassie-ramp-2.1", "cassie-2.5mps"])
def test_holds_the_fast_commands(results, tracker, name):
    r = results[(f"{name}-cc-ekf", tracker)]
    _walked(r)
    _speed_ok(r)


@pytest.mark.parametrize("tracker", ["qp", "pbc"])
def test_turns_90_degrees_within_10s(results, tracker):
    r = results[("cassie-turn-90-cc-ekf", tracker)]
    _walked(r)
    assert math.degrees(r["heading_end_rad"]) == pytest.approx(90.0, abs=0.5)
    assert math.degrees(r["yaw_change_10s_rad"]) == pytest.approx(90.0, abs=10.0)
    assert 0.5 <= r["vx_mps"] <= 1.0
    _speed_ok(r)


@pytest.mark.parametrize("tracker", ["qp", "pbc"])
def test_survives_a_100N_push_at_1mps(results, tracker):
    r = results[("cassie-push-cc-ekf", tracker)]
    _walked(r)
    _speed_ok(r)  # over the last 3 s, 0.8 s after the push ended


@pytest.mark.parametrize("tracker", ["qp", "pbc"])
def test_the_ekf_base_velocity_is_accurate_while_walking_at_1mps(results, tracker):
    """The EKF's base velocity against the simulator's truth, RMS over the 10 s run (goal: 0.05 m/s)."""
    r = results[("cassie-1mps-cc-ekf", tracker)]
    assert r["base_velocity_error_rms_mps"] <= 0.05


@pytest.mark.parametrize("key", ["mass-0.8", "mass-1.2", "payload-5kg", "friction-0.5", "delay-1"])
def test_qp_walks_1mps_for_10s_under_model_mismatch(results, key):
    r = results[(f"cassie-1mps-cc-ekf-{key}", "qp")]
    _walked(r)
    assert r["duration_s"] == 10.0
    _speed_ok(r)


def _ramp_from_a_raised_start(k: int) -> tuple[bool, float]:
    """The QP's closed-chain 2.1 m/s ramp started with the base k * 1e-12 m higher: (fell, forward speed over
    the last 3 s in the heading frame, m/s)."""
    from amlip_qp.sim.reports.summary import mean_velocity_heading
    from amlip_qp.sim.scenarios.factory import build_simulation
    from amlip_qp.sim.scenarios.named import SCENARIOS

    sc = SCENARIOS["cassie-ramp-2.1-cc-ekf"]
    sim = build_simulation(sc, "qp")
    sim.data.qpos[2] += k * 1e-12
    res = sim.run(sc.duration_s, log="summary")
    return bool(res.fell), float(mean_velocity_heading(res, 3.0)[0])


def test_the_qp_ramp_does_not_depend_on_rounding(results):
    """Starts 1e-12 and 2e-12 m higher end the ramp as the suite's own start does, within 0.02 m/s of 2.1 m/s.

    Before the QP damped the swing leg's spring rate harder (``CASSIE_CONFIG.coupling_kd`` 40 -> 60 1/s; the
    closed chain's swing shin spring rang at about 22 Hz at speed) such starts ended at 1.877 and 1.932 m/s
    with the QP build that gathers its inputs, the suite's own at 2.039 (docs/TUNING.md).
    """
    with ProcessPoolExecutor(max_workers=2) as pool:
        runs = list(pool.map(_ramp_from_a_raised_start, (1, 2)))
    speeds = [v for _, v in runs] + [results[("cassie-ramp-2.1-cc-ekf", "qp")]["vx_mps"]]
    assert len(set(speeds)) == 3, f"the raised starts did not change the run: {speeds}"
    assert not any(fell for fell, _ in runs)
    assert max(abs(v - 2.1) for v in speeds) < 0.02, f"end speeds {speeds} m/s"
