"""Tests of the passivity-based tracker (amlip_qp.control.pbc.tracker)."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pinocchio as pin
import pytest

from amlip_qp.control.pbc.gains import PBCGains, default_gains
from amlip_qp.control.pbc.springs import spring_deflections_rad
from amlip_qp.control.pbc.tracker import PBCTracker
from amlip_qp.control.tracker import TrackingTarget
from amlip_qp.robots import load_robot
from amlip_qp.robots.kinematics import RobotKinematics
from amlip_qp.robots.outputs import OutputMap


@pytest.fixture(scope="module", params=["cassie", "rabbit"])
def robot(request):
    return load_robot(request.param)


def _state(robot, seed):
    rng = np.random.default_rng(seed)
    q = robot.q_stand.copy()
    q[robot.actuated.pin_q_idx] += rng.normal(0.0, 0.02, robot.nu)
    v = rng.normal(0.0, 0.3, robot.nv)
    return q, v


def _encoder_tracker(robot):
    """The default gains with the springs held at their estimates in the IK (no spring model) and no
    pelvis-yaw feedback: then references equal to the measured outputs give zero tracking errors."""
    gains = dataclasses.replace(default_gains(robot), spring_model_offset=False, hip_yaw_feedback=0.0)
    return PBCTracker(robot, gains=gains)


def _target_at_estimate(kin, stance, phase=0.5):
    """References equal to the current outputs and their rates: zero tracking errors."""
    h, J, jdv = kin.outputs(stance, 0.0)
    return TrackingTarget(stance=stance, phase=phase, heading_rad=0.0, h_d=h, dh_d=J @ kin.v, ddh_d=np.zeros_like(h))


@pytest.mark.parametrize("stance", ["left", "right"])
def test_torques_reproduce_the_constrained_inverse_dynamics(robot, stance):
    """With zero errors, M vdot + h - tau_pas = B tau + J_c^T lambda and J_c vdot + Jdot v = 0
    hold with the recovered lambda, and the controlled joints get the commanded accelerations."""
    q, v = _state(robot, 11)
    kin = RobotKinematics(robot)
    kin.update(q, v)
    tracker = _encoder_tracker(robot)
    res = tracker.compute(kin, _target_at_estimate(kin, stance))
    assert res.ok and np.all(np.isfinite(res.tau_Nm))
    # the IK reproduces the estimate: zero position errors
    lay = tracker.layout(stance)
    assert res.info["tracking_error_rad"] < 1e-8
    ik = tracker.ik.last_result
    vdot_cmd = ik.a_r[lay.ctrl_v] + lay.kd * (ik.v_r[lay.ctrl_v] - v[lay.ctrl_v])
    vdot, tau_c, lam = tracker.solve_dynamics(kin, stance, vdot_cmd)
    np.testing.assert_allclose(tau_c, res.tau_Nm[lay.ctrl], atol=1e-8)
    # recompute the dynamics independently with Pinocchio's RNEA
    tau_full = np.zeros(robot.nv)
    tau_full[robot.actuated.pin_v_idx] = res.tau_Nm
    Jc, jdv = tracker.constraints(kin, stance)
    data = robot.pin_model.createData()
    rnea = pin.rnea(robot.pin_model, data, q, v, vdot)  # Pinocchio 3+: armature included
    residual = rnea - kin.passive_forces() - tau_full - Jc.T @ lam
    assert np.max(np.abs(residual)) < 1e-8
    np.testing.assert_allclose(Jc @ vdot + jdv, 0.0, atol=1e-9)
    np.testing.assert_allclose(vdot[lay.ctrl_v], vdot_cmd, atol=1e-9)
    # the stance ankle of Cassie is passive: zero torque
    if not robot.is_planar:
        k = robot.actuated.joint_names.index(f"{stance}-foot")
        assert res.tau_Nm[k] == 0.0


def test_static_standing_needs_about_the_weight_on_the_stance_foot(robot):
    kin = RobotKinematics(robot)
    kin.update(robot.q_stand, np.zeros(robot.nv))
    tracker = _encoder_tracker(robot)
    res = tracker.compute(kin, _target_at_estimate(kin, "left"))
    assert res.ok
    # single-support model on the standing pose: the stance foot carries the weight
    # plus the (zero here) vertical acceleration of the CoM
    assert res.info["contact_force_z_N"] == pytest.approx(robot.mass_kg * 9.81, rel=0.05)


@pytest.mark.parametrize("bad", ["nan_h", "nan_phase", "inf_weight"])
def test_never_nan_on_degenerate_input(robot, bad):
    kin = RobotKinematics(robot)
    q, v = _state(robot, 12)
    kin.update(q, v)
    tracker = PBCTracker(robot)
    tgt = _target_at_estimate(kin, "left")
    if bad == "nan_h":
        tgt.h_d = np.full_like(tgt.h_d, np.nan)
    elif bad == "nan_phase":
        tgt.phase = float("nan")
    else:
        tgt.swing_contact_weight = float("inf")
    res = tracker.compute(kin, tgt)
    assert np.all(np.isfinite(res.tau_Nm))
    assert res.tau_Nm.shape == (robot.nu,)
    if bad == "nan_h":
        assert not res.ok and res.fallback == "ik_failed"


def test_singular_dynamics_falls_back(robot, monkeypatch):
    kin = RobotKinematics(robot)
    kin.update(robot.q_stand, np.zeros(robot.nv))
    tracker = PBCTracker(robot)

    def singular(*_args, **_kw):
        raise np.linalg.LinAlgError("singular")

    monkeypatch.setattr(tracker, "solve_dynamics", singular)
    res = tracker.compute(kin, _target_at_estimate(kin, "right"))
    assert not res.ok and res.fallback == "singular_dynamics"
    assert np.all(np.isfinite(res.tau_Nm))


def test_swing_torso_compensation_moves_the_swing_leg_to_the_measured_torso():
    """Cassie: with a torso error, the swing joints' references become (to first order) those of
    the IK solved for the measured torso orientation; the stance joints' stay on the reference."""
    robot = load_robot("cassie")
    kin = RobotKinematics(robot)
    q, v = _state(robot, 13)
    kin.update(q, v)
    stance = "left"
    h, J, _ = kin.outputs(stance, 0.0)
    h_d = h.copy()
    h_d[0] -= 0.03  # torso pitch reference 0.03 rad behind the measured pitch
    h_d[1] += 0.02  # and roll
    dh = np.zeros_like(h)
    tgt = TrackingTarget(stance=stance, phase=0.5, heading_rad=0.0, h_d=h_d, dh_d=dh, ddh_d=dh)
    on = PBCTracker(robot, gains=PBCGains(swing_torso_compensation=1.0))
    off = PBCTracker(robot, gains=PBCGains(swing_torso_compensation=0.0))
    lay = on.layout(stance)
    r_on, r_off = on.compute(kin, tgt), off.compute(kin, tgt)
    assert r_on.ok and r_off.ok
    # the IK at the measured torso
    h_meas = h_d.copy()
    h_meas[:2] = h[:2]
    ref = PBCTracker(robot).ik.solve(kin, stance, 0.0, h_meas, dh, dh, iterations=12).q_r
    base = off.ik.last_result.q_r
    sw, st = lay.swing_mask, ~lay.swing_mask
    np.testing.assert_allclose(on.ik.last_result.q_r, base, atol=1e-12)  # same IK solution in both
    q_r = base[lay.ctrl_q].copy()
    v_r = on.ik.last_result.v_r[lay.ctrl_v].copy()
    on.compensate_swing(kin, tgt, lay, 1.0, q_r, v_r)
    change = np.abs(ref[lay.ctrl_q[sw]] - base[lay.ctrl_q[sw]])
    assert np.max(change) > 0.01  # the torso error matters for the swing leg
    np.testing.assert_allclose(q_r[sw], ref[lay.ctrl_q[sw]], atol=0.1 * np.max(change))
    np.testing.assert_array_equal(q_r[st], base[lay.ctrl_q[st]])
    # the torques differ only through the swing joints' references
    assert not np.allclose(r_on.tau_Nm, r_off.tau_Nm)
    np.testing.assert_allclose(on.ik.last_result.q_r[lay.ctrl_q[st]], base[lay.ctrl_q[st]], atol=1e-9)


def test_spring_model_offset_holds_the_stance_springs_at_the_model_deflection():
    """With spring_model_offset the IK holds the stance shin/achilles at rest + the model's deflection
    under the last commanded contact force, and the swing leg's springs at rest."""
    robot = load_robot("cassie")
    kin = RobotKinematics(robot)
    q, v = _state(robot, 14)
    kin.update(q, v)
    tracker = PBCTracker(robot, gains=PBCGains(spring_model_offset=True))
    tgt = _target_at_estimate(kin, "left")
    assert tracker.compute(kin, tgt).ok
    f = tracker.last_contact_force_N("left")
    assert f is not None and f[2] > 0
    res = tracker.compute(kin, tgt)
    assert res.ok
    q_r = tracker.ik.last_result.q_r
    smap = robot.state_map
    shin, achilles = spring_deflections_rad(kin, "left", f)
    assert q_r[smap.joint_pin_q["left-shin"]] == pytest.approx(shin, abs=1e-9)
    assert q_r[smap.joint_pin_q["right-shin"]] == pytest.approx(0.0, abs=1e-9)
    rest = tracker.ik.equations.spring_rest_values()[-1]
    for side, expect in (("left", rest + achilles), ("right", rest)):
        length = q_r[smap.joint_pin_q[f"{side}-knee"]] + q_r[smap.joint_pin_q[f"{side}-tarsus"]]
        assert length == pytest.approx(expect, abs=1e-9)


def test_cassie_spring_model_holds_the_linkage_deflection_under_the_weight():
    """Cassie's gains (achilles linkage, weight load): the IK holds the stance shin and achilles at
    rest + the linkage's deflections under m g, whatever force the PBC commanded before."""
    robot = load_robot("cassie")
    kin = RobotKinematics(robot)
    q, v = _state(robot, 14)
    kin.update(q, v)
    gains = default_gains(robot)
    assert gains.spring_model_load == "weight" and gains.spring_model_linkage is not None
    tracker = PBCTracker(robot, gains=gains)
    tgt = _target_at_estimate(kin, "left")
    assert tracker.compute(kin, tgt).ok
    assert tracker.compute(kin, tgt).ok
    q_r = tracker.ik.last_result.q_r
    smap = robot.state_map
    shin, achilles = spring_deflections_rad(kin, "left", None, gains.spring_model_linkage)
    assert shin < -0.03  # the rod's tension bends the knee spring (the tendon model: about 0)
    assert q_r[smap.joint_pin_q["left-shin"]] == pytest.approx(shin, abs=1e-9)
    rest = tracker.ik.equations.spring_rest_values()[-1]
    length = q_r[smap.joint_pin_q["left-knee"]] + q_r[smap.joint_pin_q["left-tarsus"]]
    assert length == pytest.approx(rest + achilles, abs=1e-9)


def test_hip_yaw_feedback_turns_the_swing_hip_yaw_reference_against_the_pelvis_yaw_error():
    """Cassie's gains feed the pelvis yaw back into the swing hip-yaw reference: with references at
    the estimate and a pelvis yawed 0.2 rad off its nominal yaw, the IK's swing hip-yaw joint
    reference is the measured angle minus 0.2 rad (the output is that joint's angle)."""
    robot = load_robot("cassie")
    gains = default_gains(robot)
    assert gains.hip_yaw_feedback == 1.0
    q, v = _state(robot, 3)
    q[3:7] = pin.Quaternion(pin.utils.rpyToMatrix(0.0, 0.0, 0.5)).coeffs()
    kin = RobotKinematics(robot)
    kin.update(q, v)
    names = OutputMap(robot).names
    tgt = _target_at_estimate(kin, "left")
    i_st = names.index("stance_hip_yaw")
    heading = 0.5 + float(tgt.h_d[i_st]) - 0.2  # nominal pelvis yaw D - h_d[stance] = 0.3 rad
    tgt = dataclasses.replace(tgt, heading_rad=heading)
    h, J, _ = kin.outputs("left", heading)
    tgt = dataclasses.replace(tgt, h_d=h, dh_d=J @ kin.v)
    tracker = PBCTracker(robot, gains=dataclasses.replace(gains, spring_model_offset=False))
    assert tracker.compute(kin, tgt).ok
    q_r = tracker.ik.last_result.q_r
    iq = robot.state_map.joint_pin_q["right-hip-yaw"]
    R = kin.base_rotation()
    e = math.atan2(R[1, 0], R[0, 0]) - (heading - float(h[i_st]))
    assert e == pytest.approx(0.2, abs=1e-9)
    assert q_r[iq] == pytest.approx(q[iq] - e, abs=1e-6)


@pytest.mark.parametrize("stance", ["left", "right"])
def test_swing_ankle_gain_scale_stiffens_only_the_swing_ankle(stance):
    """Cassie's swing toe gets ``scale`` x K_p and sqrt(scale) x K_d; every other joint keeps its gains."""
    robot = load_robot("cassie")
    base = dataclasses.replace(default_gains(robot), swing_ankle_gain_scale=1.0)
    stiff = dataclasses.replace(base, swing_ankle_gain_scale=10.0)
    a, b = PBCTracker(robot, gains=base).layout(stance), PBCTracker(robot, gains=stiff).layout(stance)
    names = [robot.actuated.joint_names[k] for k in a.ctrl]
    swing = "right" if stance == "left" else "left"
    toe = np.array([n == f"{swing}-foot" for n in names])
    assert toe.sum() == 1 and f"{stance}-foot" not in names  # the stance toe is passive
    assert b.kp[toe][0] == pytest.approx(10.0 * base.kp_swing_ps2)
    assert b.kd[toe][0] == pytest.approx(math.sqrt(10.0) * base.kd_swing_ps)
    np.testing.assert_array_equal(b.kp[~toe], a.kp[~toe])
    np.testing.assert_array_equal(b.kd[~toe], a.kd[~toe])


def test_the_walking_controllers_pbc_ik_evaluates_the_controllers_generated_output_map():
    """In the walking loop with the default kinematics the IK evaluates the controller's generated-C
    output map (the same object, on the IK's own Pinocchio data), and the walk stands on it."""
    import mujoco

    from amlip_qp import MujocoLoop
    from amlip_qp.control.walking.controller import WalkingController
    from amlip_qp.control.walking.outputs_compiled import CompiledOutputMap

    robot = load_robot("cassie")
    model, data = robot.mj_model, robot.new_mj_data("stand")
    tracker = PBCTracker(robot)
    controller = WalkingController(robot, tracker)
    loop = MujocoLoop(robot, controller, model, data)
    command = loop.command(vx_mps=0.5)
    z_stand_m = float(data.qpos[2])
    for _ in range(400):  # 0.2 s
        tick = loop.step(command)
        mujoco.mj_step(model, data)
        assert tick.tracker_ok
    assert isinstance(controller.kin.output_map, CompiledOutputMap)
    assert tracker.ik.kin.output_map is controller.kin.output_map
    assert tracker.ik.kin.data is not controller.kin.data
    assert data.qpos[2] > 0.8 * z_stand_m
