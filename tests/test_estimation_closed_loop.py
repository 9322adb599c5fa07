"""The contact-aided invariant EKF in the closed loop: its accuracy goal on a plant it was not built from.

Cassie with the QP tracker walks 1 m/s for 20 s on the closed-chain plant
(``cassie-closed-chain``) with the robot's own sensors (noisy, biased IMU;
quantised encoders; noisy force-threshold contact switches) and the EKF giving
the controller its base state. The estimate is compared with the simulator's
truth at every tick: the base velocity error RMS (world, m/s) at most 0.05 m/s,
the yaw drift at the end at most 2 degrees, and the estimate never diverges
(no safe-mode tick). Equivalent to::

    amlip-qp walk --robot cassie --tracker qp --vx 1.0 --duration 20 \\
        --plant cassie-closed-chain --sensors robot --estimator ekf
"""

from __future__ import annotations

import pytest

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def summary() -> dict:
    from amlip_qp.sim.reports.summary import summarize
    from amlip_qp.sim.scenarios.factory import run_scenario
    from amlip_qp.sim.scenarios.scenarios import Scenario, SpeedProfile, check_scenario

    scenario = Scenario("custom", "cassie", 20.0).with_(vx=SpeedProfile.constant(1.0))
    check_scenario(scenario)
    result = run_scenario(scenario, "qp", plant="cassie-closed-chain", sensors="robot", estimator="ekf")
    return summarize(result)


def test_it_walks_the_whole_20_s_at_1_mps(summary):
    assert not summary["fell"]
    assert summary["sim_time_s"] == pytest.approx(20.0, abs=1e-6)
    assert summary["mean_velocity"][0] == pytest.approx(1.0, abs=0.1)


def test_the_estimate_never_diverges(summary):
    assert summary["safe_mode_ticks"] == 0
    assert summary["estimator_divergences"] == 0


def test_the_base_velocity_error_rms_is_at_most_5_cm_per_s(summary):
    assert summary["base_velocity_error_rms_mps"] <= 0.05


def test_the_yaw_drifts_at_most_2_degrees_in_20_s(summary):
    assert summary["yaw_estimate_error_deg"] <= 2.0
