"""Shared test helpers: the robots under test, random states, MuJoCo's forward pass and finite
differences (not a test module)."""

import mujoco
import numpy as np
import pinocchio as pin

from amlip_qp.robots import mj_to_pin

#: Every bundled robot; the robots/ tests run on each.
ROBOTS = ["rabbit", "cassie"]


def random_mj_state(robot, rng):
    """Random MuJoCo state: joints within range, random base pose and velocities."""
    m = robot.mj_model
    qpos = m.qpos0.copy()
    for j in range(m.njnt):
        qa, jt = m.jnt_qposadr[j], m.jnt_type[j]
        if jt == mujoco.mjtJoint.mjJNT_FREE:
            qpos[qa : qa + 3] = rng.uniform(-1, 1, 3)
            quat = rng.normal(size=4)
            qpos[qa + 3 : qa + 7] = quat / np.linalg.norm(quat)
        elif m.jnt_limited[j]:
            qpos[qa] = rng.uniform(*m.jnt_range[j])
        else:
            qpos[qa] = rng.uniform(-1, 1)
    return qpos, rng.normal(size=m.nv)


def random_states(robot, n, seed):
    """``n`` random states: ``(qpos, qvel)`` (MuJoCo) and the same ``(q, v)`` (Pinocchio)."""
    rng = np.random.default_rng(seed)
    for _ in range(n):
        qpos, qvel = random_mj_state(robot, rng)
        q, v = mj_to_pin(robot, qpos, qvel)
        yield qpos, qvel, q, v


def mujoco_at(robot, qpos, qvel):
    """MuJoCo's data after its forward pass (and the subtree velocities) at ``(qpos, qvel)``."""
    m = robot.mj_model
    d = mujoco.MjData(m)
    d.qpos[:], d.qvel[:] = qpos, qvel
    mujoco.mj_forward(m, d)
    mujoco.mj_subtreeVel(m, d)
    return d


def fd_along(robot, fun, q, direction, h=1e-6):
    """d/dt fun(q(t)) at t=0 with q(t) = integrate(q, direction t) (central difference)."""
    qp = pin.integrate(robot.pin_model, q, direction * h)
    qm = pin.integrate(robot.pin_model, q, -direction * h)
    return (fun(qp) - fun(qm)) / (2 * h)


def fd_jacobian(robot, fun, q):
    """The Jacobian of ``fun`` at ``q`` by central differences along each velocity direction."""
    eye = np.eye(robot.nv)
    return np.column_stack([fd_along(robot, fun, q, eye[k]) for k in range(robot.nv)])


def assert_jacobians_match_fd(robot, checks, q, v, at, tol):
    """Each ``(pos_fun, J, Jdot_v, jac_fun)`` of ``checks``: ``J`` against the finite difference of
    ``pos_fun`` at ``q``, ``Jdot_v`` against that of ``jac_fun(q) @ v`` along ``v``; ``at(q, v, fun)``
    evaluates ``fun`` on kinematics updated at ``(q, v)``."""
    for pos_fun, J, jdv, jac_fun in checks:
        J_fd = fd_jacobian(robot, lambda qq, f=pos_fun: at(qq, v, f), q)
        np.testing.assert_allclose(J, J_fd, atol=tol)
        jdv_fd = fd_along(robot, lambda qq, f=jac_fun: at(qq, v, f) @ v, q, v)
        np.testing.assert_allclose(jdv, jdv_fd, atol=tol * max(1.0, np.abs(jdv_fd).max(initial=0.0)))


def tuned_config(robot_name: str, tracker: str):
    """The bundled robot's tuned tracker configuration, from its profile file."""
    from amlip_qp.profiles import get_profile

    return get_profile(robot_name).tracker_config(tracker)


def near_stand_q(robot, rng, spread_rad=0.1):
    """A configuration near the stand pose: every scalar joint moved by a normal draw of
    ``spread_rad`` and, on a floating base, a random base orientation near upright."""
    q = robot.q_stand.copy()
    q[robot.state_map.scalar_pin_q] += rng.normal(0.0, spread_rad, robot.state_map.scalar_pin_q.size)
    if robot.is_floating:
        quat = rng.normal(0.0, 0.2, 4)
        quat[3] += 1.0
        q[3:7] = quat / np.linalg.norm(quat)
    return q
