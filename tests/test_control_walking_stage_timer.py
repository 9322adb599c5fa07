"""The walking controller's stage timer: one entry per tick that ran the tracker, nothing else changed."""

import numpy as np

from amlip_qp.control.pbc.tracker import PBCTracker
from amlip_qp.control.walking.controller import WalkingController
from amlip_qp.control.walking.gait import swing_contact_weight
from amlip_qp.control.walking.stage_timer import StageTimer
from amlip_qp.control.wbc.tracker import QPTracker
from amlip_qp.messages import Command, Measurement
from amlip_qp.robots import load_robot


def _ticks(timer, ticks=8, nan_at=None, tracker=QPTracker):
    cassie = load_robot("cassie")
    controller = WalkingController(cassie, tracker(cassie), stage_timer=timer)
    gait = cassie.profile.gait
    command = Command(
        step_time_s=gait.step_time_s, com_height_m=gait.com_height_m, clearance_m=gait.clearance_m, vx_mps=0.5
    )
    rng = np.random.default_rng(5)
    taus = []
    for k in range(ticks):
        q, v = cassie.q_stand.copy(), rng.normal(0.0, 0.05, cassie.nv)
        if k == nan_at:
            q[0] = np.nan
        taus.append(controller.step(Measurement(k * controller.dt_s, q, v), command).tau_Nm)
    return np.array(taus)


def test_the_timer_gets_every_stage_of_every_tick_and_changes_no_torque():
    timer = StageTimer()
    timed = _ticks(timer)
    assert len(timer.kinematics_us) == len(timer.tracker_us) == len(timer.estimate_us) == len(timer.plan_us) == 8
    assert all(t > 0.0 for t in timer.kinematics_us + timer.tracker_us + timer.estimate_us + timer.plan_us)
    assert timer.tracker_work_us == [k + t for k, t in zip(timer.kinematics_us, timer.tracker_us)]
    # the QP tracker's own build and solve times (its info), each a part of its compute
    assert len(timer.build_us) == len(timer.solve_us) == 8
    assert all(0.0 < b + s < t for b, s, t in zip(timer.build_us, timer.solve_us, timer.tracker_us))
    np.testing.assert_array_equal(timed, _ticks(None))
    timer.clear()
    assert timer.kinematics_us == timer.tracker_us == timer.tracker_work_us == timer.build_us == timer.solve_us == []
    assert timer.estimate_us == timer.plan_us == []


def test_the_pbc_times_its_ik_compensation_and_dynamics_within_its_compute():
    timer = StageTimer()
    timed = _ticks(timer, tracker=PBCTracker)
    parts = list(zip(timer.ik_us, timer.compensation_us, timer.dynamics_us, timer.tracker_us))
    assert len(parts) == 8 and all(min(i, c, d) > 0.0 and i + c + d < t for i, c, d, t in parts)
    assert np.isnan(timer.build_us).all() and np.isnan(timer.solve_us).all()  # the QP's parts
    np.testing.assert_array_equal(timed, _ticks(None, tracker=PBCTracker))
    qp = StageTimer()
    _ticks(qp, ticks=3)
    assert np.isnan(qp.ik_us + qp.compensation_us + qp.dynamics_us).all()
    qp.clear()
    assert qp.ik_us == qp.compensation_us == qp.dynamics_us == []


def test_a_part_the_tracker_does_not_time_is_nan():
    timer = StageTimer()
    timer.record(2000, 9000, {"solve_us": 4.5, "build_us": float("inf")})
    timer.record(2000, 9000, {"build_us": True})
    timer.record(2000, 9000)
    assert timer.solve_us[0] == 4.5 and np.isnan(timer.solve_us[1:]).all()
    assert np.isnan(timer.estimate_us).all() and np.isnan(timer.plan_us).all()  # stages the caller did not time
    assert np.isnan(timer.build_us).all()
    assert timer.tracker_work_us == [11.0, 11.0, 11.0]


def test_a_safe_mode_tick_runs_no_tracker_and_records_nothing():
    timer = StageTimer()
    _ticks(timer, ticks=6, nan_at=3)
    assert len(timer.tracker_us) == 5


def test_the_swing_contact_weight_rises_over_the_last_tenth_of_the_step():
    weights = [swing_contact_weight(s) for s in (0.0, 0.9, 0.95, 1.0, 1.3)]
    np.testing.assert_allclose(weights, [0.0, 0.0, 0.5, 1.0, 1.0], rtol=0, atol=1e-12)
    assert swing_contact_weight(float("nan")) == 0.0
