"""Tests of the frame terms read from Pinocchio's data (amlip_qp.codegen.frame_terms)."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pinocchio as pin
import pytest

from amlip_qp.codegen.frame_terms import FrameTerms
from amlip_qp.robots import load_robot
from amlip_qp.robots.kinematics import RobotKinematics


def _frames(robot):
    out = [robot.base_frame_id]
    for side in robot.foot_sides:
        out += [robot.contact_frame_ids[side], *robot.force_frame_ids[side]]
    return out


def _state(robot, rng):
    q = robot.q_stand.copy()
    q[robot.state_map.scalar_pin_q] += rng.normal(0.0, 0.2, robot.state_map.scalar_pin_q.size)
    if robot.is_floating:
        q[3:7] = pin.Quaternion(pin.utils.rpyToMatrix(*rng.normal(0.0, 0.3, 3))).coeffs()
    return q, rng.normal(0.0, 1.0, robot.nv)


def _function(terms):
    outs = []
    for f in terms.frame_ids:
        outs += [terms.jacobian(f), terms.drift(f), terms.position(f)]
    outs += [terms.rotation(f) for f in terms.rotation_frame_ids]
    return ca.Function("terms", [s for _, s in terms.symbols], outs)


@pytest.mark.parametrize("name", ["cassie", "rabbit"])
def test_jacobians_drifts_and_positions_equal_pinocchio(name):
    robot = load_robot(name)
    terms = FrameTerms(robot.pin_model, _frames(robot), [robot.base_frame_id])
    fn = _function(terms)
    kin = RobotKinematics(robot)
    rng = np.random.default_rng(0)
    for _ in range(5):
        kin.update(*_state(robot, rng))
        got = fn(*terms.views(kin.data))
        for k, f in enumerate(terms.frame_ids):
            J, drift, p = (np.array(x) for x in got[3 * k : 3 * k + 3])
            np.testing.assert_allclose(J, kin.frame_jacobian6(f), rtol=0, atol=1e-13)
            np.testing.assert_allclose(drift.ravel(), kin.frame_jdot_v6(f), rtol=0, atol=1e-12)
            np.testing.assert_array_equal(p.ravel(), kin.frame_position(f))
        np.testing.assert_array_equal(np.array(got[-1]), kin.frame_rotation(robot.base_frame_id))


@pytest.mark.parametrize("name", ["cassie", "rabbit"])
def test_jacobian_and_drift_by_finite_differences(name):
    """``J v`` is the frame's velocity and ``Jdot v`` the change of ``J v`` along the motion at ``vdot = 0``."""
    robot = load_robot(name)
    terms = FrameTerms(robot.pin_model, _frames(robot))
    fn = _function(terms)
    model = robot.pin_model
    kin = RobotKinematics(robot)
    q, v = _state(robot, np.random.default_rng(1))
    eps = 1e-6

    def at(qq):
        kin.update(qq, v)
        got = fn(*terms.views(kin.data))
        return [(np.array(got[3 * k]), np.array(got[3 * k + 1]).ravel(), np.array(got[3 * k + 2]).ravel())
                for k in range(len(terms.frame_ids))]  # fmt: skip

    minus, mid, plus = at(pin.integrate(model, q, -eps * v)), at(q), at(pin.integrate(model, q, eps * v))
    for (Jm, _, pm), (J, drift, _), (Jp, _, pp) in zip(minus, mid, plus):
        np.testing.assert_allclose(J[:3] @ v, (pp - pm) / (2 * eps), rtol=0, atol=1e-7)
        # d/dt (J(q) v) at vdot = 0, linear and angular rows
        np.testing.assert_allclose(drift, (Jp @ v - Jm @ v) / (2 * eps), rtol=0, atol=2e-6)


def test_the_views_are_pinocchios_storage_and_stay_live():
    robot = load_robot("cassie")
    terms = FrameTerms(robot.pin_model, _frames(robot), [robot.base_frame_id])
    kin = RobotKinematics(robot)
    rng = np.random.default_rng(2)
    kin.update(*_state(robot, rng))
    views = terms.views(kin.data)
    assert all(not a.flags.owndata and (a.flags.f_contiguous or a.flags.c_contiguous) for a in views)
    first = [a.copy() for a in views]
    kin.update(*_state(robot, rng))
    fresh = terms.views(kin.data)
    for live, new in zip(views, fresh):
        np.testing.assert_array_equal(live, new)  # the views made before show the new update
    assert any(not np.array_equal(o, n) for o, n in zip(first, fresh))
    names = [n for n, _ in terms.symbols]
    assert names[:4] == ["J", "Jcom", "com", "acom"] and len(names) == len(set(names)) == len(views)
