"""Tests of amlip_qp.robots.outputs: h_0(q) values, Jacobians and drifts."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pinocchio as pin
import pytest
from scipy.spatial.transform import Rotation

from amlip_qp.alip import other_side
from amlip_qp.exceptions import InputError, MJCFError
from amlip_qp.robots import CASSIE_OUTPUTS, PLANAR_OUTPUTS, OutputMap, RobotKinematics, load_robot
from amlip_qp.robots.outputs import check_output_map, output_layout
from robot_states import ROBOTS


@pytest.fixture(scope="module", params=ROBOTS)
def robot(request):
    return load_robot(request.param)


def random_state(robot, rng):
    """Random Pinocchio state near the stand keyframe (joints within range)."""
    pm = robot.pin_model
    q = robot.q_stand.copy()
    dq = rng.uniform(-0.3, 0.3, robot.nv)
    q = pin.integrate(pm, q, dq)
    lo, hi = pm.lowerPositionLimit, pm.upperPositionLimit
    finite = np.isfinite(lo) & np.isfinite(hi) & (hi - lo < 100)
    if robot.is_floating:
        finite[:7] = False
    q[finite] = np.clip(q[finite], lo[finite], hi[finite])
    return q, rng.normal(size=robot.nv)


def test_layout(robot):
    omap = OutputMap(robot)
    expect = CASSIE_OUTPUTS if robot.is_floating else PLANAR_OUTPUTS
    assert omap.names == expect and omap.size == len(expect)
    # the layout is the robot profile's, also the planner's robot name
    assert omap.layout == output_layout(robot) == robot.profile.output_layout == robot.name
    if omap.layout == "cassie":
        assert omap.yaw_q_idx["left"] == robot.state_map.joint_pin_q["left-hip-yaw"]
        assert omap.yaw_v_idx["right"] == robot.state_map.joint_pin_v["right-hip-yaw"]
    else:
        assert omap.yaw_q_idx == omap.yaw_v_idx == {}


def test_a_model_without_profile_gets_the_layout_it_fits_and_a_profile_must_fit(robot):
    assert output_layout(dataclasses.replace(robot, profile=None)) == robot.name
    other = "rabbit" if robot.name == "cassie" else "cassie"
    wrong = dataclasses.replace(robot.profile, output_layout=other)
    with pytest.raises(MJCFError, match=f"names the output layout '{other}'"):
        output_layout(dataclasses.replace(robot, profile=wrong))


def test_values_follow_the_definitions(robot):
    rng = np.random.default_rng(20)
    kin = RobotKinematics(robot)
    for _ in range(3):
        q, v = random_state(robot, rng)
        kin.update(q, v)
        D = rng.uniform(-np.pi, np.pi)
        for st in robot.foot_sides:
            sw = other_side(st)
            y, J, jdv = kin.outputs(st, D)
            c, r_st, r_sw = kin.com(), kin.contact_position(st), kin.contact_position(sw)
            xD, yD = np.array([np.cos(D), np.sin(D), 0]), np.array([-np.sin(D), np.cos(D), 0])
            named = dict(zip(OutputMap(robot).names, y))
            assert named["com_z_over_stance"] == pytest.approx(c[2] - r_st[2], abs=1e-14)
            assert named["com_x_over_swing"] == pytest.approx((c - r_sw) @ xD, abs=1e-14)
            assert named["com_z_over_swing"] == pytest.approx(c[2] - r_sw[2], abs=1e-14)
            R = kin.base_rotation()
            if robot.is_planar:
                assert named["torso_pitch"] == pytest.approx(q[2], abs=1e-12)  # root-pitch, absolute
            else:
                yaw, pitch, roll = Rotation.from_matrix(R).as_euler("ZYX")
                assert named["torso_pitch"] == pytest.approx(pitch, abs=1e-12)
                assert named["torso_roll"] == pytest.approx(roll, abs=1e-12)
                sm = robot.state_map
                assert named["stance_hip_yaw"] == q[sm.joint_pin_q[f"{st}-hip-yaw"]]
                assert named["swing_hip_yaw"] == q[sm.joint_pin_q[f"{sw}-hip-yaw"]]
                assert named["com_y_over_swing"] == pytest.approx((c - r_sw) @ yD, abs=1e-14)
                toe, heel = (kin.frame_position(f) for f in robot.force_frame_ids[sw])
                dlt = toe - heel
                assert named["swing_toe_pitch"] == pytest.approx(
                    np.arctan2(-dlt[2], np.hypot(dlt[0], dlt[1])), abs=1e-14
                )


def test_planar_pitch_sign():
    """Rabbit: positive torso_pitch = torso leaning forward (its top moves to +x)."""
    robot = load_robot("rabbit")
    kin = RobotKinematics(robot)
    q = robot.q_stand.copy()
    q[2] = 0.2
    kin.update(q, np.zeros(7))
    y, _, _ = kin.outputs("left")
    assert y[0] == pytest.approx(0.2)
    assert kin.base_rotation()[:, 2][0] > 0  # torso axis tilts forward


def test_jacobian_and_drift_by_finite_differences(robot):
    rng = np.random.default_rng(21)
    kin, probe = RobotKinematics(robot), RobotKinematics(robot)
    h = 1e-6
    for _ in range(2):
        q, v = random_state(robot, rng)
        D = rng.uniform(-np.pi, np.pi)
        kin.update(q, v)
        for st in robot.foot_sides:
            y, J, jdv = kin.outputs(st, D)

            def out(qq, k=0):
                probe.update(qq, v)
                return probe.outputs(st, D)[k]

            cols = []
            for i in range(robot.nv):
                e = np.zeros(robot.nv)
                e[i] = h
                cols.append(
                    (out(pin.integrate(robot.pin_model, q, e)) - out(pin.integrate(robot.pin_model, q, -e))) / (2 * h)
                )
            np.testing.assert_allclose(J, np.column_stack(cols), atol=1e-6)
            jv_p = out(pin.integrate(robot.pin_model, q, v * h), 1) @ v
            jv_m = out(pin.integrate(robot.pin_model, q, -v * h), 1) @ v
            np.testing.assert_allclose(jdv, (jv_p - jv_m) / (2 * h), atol=1e-5)


def test_bad_arguments():
    robot = load_robot("rabbit")
    kin = RobotKinematics(robot)
    kin.update(robot.q_stand, np.zeros(7))
    with pytest.raises(InputError, match="stance must be 'left' or 'right'"):
        kin.outputs("both")
    with pytest.raises(InputError, match="heading_rad must be finite"):
        kin.outputs("left", float("nan"))


def test_results_are_new_arrays_that_later_evaluations_leave_alone(robot):
    """evaluate() works in scratch buffers; what it returns is never overwritten."""
    rng = np.random.default_rng(22)
    kin, omap = RobotKinematics(robot), OutputMap(robot)
    kin.update(*random_state(robot, rng))
    first = omap.evaluate(kin, "left", 0.3)
    snapshot = [a.copy() for a in first]
    kin.update(*random_state(robot, rng))
    second = omap.evaluate(kin, "right", -1.0)
    for a, s, b in zip(first, snapshot, second):
        np.testing.assert_array_equal(a, s)
        assert not np.shares_memory(a, b)


def test_position_rows_are_the_plain_formulas_bit_for_bit(robot):
    """The CoM-over-contact rows (values, Jacobian rows, drifts) equal the plain numpy
    expressions exactly: the row-wise evaluation changes no arithmetic."""
    rng = np.random.default_rng(23)
    kin = RobotKinematics(robot)
    names = OutputMap(robot).names
    row = {n: names.index(n) for n in names}
    for _ in range(3):
        kin.update(*random_state(robot, rng))
        D = float(rng.uniform(-np.pi, np.pi))
        cD, sD = math.cos(D), math.sin(D)  # what evaluate uses
        for st in robot.foot_sides:
            sw = other_side(st)
            y, J, jdv = kin.outputs(st, D)
            c, Jc, dc = kin.com(), kin.com_jacobian(), kin.com_jdot_v()
            p_st, J_st, d_st = c - kin.contact_position(st), Jc - kin.contact_jacobian(st), dc - kin.contact_jdot_v(st)
            p_sw, J_sw, d_sw = c - kin.contact_position(sw), Jc - kin.contact_jacobian(sw), dc - kin.contact_jdot_v(sw)
            expect = {
                "com_z_over_stance": (p_st[2], J_st[2], d_st[2]),
                "com_x_over_swing": (
                    cD * p_sw[0] + sD * p_sw[1],
                    cD * J_sw[0] + sD * J_sw[1],
                    cD * d_sw[0] + sD * d_sw[1],
                ),
                "com_z_over_swing": (p_sw[2], J_sw[2], d_sw[2]),
            }
            if "com_y_over_swing" in row:
                expect["com_y_over_swing"] = (
                    -sD * p_sw[0] + cD * p_sw[1],
                    -sD * J_sw[0] + cD * J_sw[1],
                    -sD * d_sw[0] + cD * d_sw[1],
                )
            for name, (value, jac_row, drift) in expect.items():
                k = row[name]
                assert y[k] == value and jdv[k] == drift
                np.testing.assert_array_equal(J[k], jac_row)


def test_an_output_map_stand_in_must_evaluate_the_same_outputs_of_the_same_model():
    cassie, rabbit = load_robot("cassie"), load_robot("rabbit")
    check_output_map(cassie, OutputMap(cassie))  # the default passes
    with pytest.raises(InputError, match=r"output_map must evaluate the outputs \('torso_pitch', .*of cassie \(nv = "):
        check_output_map(cassie, OutputMap(rabbit))

    class NoEvaluate:
        names = OutputMap(cassie).names

    with pytest.raises(InputError, match="output_map must evaluate"):
        check_output_map(cassie, NoEvaluate())
    kin = RobotKinematics(cassie)
    with pytest.raises(InputError, match="output_map must evaluate"):
        kin.output_map = NoEvaluate()
