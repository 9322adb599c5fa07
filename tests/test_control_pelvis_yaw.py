"""Tests of the pelvis-yaw feedback both trackers use (amlip_qp.control.pelvis_yaw)."""

from __future__ import annotations

import math

import casadi as ca
import numpy as np
import pinocchio as pin
import pytest

from amlip_qp.control.pelvis_yaw import PelvisYawFeedback
from amlip_qp.control.tracker import TrackingTarget
from amlip_qp.robots import load_robot
from amlip_qp.robots.kinematics import RobotKinematics
from amlip_qp.robots.outputs import OutputMap


def _kin_with_base_yaw(robot, yaw_rad: float, yaw_rate_radps: float) -> RobotKinematics:
    q = robot.q_stand.copy()
    q[3:7] = pin.Quaternion(pin.utils.rpyToMatrix(0.0, 0.0, yaw_rad)).coeffs()
    v = np.zeros(robot.nv)
    v[5] = yaw_rate_radps  # base angular velocity z (local = world for a level base)
    kin = RobotKinematics(robot)
    kin.update(q, v)
    return kin


def test_swing_hip_yaw_reference_turns_the_pelvis_back_to_its_nominal_yaw():
    robot = load_robot("cassie")
    names = OutputMap(robot).names
    fb = PelvisYawFeedback.for_outputs(names, 0.8)
    assert fb is not None
    i_st, i_sw = names.index("stance_hip_yaw"), names.index("swing_hip_yaw")
    kin = _kin_with_base_yaw(robot, 0.3, 0.5)
    h_d = np.linspace(0.1, 0.9, len(names))
    dh_d = np.linspace(-0.2, 0.2, len(names))
    heading = 0.25
    tgt = TrackingTarget(stance="left", phase=0.4, heading_rad=heading, h_d=h_d, dh_d=dh_d, ddh_d=np.zeros_like(h_d))
    h, dh = fb.references(kin, tgt)
    e = 0.3 - (heading - h_d[i_st])  # pelvis yaw error against its nominal value
    assert h[i_sw] == pytest.approx(h_d[i_sw] - 0.8 * e, abs=1e-12)
    assert dh[i_sw] == pytest.approx(dh_d[i_sw] - 0.8 * (0.5 + dh_d[i_st]), abs=1e-12)
    others = np.arange(len(names)) != i_sw
    np.testing.assert_array_equal(h[others], h_d[others])
    np.testing.assert_array_equal(dh[others], dh_d[others])
    assert tgt.h_d[i_sw] == h_d[i_sw]  # the target is not changed


def test_the_yaw_error_is_wrapped_and_no_error_changes_nothing():
    robot = load_robot("cassie")
    names = OutputMap(robot).names
    fb = PelvisYawFeedback.for_outputs(names, 1.0)
    i_st = names.index("stance_hip_yaw")
    h_d = np.zeros(len(names))
    h_d[i_st] = 0.1
    # pelvis at its nominal yaw D - h_d[stance], 2 pi away: no correction
    kin = _kin_with_base_yaw(robot, 3.0 - 0.1 - 2.0 * math.pi, 0.0)
    tgt = TrackingTarget(stance="right", phase=0.1, heading_rad=3.0, h_d=h_d, dh_d=np.zeros_like(h_d), ddh_d=h_d)
    h, dh = fb.references(kin, tgt)
    np.testing.assert_allclose(h, h_d, atol=1e-12)
    np.testing.assert_allclose(dh, 0.0, atol=1e-12)


def test_no_feedback_without_gain_or_hip_yaw_outputs():
    assert PelvisYawFeedback.for_outputs(("stance_hip_yaw", "swing_hip_yaw"), 0.0) is None
    assert PelvisYawFeedback.for_outputs(OutputMap(load_robot("rabbit")).names, 1.0) is None


@pytest.mark.parametrize("yaw_rad", [-7.0, -3.3, -math.pi, -0.4, 0.0, 0.2, math.pi - 1e-9, 3.3, 9.5])
def test_the_symbolic_correction_equals_the_numeric_one(yaw_rad):
    """The CasADi form the QP tracker's generated assembly uses, with the wrap of any yaw error."""
    robot = load_robot("cassie")
    names = OutputMap(robot).names
    fb = PelvisYawFeedback.for_outputs(names, 0.7)
    n = len(names)
    kin = _kin_with_base_yaw(robot, yaw_rad, -0.3)
    h_d, dh_d = np.linspace(-0.3, 0.4, n), np.linspace(0.2, -0.1, n)
    tgt = TrackingTarget(stance="left", phase=0.3, heading_rad=0.6, h_d=h_d, dh_d=dh_d, ddh_d=np.zeros(n))
    R, rate, D = ca.SX.sym("R", 3, 3), ca.SX.sym("rate"), ca.SX.sym("D")
    hs, dhs = ca.SX.sym("h_d", n), ca.SX.sym("dh_d", n)
    fn = ca.Function("corr", [R, rate, D, hs, dhs], list(fb.symbolic_correction(R, rate, D, hs, dhs)))
    base = robot.base_frame_id
    yaw_rate = float(kin.frame_jacobian6(base)[5] @ kin.v)
    got = [float(x) for x in fn(kin.frame_rotation(base), yaw_rate, 0.6, h_d, dh_d)]
    want = fb.correction(kin, tgt)
    assert got == pytest.approx(want, rel=0, abs=1e-12)
    assert abs(got[0]) <= 0.7 * math.pi + 1e-12  # the error is wrapped into [-pi, pi)
