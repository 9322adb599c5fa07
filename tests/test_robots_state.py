"""Tests of amlip_qp.robots.state: MuJoCo (qpos, qvel) <-> Pinocchio (q, v)."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pinocchio as pin
import pytest

from amlip_qp.exceptions import InputError
from amlip_qp.robots import (
    force_mj_to_pin,
    force_pin_to_mj,
    load_robot,
    mj_to_pin,
    pin_to_mj,
    velocity_map,
    velocity_map_dot_v,
)
from robot_states import ROBOTS, random_mj_state


@pytest.fixture(scope="module", params=ROBOTS)
def robot(request):
    return load_robot(request.param)


def test_round_trips(robot):
    rng = np.random.default_rng(1)
    for _ in range(10):
        qpos, qvel = random_mj_state(robot, rng)
        q, v = mj_to_pin(robot, qpos, qvel)
        qpos2, qvel2 = pin_to_mj(robot, q, v)
        np.testing.assert_allclose(qpos2, qpos, atol=1e-14)
        np.testing.assert_allclose(qvel2, qvel, atol=1e-14)
        q3, v3 = mj_to_pin(robot, qpos2, qvel2)
        np.testing.assert_allclose(q3, q, atol=1e-14)
        np.testing.assert_allclose(v3, v, atol=1e-14)


def test_joint_coordinates_by_name(robot):
    """Each named 1-dof joint lands on the Pinocchio coordinate of the same name."""
    rng = np.random.default_rng(2)
    qpos, qvel = random_mj_state(robot, rng)
    q, v = mj_to_pin(robot, qpos, qvel)
    m, pm = robot.mj_model, robot.pin_model
    for name in robot.joint_names:
        j = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, name)
        jp = pm.getJointId(name)
        assert q[pm.joints[jp].idx_q] == qpos[m.jnt_qposadr[j]]
        assert v[pm.joints[jp].idx_v] == qvel[m.jnt_dofadr[j]]


def test_base_pose_and_body_velocity_match_mujoco(robot):
    """The converted state gives Pinocchio the same base pose and spatial velocity as MuJoCo."""
    rng = np.random.default_rng(3)
    m, pm = robot.mj_model, robot.pin_model
    d, pd = mujoco.MjData(m), pm.createData()
    fid, bid = robot.base_frame_id, mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, robot.base_body)
    for _ in range(5):
        qpos, qvel = random_mj_state(robot, rng)
        d.qpos[:], d.qvel[:] = qpos, qvel
        mujoco.mj_forward(m, d)
        q, v = mj_to_pin(robot, qpos, qvel)
        pin.forwardKinematics(pm, pd, q, v)
        pin.updateFramePlacements(pm, pd)
        np.testing.assert_allclose(pd.oMf[fid].translation, d.xpos[bid], atol=1e-12)
        np.testing.assert_allclose(pd.oMf[fid].rotation, d.xmat[bid].reshape(3, 3), atol=1e-12)
        vel = np.zeros(6)  # MuJoCo: (angular, linear) at the body origin, body axes
        mujoco.mj_objectVelocity(m, d, mujoco.mjtObj.mjOBJ_XBODY, bid, vel, 1)
        twist = pin.getFrameVelocity(pm, pd, fid, pin.ReferenceFrame.LOCAL)
        np.testing.assert_allclose(twist.angular, vel[:3], atol=1e-12)
        np.testing.assert_allclose(twist.linear, vel[3:], atol=1e-12)


def test_velocity_map_and_force_duality(robot):
    rng = np.random.default_rng(4)
    qpos, qvel = random_mj_state(robot, rng)
    q, v = mj_to_pin(robot, qpos, qvel)
    T = velocity_map(robot, q)
    np.testing.assert_allclose(T @ v, qvel, atol=1e-14)
    np.testing.assert_allclose(T.T @ T, np.eye(robot.nv), atol=1e-14)  # orthogonal
    f_mj = rng.normal(size=robot.nv)
    f_pin = force_mj_to_pin(robot, q, f_mj)
    assert f_pin @ v == pytest.approx(f_mj @ qvel, rel=1e-13)  # same power
    np.testing.assert_allclose(force_pin_to_mj(robot, q, f_pin), f_mj, atol=1e-14)


def test_velocity_map_derivative_by_finite_differences(robot):
    rng = np.random.default_rng(5)
    qpos, qvel = random_mj_state(robot, rng)
    q, v = mj_to_pin(robot, qpos, qvel)
    h = 1e-6
    Tp = velocity_map(robot, pin.integrate(robot.pin_model, q, v * h))
    Tm = velocity_map(robot, pin.integrate(robot.pin_model, q, -v * h))
    np.testing.assert_allclose((Tp - Tm) @ v / (2 * h), velocity_map_dot_v(robot, q, v), atol=1e-7)


def test_bad_states(robot):
    nq_mj, nv = robot.mj_model.nq, robot.nv
    qpos, qvel = robot.qpos_stand.copy(), np.zeros(nv)
    with pytest.raises(InputError, match=rf"qpos must have shape \({nq_mj},\)"):
        mj_to_pin(robot, qpos[:-1], qvel)
    with pytest.raises(InputError, match=rf"qvel must have shape \({nv},\)"):
        mj_to_pin(robot, qpos, np.zeros(nv + 1))
    bad = qpos.copy()
    bad[2] = np.nan
    with pytest.raises(InputError, match=r"qpos contains NaN or inf at indices \[2\]"):
        mj_to_pin(robot, bad, qvel)
    with pytest.raises(InputError, match="v contains NaN"):
        pin_to_mj(robot, robot.q_stand, np.full(nv, np.inf))
    if robot.is_floating:
        bad = qpos.copy()
        bad[3:7] = 0.0
        with pytest.raises(InputError, match="zero quaternion"):
            mj_to_pin(robot, bad, qvel)


def test_finiteness_check_refuses_only_nan_and_inf(robot):
    """The per-tick check sums first (cheap); a sum that overflows is checked exactly."""
    qpos, qvel = robot.qpos_stand.copy(), np.zeros(robot.nv)
    qvel[-2:] = 1e308  # finite, but the sum overflows
    q, v = mj_to_pin(robot, qpos, qvel)
    assert np.all(np.isfinite(v))
    qvel[-1] = -np.inf
    with pytest.raises(InputError, match=rf"qvel contains NaN or inf at indices \[{robot.nv - 1}\]"):
        mj_to_pin(robot, qpos, qvel)


def test_norm_sums_left_to_right_whatever_the_blas():
    """The norm is written out (the same numbers on any CPU); NumPy's, through its BLAS, agrees to rounding."""
    from amlip_qp.robots.state import _norm

    rng = np.random.default_rng(7)
    for _ in range(200):
        x = rng.normal(size=4) * 10.0 ** rng.uniform(-5, 5)
        a, b, c, d = x.tolist()
        assert _norm(x) == math.sqrt(((a * a + b * b) + c * c) + d * d)
        assert _norm(x) == pytest.approx(np.linalg.norm(x), rel=4e-16)


def test_rotation_entries_are_pinocchios_rotation_of_the_quaternion():
    """The one quaternion-rotation formula against Pinocchio's, on random unit quaternions."""
    from amlip_qp.robots.state import rotation_entries

    rng = np.random.default_rng(31)
    for _ in range(20):
        u = rng.normal(size=4)
        w, x, y, z = (u / np.linalg.norm(u)).tolist()
        R = pin.Quaternion(w, x, y, z).toRotationMatrix()
        np.testing.assert_allclose(np.reshape(rotation_entries(w, x, y, z), (3, 3)), R, atol=1e-15)
