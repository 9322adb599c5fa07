"""Tasks of the whole-body QP: Jacobians and drifts against finite differences."""

import numpy as np
import pinocchio as pin
import pytest

from amlip_qp.control.tracker import TrackingTarget
from amlip_qp.control.wbc.builder import WholeBodyQP
from amlip_qp.control.wbc.tasks import Gains, JointTask, OutputTask
from amlip_qp.exceptions import InputError
from amlip_qp.robots import load_robot
from amlip_qp.robots.kinematics import RobotKinematics


@pytest.fixture(scope="module", params=["cassie", "rabbit"])
def robot(request):
    return load_robot(request.param)


def _state(robot, seed):
    rng = np.random.default_rng(seed)
    q = robot.q_stand.copy()
    q[robot.state_map.scalar_pin_q] += rng.normal(0.0, 0.05, robot.state_map.scalar_pin_q.size)
    v = rng.normal(0.0, 0.5, robot.nv)
    return q, v


def _target(n, stance="left", heading=0.3):
    z = np.zeros(n)
    return TrackingTarget(stance=stance, phase=0.4, heading_rad=heading, h_d=z, dh_d=z, ddh_d=z)


def _tasks(robot):
    builder = WholeBodyQP(robot)
    return builder.tasks


def test_the_builder_has_output_posture_and_spring_tasks(robot):
    tasks = _tasks(robot)
    assert [t.name for t in tasks] == ["outputs", "posture"] + (["springs"] if robot.passive_v_idx.size else [])
    assert isinstance(tasks[0], OutputTask) and all(isinstance(t, JointTask) for t in tasks[1:])


@pytest.mark.parametrize("stance", ["left", "right"])
def test_every_task_jacobian_matches_finite_differences(robot, stance):
    """Every column of every task's Jacobian (each velocity direction) against central differences."""
    q, v = _state(robot, 1)
    kin = RobotKinematics(robot)
    kin.update(q, v)
    tasks = _tasks(robot)
    target = _target(tasks[0].size, stance)
    eps = 1e-6
    for task in tasks:
        J = task.jacobian(kin, target).copy()
        y0 = task.value(kin, target).copy()
        kin_p = RobotKinematics(robot)
        for direction in np.eye(robot.nv):
            kin_p.update(pin.integrate(robot.pin_model, q, eps * direction), v)
            y_p = task.value(kin_p, target).copy()
            kin_p.update(pin.integrate(robot.pin_model, q, -eps * direction), v)
            y_m = task.value(kin_p, target).copy()
            fd = (y_p - y_m) / (2 * eps)
            assert np.max(np.abs(fd - J @ direction)) < 1e-5, (task.name, direction)
        assert np.allclose(task.value(kin, target), y0)


def test_output_drift_matches_finite_difference_of_J_v(robot):
    q, v = _state(robot, 2)
    kin = RobotKinematics(robot)
    kin.update(q, v)
    task = _tasks(robot)[0]
    target = _target(task.size)
    drift = task.drift(kin, target).copy()
    eps = 1e-6
    other = RobotKinematics(robot)
    other.update(pin.integrate(robot.pin_model, q, eps * v), v)
    jv_p = task.jacobian(other, target) @ v
    other.update(pin.integrate(robot.pin_model, q, -eps * v), v)
    jv_m = task.jacobian(other, target) @ v
    fd = (jv_p - jv_m) / (2 * eps)
    assert np.max(np.abs(fd - drift)) < 1e-4 * max(1.0, np.max(np.abs(drift)))


def test_desired_acceleration_is_feedforward_plus_pd(robot):
    q, v = _state(robot, 3)
    kin = RobotKinematics(robot)
    kin.update(q, v)
    n = len(WholeBodyQP(robot).config.output_kp)
    task = OutputTask(Gains.of(n, 100.0, 20.0, 1.0))
    rng = np.random.default_rng(0)
    h_d, dh_d, ddh_d = rng.normal(size=(3, n))
    target = TrackingTarget("right", 0.5, 0.0, h_d, dh_d, ddh_d)
    y = task.value(kin, target)
    J = task.jacobian(kin, target)
    expected = ddh_d + 20.0 * (dh_d - J @ v) + 100.0 * (h_d - y)
    assert np.allclose(task.desired_acceleration(kin, target), expected)
    assert np.allclose(task.error(kin, target), h_d - y)


def test_cache_follows_the_state_and_the_stance(robot):
    kin = RobotKinematics(robot)
    task = _tasks(robot)[0]
    q, v = _state(robot, 4)
    kin.update(q, v)
    a = task.value(kin, _target(task.size, "left")).copy()
    b = task.value(kin, _target(task.size, "right")).copy()
    assert not np.allclose(a, b)
    kin.update(robot.q_stand, np.zeros(robot.nv))
    c = task.value(kin, _target(task.size, "left"))
    assert not np.allclose(a, c)


def test_gains_reject_negative_or_nan():
    with pytest.raises(InputError):
        Gains.of(3, -1.0, 1.0, 1.0)
    with pytest.raises(InputError):
        Gains.of(3, 1.0, np.nan, 1.0)


def test_joint_tasks_have_a_constant_jacobian_and_the_pd_law(robot):
    q, v = _state(robot, 5)
    kin = RobotKinematics(robot)
    kin.update(q, v)
    tasks = _tasks(robot)
    target = _target(tasks[0].size)
    assert not tasks[0].constant_jacobian  # the output map moves with the state
    joint_tasks = [t for t in tasks if t.constant_jacobian]
    assert joint_tasks, "the posture task is a JointTask"
    for task in joint_tasks:
        J = task.jacobian(None, None)
        assert np.array_equal(J, task.jacobian(kin, target))
        y, (y_d, yd_d, ydd_d) = task.value(kin, target), task.reference(kin, target)
        expected = ydd_d + task.gains.kd * (yd_d - J @ v) + task.gains.kp * (y_d - y)
        assert np.allclose(task.desired_acceleration(kin, target), expected, rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("stance", ["left", "right"])
def test_least_squares_terms_are_jacobian_and_drift_minus_desired(robot, stance):
    q, v = _state(robot, 6)
    kin = RobotKinematics(robot)
    kin.update(q, v)
    rng = np.random.default_rng(2)
    for task in _tasks(robot):
        n = task.size
        target = TrackingTarget(stance, 0.3, 0.2, *rng.normal(size=(3, n)))
        J, r = task.least_squares(kin, target)
        assert np.array_equal(J, task.jacobian(kin, target))
        expected = task.drift(kin, target) - task.desired_acceleration(kin, target)
        assert np.allclose(r, expected, rtol=1e-12, atol=1e-12), task.name
        assert r.shape == (n,)


def test_joint_task_residual_is_the_documented_affine_map_of_the_state(robot):
    q, v = _state(robot, 7)
    kin = RobotKinematics(robot)
    kin.update(q, v)
    tasks = [t for t in _tasks(robot) if t.constant_jacobian]
    target = _target(_tasks(robot)[0].size)
    for task in tasks:
        cols_q, Rq, cols_v, Rv, r0 = task.affine_residual()
        _, r = task.least_squares(kin, target)
        assert np.allclose(Rq @ q[cols_q] + Rv @ v[cols_v] + r0, r, rtol=1e-12, atol=1e-10), task.name


def test_joint_tasks_need_an_updated_kinematics(robot):
    posture = _tasks(robot)[1]
    with pytest.raises(InputError, match="update"):
        posture.desired_acceleration(RobotKinematics(robot), None)
