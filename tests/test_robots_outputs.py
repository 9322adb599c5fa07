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
from amlip_qp.robots import OutputMap, RobotKinematics, load_robot, output_names
from amlip_qp.robots.outputs import DEFAULT_OUTPUTS_3D, DEFAULT_OUTPUTS_PLANAR, check_output_map
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


def test_the_outputs_are_the_profiles_declaration(robot):
    omap = OutputMap(robot)
    assert omap.names == output_names(robot) == robot.profile.outputs and omap.size == len(omap.names)
    assert [p.name for p in omap.primitives] == list(omap.names)
    rows = [omap.names.index(n) for n in ("stance_hip_yaw", "swing_hip_yaw") if n in omap.names]
    assert omap.joint_rows == tuple(rows)
    if rows:
        q_idx, v_idx = omap.joint_indices("left")
        assert q_idx == (robot.state_map.joint_pin_q["left-hip-yaw"], robot.state_map.joint_pin_q["right-hip-yaw"])
        assert v_idx[1] == robot.state_map.joint_pin_v["right-hip-yaw"]


def test_a_model_without_a_profile_gets_the_default_outputs_it_fits(robot):
    bare = dataclasses.replace(robot, profile=None)
    assert output_names(bare) == (DEFAULT_OUTPUTS_PLANAR if robot.is_planar else DEFAULT_OUTPUTS_3D)
    assert output_names(bare) == robot.profile.outputs  # the bundled ones declare the same


def test_an_output_the_model_cannot_compute_is_refused_at_load():
    cassie, rabbit = load_robot("cassie"), load_robot("rabbit")
    lateral = dataclasses.replace(rabbit.profile, outputs=(*rabbit.profile.outputs, "com_y_over_swing"))
    with pytest.raises(MJCFError, match="planar robot has no lateral output: drop com_y_over_swing"):
        OutputMap(dataclasses.replace(rabbit, profile=lateral))
    no_yaw = dataclasses.replace(cassie.profile, joint_roles={"hip_yaw": "{side}-no-such-joint"})
    with pytest.raises(MJCFError, match="'stance_hip_yaw' needs a hip_yaw joint on each leg"):
        OutputMap(dataclasses.replace(cassie, profile=no_yaw))
    one_point = dataclasses.replace(
        cassie,
        force_sites={s: cassie.force_sites[s][:1] for s in cassie.foot_sides},
        sole_line_sites=dict.fromkeys(cassie.foot_sides, ()),
    )
    with pytest.raises(MJCFError, match="'swing_toe_pitch' needs a sole line on each foot: two or four force points"):
        OutputMap(one_point)


def test_swing_foot_roll_is_the_contact_frames_roll_with_its_derivatives():
    robot = load_robot("g1")  # declared last
    rng = np.random.default_rng(24)
    kin, probe, omap = RobotKinematics(robot), RobotKinematics(robot), OutputMap(robot)
    assert omap.names[-1] == "swing_foot_roll" and omap.size == 10
    h = 1e-6
    for _ in range(2):
        q, v = random_state(robot, rng)
        kin.update(q, v)
        for st in robot.foot_sides:
            y, J, jdv = omap.evaluate(kin, st, 0.7)
            R = kin.frame_rotation(robot.contact_frame_ids[other_side(st)])
            assert y[-1] == pytest.approx(Rotation.from_matrix(R).as_euler("ZYX")[2], abs=1e-12)

            def roll(qq, k=0):
                probe.update(qq, v)
                return omap.evaluate(probe, st, 0.7)[k][-1]

            fd = [(roll(pin.integrate(robot.pin_model, q, e)) - roll(pin.integrate(robot.pin_model, q, -e))) / (2 * h)
                  for e in np.eye(robot.nv) * h]  # fmt: skip
            np.testing.assert_allclose(J[-1], fd, atol=1e-6)
            jv = [roll(pin.integrate(robot.pin_model, q, sign * v * h), 1) @ v for sign in (1, -1)]
            assert jdv[-1] == pytest.approx((jv[0] - jv[1]) / (2 * h), abs=1e-5)
            assert abs(jdv[-1]) > 1e-3  # the check is not vacuous


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


def test_a_reordered_declaration_gives_the_same_rows_bit_for_bit(robot):
    """The evaluation plan (made once per stance) follows the declared order: the outputs declared in
    reverse give the same values, Jacobian rows and drifts, bit for bit, in reverse."""
    rng = np.random.default_rng(24)
    reversed_profile = dataclasses.replace(robot.profile, outputs=tuple(reversed(robot.profile.outputs)))
    omap, rmap = OutputMap(robot), OutputMap(dataclasses.replace(robot, profile=reversed_profile))
    assert rmap.names == tuple(reversed(omap.names))
    kin = RobotKinematics(robot)
    for _ in range(2):
        kin.update(*random_state(robot, rng))
        for st in robot.foot_sides:
            D = float(rng.uniform(-np.pi, np.pi))
            for a, b in zip(omap.evaluate(kin, st, D), rmap.evaluate(kin, st, D)):
                assert a.tobytes() == b[::-1].tobytes()


def test_an_output_map_stand_in_must_evaluate_the_same_outputs_of_the_same_model():
    cassie, rabbit = load_robot("cassie"), load_robot("rabbit")
    check_output_map(cassie, OutputMap(cassie))  # the default passes
    with pytest.raises(InputError, match=r"output_map must evaluate the outputs \('torso_pitch', .*of cassie \(nv = "):
        check_output_map(cassie, OutputMap(rabbit))

    class NoEvaluate:
        names = OutputMap(cassie).names

    with pytest.raises(InputError, match="output_map must evaluate"):
        check_output_map(cassie, NoEvaluate())
    with pytest.raises(InputError, match="output_map must evaluate"):
        RobotKinematics(cassie, NoEvaluate())
    with pytest.raises(InputError, match="output_map must evaluate"):
        RobotKinematics(cassie, output_map=OutputMap(rabbit))


def test_a_profile_declares_one_output_per_free_leg_joint():
    """G1: 12 actuated leg joints, the stance ankle's pitch and roll passive: 10 outputs, not 9."""
    g1 = load_robot("g1")
    nine = dataclasses.replace(g1.profile, outputs=tuple(n for n in g1.profile.outputs if n != "swing_foot_roll"))
    with pytest.raises(MJCFError, match=r"declares 9 outputs; the legs need 10: .*12 actuated leg joints minus 2 "):
        output_names(dataclasses.replace(g1, profile=nine))


def test_the_controller_refuses_outputs_that_lose_rank_at_the_stand_pose():
    """Rabbit with straight knees at the stand pose: the legs cannot lengthen, so an output loses its rank."""
    from amlip_qp.control.walking.controller import WalkingController
    from amlip_qp.robots.kinematics import RANK_TOL, stand_output_rank

    rabbit = load_robot("rabbit")
    q = rabbit.q_stand.copy()
    for side in rabbit.foot_sides:
        q[rabbit.state_map.joint_pin_q[f"{side}-knee"]] = 0.0
    straight = dataclasses.replace(rabbit, q_stand=q)
    rank, n, smallest, _ = stand_output_rank(straight)
    assert rank < n == 4 and smallest < RANK_TOL
    assert stand_output_rank(rabbit)[0] == 4
    with pytest.raises(MJCFError, match=r"output Jacobian has rank \d of 4 at the stand pose"):
        WalkingController(straight, tracker=None, kinematics=RobotKinematics(straight), dt_s=0.0005)
