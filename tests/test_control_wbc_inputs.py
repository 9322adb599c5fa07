"""The per-tick inputs of the whole-body QP: gathered once, the same for both builds."""

import math

import casadi as ca
import numpy as np
import pinocchio as pin
import pytest

from amlip_qp.control.tracker import TrackingTarget
from amlip_qp.control.wbc.builder import WholeBodyQP
from amlip_qp.control.wbc.inputs import (
    PackedInput,
    PelvisYawFeedback,
    SymbolicInputs,
    gather_inputs,
    swing_force_weight,
)
from amlip_qp.exceptions import InputError
from amlip_qp.robots import load_robot
from amlip_qp.robots.kinematics import RobotKinematics
from robot_states import tuned_config
from wbc_cases import corrected_target, kin_at, target_for

CASSIE_CONFIG = tuned_config("cassie", "qp")
CASSIE_OUTPUTS = load_robot("cassie").profile.outputs
RABBIT_CONFIG = tuned_config("rabbit", "qp")


@pytest.fixture(scope="module", params=["cassie", "rabbit"])
def robot(request):
    return load_robot(request.param)


@pytest.mark.parametrize("stance", ["left", "right"])
def test_gathered_inputs_are_the_kinematics_terms(robot, stance):
    builder = WholeBodyQP(robot)
    kin = kin_at(robot, seed=2)
    target = target_for(kin, stance, phase=0.02, offset=0.01, heading=0.3)
    inp = gather_inputs(kin, target, builder.inputs)
    swing = "right" if stance == "left" else "left"
    assert inp is builder.inputs and (inp.stance, inp.swing) == (stance, swing)
    assert inp.q is kin.q and inp.v is kin.v
    assert np.array_equal(inp.hp, kin.nonlinear_effects() - kin.passive_forces())
    assert np.array_equal(np.triu(inp.mass_upper), np.triu(kin.mass_matrix()))
    axes = [0, 2] if robot.is_planar else [0, 1, 2]
    rows = [kin.frame_jacobian(f)[axes] for side in (stance, swing) for f in robot.force_frame_ids[side]]
    assert np.array_equal(inp.Jf, np.vstack(rows))
    fids = robot.force_frame_ids[stance]
    for i, f in enumerate(fids):
        assert np.array_equal(inp.point_jacobians[i], kin.frame_jacobian(f))
        assert np.array_equal(inp.point_positions[i], kin.frame_position(f))
        assert np.array_equal(inp.point_drifts[i], kin.frame_jdot_v(f))
    J, r = builder.output_task.least_squares(kin, target)
    assert np.array_equal(inp.output_jacobian, J) and np.array_equal(inp.output_residual, r)
    assert inp.swing_force_weight == pytest.approx(1.0 - 0.02 / builder.config.liftoff_phase, abs=1e-15)


def test_swing_force_weight_is_the_larger_ramp_clipped_to_one():
    def w(config, phase, contact):
        return swing_force_weight(config, TrackingTarget("left", phase, 0.0, None, None, None, contact))

    cfg = RABBIT_CONFIG.with_(liftoff_phase=0.1, touchdown_blend=0.5)
    assert w(cfg, 0.5, 0.0) == 0.0  # mid-step: in the air
    assert w(cfg, 0.025, 0.0) == pytest.approx(0.75)  # liftoff ramp of the previous stance foot
    assert w(cfg, 0.95, 0.6) == pytest.approx(0.3)  # blend * pre-touchdown weight
    assert w(cfg, 0.0, 1.0) == 1.0
    assert w(cfg.with_(touchdown_blend=1.0), 0.95, 3.0) == 1.0  # clipped
    assert w(cfg, 0.95, math.nan) == 0.0 and w(cfg, 0.95, math.inf) == 0.0  # never non-finite
    assert w(cfg.with_(liftoff_phase=0.0), 0.0, 0.0) == 0.0  # no liftoff ramp


@pytest.mark.parametrize("stance", ["left", "right"])
def test_pelvis_yaw_feedback_aims_the_swing_foot_at_the_heading_whatever_the_pelvis_yaw(stance):
    cassie = load_robot("cassie")
    i_st, i_sw = CASSIE_OUTPUTS.index("stance_hip_yaw"), CASSIE_OUTPUTS.index("swing_hip_yaw")
    q = cassie.q_stand.copy()
    yaw = 0.3  # pelvis yawed 0.3 rad off the heading
    q[3:7] = pin.Quaternion(pin.utils.rpyToMatrix(0.0, 0.0, yaw)).coeffs()  # xyzw
    v = np.zeros(cassie.nv)
    v[5] = 0.5  # yaw rate about the (level) base z, rad/s
    kin = RobotKinematics(cassie)
    kin.update(q, v)
    n = len(CASSIE_OUTPUTS)
    h_d, dh_d = np.zeros(n), np.zeros(n)
    h_d[i_st], dh_d[i_st] = 0.05, 0.2
    target = TrackingTarget(stance, 0.4, 0.1, h_d, dh_d, np.zeros(n))
    k = 0.8
    fb = PelvisYawFeedback.for_outputs(CASSIE_OUTPUTS, k)
    assert (fb.stance_index, fb.swing_index, fb.gain) == (i_st, i_sw, k)
    e = yaw - (0.1 - 0.05)  # pelvis yaw minus its nominal D - h_d[stance_hip_yaw]
    dh, ddh = fb.correction(kin, target)
    assert dh == pytest.approx(-k * e, abs=1e-12) and ddh == pytest.approx(-k * (0.5 + 0.2), abs=1e-12)
    # The residual moves by -(K_d ddh + K_p dh) on the swing hip yaw only: the
    # output task's residual for the swing hip-yaw reference and rate corrected by (dh, ddh).
    builder = WholeBodyQP(cassie, CASSIE_CONFIG.with_(hip_yaw_feedback=k))
    inp = gather_inputs(kin, target, builder.inputs)
    gains = builder.output_task.gains
    assert inp.residual_shift == pytest.approx(gains.kd[i_sw] * ddh + gains.kp[i_sw] * dh, rel=1e-12)
    out = corrected_target(fb, kin, target)
    assert out.h_d[i_sw] == pytest.approx(-k * e, abs=1e-12)
    assert out.dh_d[i_sw] == pytest.approx(-k * (0.5 + 0.2), abs=1e-12)
    _, r_corrected = builder.output_task.least_squares(kin, out)
    shifted = inp.output_residual.copy()
    shifted[i_sw] -= inp.residual_shift
    assert np.allclose(shifted, r_corrected, rtol=1e-12, atol=1e-12)
    # The error wraps: a pelvis 2 pi further round is the same pelvis.
    q[3:7] = pin.Quaternion(pin.utils.rpyToMatrix(0.0, 0.0, yaw - 2 * math.pi)).coeffs()
    kin.update(q, v)
    assert fb.correction(kin, target)[0] == pytest.approx(-k * e, abs=1e-9)


def test_pelvis_yaw_feedback_is_off_without_gain_or_hip_yaw_outputs():
    assert PelvisYawFeedback.for_outputs(CASSIE_OUTPUTS, 0.0) is None
    rabbit = load_robot("rabbit")
    builder = WholeBodyQP(rabbit, RABBIT_CONFIG.with_(hip_yaw_feedback=1.0))
    assert builder.feedback is None
    kin = kin_at(rabbit)
    target = target_for(kin)
    assert gather_inputs(kin, target, builder.inputs).residual_shift == 0.0


def test_packed_input_holds_what_the_generated_build_reads(robot):
    config = (CASSIE_CONFIG if robot.name == "cassie" else RABBIT_CONFIG).with_(hip_yaw_feedback=1.0)
    builder = WholeBodyQP(robot, config)
    kin = kin_at(robot, seed=5)
    inp = gather_inputs(kin, target_for(kin, "right", phase=0.01), builder.inputs)
    packed = PackedInput(robot.nq, builder.layout, builder.output_task.size)
    small, u = packed.slices, packed.array
    u[:] = np.nan
    packed.pack(inp)
    assert np.all(np.isfinite(u)), "every slot is written"
    assert np.array_equal(u[small["q"]], kin.q) and np.array_equal(u[small["v"]], kin.v)
    con = u[small["contact"]]
    if builder.layout.n_points == 2:
        toe, heel = robot.force_frame_ids["right"]
        expected = np.r_[
            kin.frame_position(toe), kin.frame_position(heel), kin.frame_jdot_v(toe), kin.frame_jdot_v(heel)
        ]
        assert np.array_equal(con, expected)
    else:
        assert np.array_equal(con, kin.frame_jdot_v(robot.force_frame_ids["right"][0])[[0, 2]])
    r = inp.output_residual.copy()
    if inp.feedback is not None:
        r[inp.feedback.swing_index] -= inp.residual_shift
    assert np.array_equal(u[small["r"]], r)
    assert u[small["w"]][0] == inp.swing_force_weight == pytest.approx(1.0 - 0.01 / builder.config.liftoff_phase)


def test_symbolic_mass_matrix_reads_the_upper_triangle_only():
    cassie = load_robot("cassie")
    builder = WholeBodyQP(cassie)
    sym = SymbolicInputs.create("left", cassie.nq, builder.layout, builder.output_task.size)
    assert sym.swing == "right" and sym.argument_names == ("M_upper", "hp", "JfT", "JoT", "packed")
    fn = ca.Function("M", [sym.arguments[0]], [sym.mass_matrix])
    A = np.random.default_rng(0).normal(size=(cassie.nv, cassie.nv))
    M = np.asarray(fn(np.triu(A) + 1e9 * np.tril(np.ones_like(A), -1)))
    assert np.array_equal(M, M.T) and np.array_equal(np.triu(M), np.triu(A))


def test_a_bad_stance_or_a_kinematics_without_dynamics_is_an_input_error():
    rabbit = load_robot("rabbit")
    builder = WholeBodyQP(rabbit)
    kin = kin_at(rabbit)
    target = target_for(kin)
    target.stance = "up"
    with pytest.raises(InputError, match="side"):
        gather_inputs(kin, target, builder.inputs)
    kin.update_positions(rabbit.q_stand)
    with pytest.raises(InputError, match="update"):
        gather_inputs(kin, target_for(kin), builder.inputs)
