"""Tests of the iterative IK (amlip_qp.control.pbc.ik) on Cassie and Rabbit."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from amlip_qp.control.pbc.ik import IterativeIK
from amlip_qp.control.pbc.ik_settings import IKSettings
from amlip_qp.exceptions import InputError
from amlip_qp.robots import load_robot
from amlip_qp.robots.kinematics import RobotKinematics


@pytest.fixture(scope="module", params=["cassie", "rabbit"])
def robot(request):
    return load_robot(request.param)


def _perturbed_state(robot, seed: int, scale: float = 0.05):
    """A standing configuration with perturbed joints and base, and a random velocity."""
    rng = np.random.default_rng(seed)
    dq = np.zeros(robot.nv)
    nb = robot.nv - robot.nu - len(robot.passive_v_idx)
    dq[:nb] = rng.normal(0.0, 0.02, nb)
    dq[nb:] = rng.normal(0.0, scale, robot.nv - nb)
    q = pin.integrate(robot.pin_model, robot.q_stand, dq)
    q[robot.actuated.pin_q_idx] = np.clip(
        q[robot.actuated.pin_q_idx],
        robot.pin_model.lowerPositionLimit[robot.actuated.pin_q_idx] + 0.05,
        robot.pin_model.upperPositionLimit[robot.actuated.pin_q_idx] - 0.05,
    )
    v = rng.normal(0.0, 0.2, robot.nv)
    return q, v


def test_ik_evaluates_the_output_map_on_its_own_kinematics(robot):
    """The IK has no output code of its own: it evaluates robots.outputs.OutputMap on a
    private RobotKinematics (own Pinocchio data), and leaves the controller's untouched."""
    q, v = _perturbed_state(robot, 1)
    kin = RobotKinematics(robot)
    kin.update(q, v)
    # no row exchange (h + 0.01 is out of reach from some of these states): every row of A is an output's
    ik = IterativeIK(robot, IKSettings(knee_limit_swap=False))
    assert ik.kin is not kin and ik.kin.data is not kin.data
    heading = 0.3 if not robot.is_planar else 0.0
    for stance in ("left", "right"):
        h, J, _ = kin.outputs(stance, heading)
        h, J = h.copy(), J.copy()
        ik.kin.update_positions(q)
        y, J_ik, _ = ik.kin.outputs(stance, heading)
        np.testing.assert_allclose(y, h, atol=1e-12)
        np.testing.assert_allclose(J_ik, J, atol=1e-12)
        n = h.size
        res = ik.solve(kin, stance, heading, h + 0.01, np.zeros(n), np.zeros(n))
        assert res.ok and ik.last_result is res
        # The output rows of the IK's matrix A(q_r) are the output map's Jacobian at q_r:
        # A dq = [dh; 0] moves the outputs by J(q_r) dq = dh.
        ik.kin.update_positions(res.q_r)
        J_r = ik.kin.outputs(stance, heading)[1]
        rhs = np.zeros(robot.nv)
        rhs[:n] = np.linspace(-0.01, 0.01, n)
        np.testing.assert_allclose(J_r @ ik.solve_linear(rhs), rhs[:n], atol=1e-9)
        np.testing.assert_array_equal(kin.q, q)
        np.testing.assert_array_equal(kin.v, v)
        np.testing.assert_array_equal(kin.outputs(stance, heading)[0], h)


def test_ik_evaluates_the_output_map_of_the_kinematics_it_is_given(robot):
    """Given the walking controller's kinematics (the generated-C output map by default), the IK
    evaluates that same map on its own kinematics; given Python-map kinematics, the Python map.
    The two give the same references to rounding (converged or not: the iterates are the same)."""
    from amlip_qp.control.walking.outputs_compiled import CompiledOutputMap, make_kinematics
    from amlip_qp.robots.outputs import OutputMap

    q, v = _perturbed_state(robot, 3)
    kin_c, kin_p = make_kinematics(robot), RobotKinematics(robot)
    assert isinstance(kin_c.output_map, CompiledOutputMap)
    for k in (kin_c, kin_p):
        k.update(q, v)
    settings = IKSettings(knee_limit_swap=False)
    ik_c, ik_p = IterativeIK(robot, settings), IterativeIK(robot, settings)
    assert isinstance(ik_c.kin.output_map, OutputMap)  # before any solve
    heading = 0.0 if robot.is_planar else 0.25
    for stance in ("left", "right"):
        h = kin_p.outputs(stance, heading)[0]
        n = h.size
        dh, ddh = np.linspace(-0.1, 0.1, n), np.linspace(0.2, -0.2, n)
        res_c = ik_c.solve(kin_c, stance, heading, h + 0.001, dh, ddh)
        res_p = ik_p.solve(kin_p, stance, heading, h + 0.001, dh, ddh)
        assert ik_c.kin.output_map is kin_c.output_map and ik_c.kin.data is not kin_c.data
        assert ik_p.kin.output_map is kin_p.output_map
        assert res_c.ok and res_p.ok and res_c.iterations == res_p.iterations
        np.testing.assert_allclose(res_c.q_r, res_p.q_r, rtol=0, atol=1e-10)
        np.testing.assert_allclose(res_c.v_r, res_p.v_r, rtol=0, atol=1e-8)
        np.testing.assert_allclose(res_c.a_r, res_p.a_r, rtol=0, atol=1e-6)
    # handed the other kinematics, it follows them
    ik_c.solve(kin_p, "left", heading, kin_p.outputs("left", heading)[0], np.zeros(n), np.zeros(n))
    assert ik_c.kin.output_map is kin_p.output_map


@pytest.mark.parametrize("stance", ["left", "right"])
def test_converges_and_holds_the_stance_foot_and_passive_joints(robot, stance):
    q_est, v_est = _perturbed_state(robot, 2)
    kin = RobotKinematics(robot)
    kin.update(q_est, v_est)
    heading = 0.0 if robot.is_planar else 0.2
    h_est, _, _ = kin.outputs(stance, heading)
    # a target near the estimate's outputs, solved from the estimate (cold start)
    ik = IterativeIK(robot)
    rng = np.random.default_rng(3)
    h_d = h_est + rng.normal(0.0, 0.01, h_est.size)
    n = h_d.size
    res = ik.solve(kin, stance, heading, h_d, np.zeros(n), np.zeros(n), iterations=12)
    assert res.ok
    assert res.residual < 1e-8
    kin_r = RobotKinematics(robot)
    kin_r.update(res.q_r, np.zeros(robot.nv))
    h_r, _, _ = kin_r.outputs(stance, heading)
    np.testing.assert_allclose(h_r, h_d, atol=1e-8)
    # stance contact pose held
    cid = robot.contact_frame_ids[stance]
    np.testing.assert_allclose(kin_r.frame_position(cid), kin.frame_position(cid), atol=1e-8)
    rot_err = pin.log3(kin_r.frame_rotation(cid) @ kin.frame_rotation(cid).T)
    np.testing.assert_allclose(rot_err, 0.0, atol=1e-8)
    # passive joints: the shins fixed, each coupling length fixed
    coupled = {int(i) for c in robot.couplings for i in c.pin_q_idx}
    for iq in robot.passive_q_idx:
        if int(iq) not in coupled:
            assert res.q_r[iq] == pytest.approx(q_est[iq], abs=1e-10)
    for c in robot.couplings:
        assert c.coefficients @ res.q_r[c.pin_q_idx] == pytest.approx(c.coefficients @ q_est[c.pin_q_idx], abs=1e-10)
    # Cassie's stance toe (passive in the paper) held
    if not robot.is_planar:
        iq = robot.state_map.joint_pin_q[f"{stance}-foot"]
        assert res.q_r[iq] == pytest.approx(q_est[iq], abs=1e-10)


def test_warm_start_converges_in_few_iterations(robot):
    q_est, v_est = _perturbed_state(robot, 4)
    kin = RobotKinematics(robot)
    kin.update(q_est, v_est)
    h, _, _ = kin.outputs("left", 0.0)
    ik = IterativeIK(robot, IKSettings(iterations=2, tolerance=1e-10))
    n = h.size
    first = ik.solve(kin, "left", 0.0, h - 0.01, np.zeros(n), np.zeros(n))
    assert first.residual < 1e-8
    res = ik.solve(kin, "left", 0.0, h - 0.011, np.zeros(n), np.zeros(n))
    assert 1 <= res.iterations <= 2
    assert res.residual < 1e-8
    # the warm start reuses the previous final evaluation: equal to a cold solve to the same target
    cold = IterativeIK(robot).solve(kin, "left", 0.0, h - 0.011, np.zeros(n), np.zeros(n), iterations=12)
    np.testing.assert_allclose(res.q_r, cold.q_r, atol=1e-6)
    np.testing.assert_allclose(res.v_r, cold.v_r, atol=1e-5)


def test_velocity_reference_maps_to_dh_d_and_is_the_derivative_of_q_r(robot):
    """J(q_r) v_r = dh_d, and v_r matches a finite difference of q_r along h_d(t)."""
    stance = "right"
    q_est, v_est = _perturbed_state(robot, 5)
    v_est[:] = 0.0  # a still estimate: the held coordinates have zero rate
    kin = RobotKinematics(robot)
    kin.update(q_est, v_est)
    h0, _, _ = kin.outputs(stance, 0.0)
    rng = np.random.default_rng(6)
    dh = rng.normal(0.0, 0.2, h0.size)
    ddh = rng.normal(0.0, 1.0, h0.size)
    ik = IterativeIK(robot)

    def h_of(t):
        return h0 - 0.01 + dh * t + 0.5 * ddh * t * t

    res = ik.solve(kin, stance, 0.0, h_of(0.0), dh, ddh, iterations=15)
    kin_r = RobotKinematics(robot)
    kin_r.update(res.q_r, res.v_r)
    _, J, jdv = kin_r.outputs(stance, 0.0)
    np.testing.assert_allclose(J @ res.v_r, dh, atol=1e-9)
    # acceleration reference: J a_r + Jdot v_r = ddh_d (finite-difference drift)
    np.testing.assert_allclose(J @ res.a_r + jdv, ddh, atol=1e-4)
    dt = 1e-5
    q_p = ik.solve(kin, stance, 0.0, h_of(dt), dh + ddh * dt, ddh, iterations=15).q_r
    q_m = ik.solve(kin, stance, 0.0, h_of(-dt), dh - ddh * dt, ddh, iterations=15).q_r
    v_fd = pin.difference(robot.pin_model, q_m, q_p) / (2 * dt)
    np.testing.assert_allclose(v_fd, res.v_r, atol=1e-5)


def test_warm_solves_along_a_trajectory_match_exact_solves(robot):
    """Warm default solves (cached first step, drift at the previous v_r) along a smooth h_d(t)
    give the references of exact cold solves: q_r, v_r to the tolerance, a_r to ~dt |a_r|."""
    stance = "left"
    q_est, v_est = _perturbed_state(robot, 9)
    kin = RobotKinematics(robot)
    kin.update(q_est, v_est)
    h0, J0, _ = kin.outputs(stance, 0.0)
    h0, dh = h0.copy(), J0 @ v_est
    rng = np.random.default_rng(10)
    ddh = rng.normal(0.0, 2.0, h0.size)
    ik = IterativeIK(robot)
    dt = 5e-4
    for k in range(20):
        t = k * dt
        h_t, dh_t = h0 + dh * t + 0.5 * ddh * t * t, dh + ddh * t
        warm = ik.solve(kin, stance, 0.0, h_t, dh_t, ddh)
    assert warm.ok and warm.iterations <= 2
    exact = IterativeIK(robot).solve(kin, stance, 0.0, h_t, dh_t, ddh, iterations=12)
    assert warm.residual < 1e-6
    np.testing.assert_allclose(warm.q_r, exact.q_r, atol=1e-5)
    np.testing.assert_allclose(warm.v_r, exact.v_r, atol=1e-4)
    err = np.max(np.abs(warm.a_r - exact.a_r))
    assert err < 0.02 * max(1.0, np.max(np.abs(exact.a_r))), err


def test_nan_target_falls_back_to_previous_reference(robot):
    q_est, v_est = _perturbed_state(robot, 7)
    kin = RobotKinematics(robot)
    kin.update(q_est, v_est)
    h, _, _ = kin.outputs("left", 0.0)
    n = h.size
    ik = IterativeIK(robot)
    good = ik.solve(kin, "left", 0.0, h, np.zeros(n), np.zeros(n))
    bad = ik.solve(kin, "left", 0.0, np.full(n, np.nan), np.zeros(n), np.zeros(n))
    assert not bad.ok
    np.testing.assert_array_equal(bad.q_r, good.q_r)
    assert np.all(np.isfinite(bad.v_r)) and np.all(np.isfinite(bad.a_r))
    # without a previous reference: the estimate
    ik.reset()
    bad = ik.solve(kin, "left", 0.0, np.full(n, np.nan), np.zeros(n), np.zeros(n))
    assert not bad.ok
    np.testing.assert_array_equal(bad.q_r, q_est)


def test_joint_limits_are_respected(robot):
    q_est, v_est = _perturbed_state(robot, 8)
    kin = RobotKinematics(robot)
    kin.update(q_est, v_est)
    h, _, _ = kin.outputs("left", 0.0)
    n = h.size
    res = IterativeIK(robot).solve(kin, "left", 0.0, h + 5.0, np.zeros(n), np.zeros(n))
    aq = robot.actuated.pin_q_idx
    assert np.all(np.isfinite(res.q_r))
    assert np.all(res.q_r[aq] >= robot.pin_model.lowerPositionLimit[aq] - 1e-12)
    assert np.all(res.q_r[aq] <= robot.pin_model.upperPositionLimit[aq] + 1e-12)


def test_bad_shapes_raise(robot):
    kin = RobotKinematics(robot)
    kin.update(robot.q_stand, np.zeros(robot.nv))
    with pytest.raises(InputError):
        IterativeIK(robot).solve(kin, "left", 0.0, np.zeros(2), np.zeros(2), np.zeros(2))


def test_unreachable_com_height_holds_the_stance_knee_straight_and_keeps_the_other_outputs():
    """Cassie: a CoM height the stance leg cannot reach. The IK exchanges that output for the
    stance knee held at its straight-leg limit and still meets every other equation exactly
    (instead of clamped iterates that break the coupling rows)."""
    robot = load_robot("cassie")
    q_est, v_est = _perturbed_state(robot, 11, scale=0.02)
    kin = RobotKinematics(robot)
    kin.update(q_est, v_est)
    stance = "left"
    h, _, _ = kin.outputs(stance, 0.0)
    h_d = h.copy()
    h_d[4] += 0.3  # com_z_over_stance 30 cm higher: beyond the straight leg
    n = h.size
    ik = IterativeIK(robot)
    res = ik.solve(kin, stance, 0.0, h_d, np.zeros(n), np.zeros(n))
    assert res.ok and res.knee_at_limit
    assert res.residual < 1e-6
    iq = robot.state_map.joint_pin_q[f"{stance}-knee"]
    assert res.q_r[iq] == pytest.approx(robot.pin_model.upperPositionLimit[iq], abs=1e-9)
    kin_r = RobotKinematics(robot)
    kin_r.update_positions(res.q_r)
    h_r, _, _ = kin_r.outputs(stance, 0.0)
    others = [i for i in range(n) if i != 4]
    np.testing.assert_allclose(h_r[others], h_d[others], atol=1e-6)
    assert h_r[4] < h_d[4] - 0.1  # the CoM height gave way
    for c in robot.couplings:  # and the couplings are held
        assert c.coefficients @ res.q_r[c.pin_q_idx] == pytest.approx(c.coefficients @ q_est[c.pin_q_idx], abs=1e-6)
    # without the exchange the clamped iterates do not converge
    stuck = IterativeIK(robot, IKSettings(knee_limit_swap=False)).solve(kin, stance, 0.0, h_d, np.zeros(n), np.zeros(n))
    assert not stuck.knee_at_limit and stuck.residual > 1e-3
    # a reachable target does not trigger it
    ok = IterativeIK(robot).solve(kin, stance, 0.0, h, np.zeros(n), np.zeros(n))
    assert not ok.knee_at_limit and ok.residual < 1e-6


#: A right touchdown of the PBC on the closed-chain plant ramping to 2.1 m/s (t = 10.3445 s; the
#: plant's state mapped to the controller's model, rounded to 1e-6): the new stance foot is far
#: ahead and the springs are held at the spring model's deflections (``HELD``), so the CoM height
#: of 0.8 m over the stance foot is out of reach by about 7 mm with the knee off its limit.
FOLD_Q = [10.702951, -0.115186, 0.968636, 0.00377, 0.03558, -0.052107, 0.998, -0.057314, 0.008473,
          -0.086403, -0.842082, -0.068922, 1.190809, -0.994688, -0.000893, 0.119845, 0.885494,
          -1.020151, 0.009475, 1.232966, -1.927993]  # fmt: skip
FOLD_V = [2.454716, 0.180246, 0.268322, 0.065925, -0.043806, -0.025825, -0.101981, 0.343629, -4.625136,
          4.555202, 0.407349, -5.344723, 4.969958, 0.140139, -0.333119, -2.866441, 4.927423, -1.176374,
          -1.866049, 3.368553]  # fmt: skip
FOLD_H_D = [0.0, 0.0, 0.119845, 0.008473, 0.8, 0.426661, -0.123059, 0.8, 0.0]
FOLD_DH_D = [0.0, 0.0, -0.399482, -0.028243, 0.0, 0.0, 0.0, -1.333333, 0.0]
FOLD_DDH_D = [0.0, 0.0, 0.0, 0.0, 0.0, -39.356273, -2.729686, 8.888889, 0.0]
FOLD_HELD = [0.0, -0.040134, 0.226893, 0.337928]


def test_com_height_out_of_reach_short_of_the_knee_limit_holds_the_knee_at_its_estimate():
    """The fold (FOLD_*): without any exchange the Newton iterates circle it, unconverged, and the
    knee reference moves by tenths of a radian with the iteration count (ticks of +-195 N m in
    the closed loop); with it the IK converges with the stance knee at its estimate, every
    other output exact and the CoM height short of its reference."""
    robot = load_robot("cassie")
    kin = RobotKinematics(robot)
    q_est = np.array(FOLD_Q)
    kin.update(q_est, np.array(FOLD_V))
    args = (kin, "right", 0.0, np.array(FOLD_H_D), np.array(FOLD_DH_D), np.array(FOLD_DDH_D))
    iq = robot.state_map.joint_pin_q["right-knee"]
    knees = []
    for its in (8, 20, 50, 200):
        stuck = IterativeIK(robot, IKSettings(knee_limit_swap=False)).solve(
            *args, iterations=its, held_springs=np.array(FOLD_HELD)
        )
        assert stuck.ok and not stuck.knee_at_limit and stuck.residual > 1e-3
        knees.append(stuck.q_r[iq])
    assert max(knees) - min(knees) > 0.05  # no limit point: it wanders
    # an explicit iteration count runs exactly those iterations: no hold
    exact = IterativeIK(robot).solve(*args, iterations=2, held_springs=np.array(FOLD_HELD))
    assert not exact.knee_at_limit
    # the exchange at the limit alone does not see it: the iterates never clamp there
    old = IterativeIK(robot, IKSettings(knee_hold_short_of_limit=False)).solve(*args, held_springs=np.array(FOLD_HELD))
    assert not old.knee_at_limit and old.residual > 1e-3
    res = IterativeIK(robot).solve(*args, held_springs=np.array(FOLD_HELD))
    assert res.ok and res.knee_at_limit and res.residual < 1e-6
    assert res.q_r[iq] == pytest.approx(q_est[iq], abs=1e-9)
    kin_r = RobotKinematics(robot)
    kin_r.update_positions(res.q_r)
    h_r, _, _ = kin_r.outputs("right", 0.0)
    others = [i for i in range(len(FOLD_H_D)) if i != 4]
    np.testing.assert_allclose(h_r[others], np.array(FOLD_H_D)[others], atol=1e-6)
    assert h_r[4] < FOLD_H_D[4] - 0.005  # the CoM height gave way
    assert np.all(np.isfinite(res.v_r)) and np.all(np.isfinite(res.a_r))
