"""The whole-body QP formulation: dynamics, contact, friction, force ramps, shapes."""

import numpy as np
import pytest

from amlip_qp.control.qp_formulation import QPConfig, WholeBodyQP, default_config
from amlip_qp.control.tracker import TrackingTarget
from amlip_qp.exceptions import InputError
from amlip_qp.qp.solver import ProxQPSolver
from amlip_qp.robots import load_robot
from amlip_qp.robots.kinematics import RobotKinematics


@pytest.fixture(scope="module", params=["cassie", "rabbit"])
def robot(request):
    return load_robot(request.param)


def _kin(robot, seed=0, scale=0.02):
    rng = np.random.default_rng(seed)
    q = robot.q_stand.copy()
    q[robot.state_map.scalar_pin_q] += rng.normal(0.0, scale, robot.state_map.scalar_pin_q.size)
    v = rng.normal(0.0, 0.2, robot.nv)
    kin = RobotKinematics(robot)
    kin.update(q, v)
    return kin


def _target(kin, stance="left", phase=0.5, weight=0.0, offset=0.0):
    y, _, _ = kin.outputs(stance, 0.0)
    n = y.size
    return TrackingTarget(stance, phase, 0.0, y + offset, np.zeros(n), np.zeros(n), swing_contact_weight=weight)


def _solve(builder, kin, target):
    problem = builder.build(kin, target)
    problem.validate()
    x = ProxQPSolver(eps_abs=1e-9, warm_start=False, eps_primal_inf=1e-9).solve(problem).x
    return problem, x


@pytest.mark.parametrize("stance", ["left", "right"])
def test_solution_satisfies_the_full_dynamics_with_recovered_torques(robot, stance):
    kin = _kin(robot)
    builder = WholeBodyQP(robot)
    problem, x = _solve(builder, kin, _target(kin, stance, phase=0.5, weight=1.0, offset=0.01))
    res = problem.residuals(x)
    assert res["eq"] < 1e-6 and res["in"] < 1e-6 and res["box"] < 1e-6
    tau = builder.torques(x)
    vdot = x[problem.variables["vdot"]]
    S_T_tau = np.zeros(robot.nv)
    S_T_tau[robot.actuated.pin_v_idx] = tau
    lhs = kin.mass_matrix() @ vdot + kin.nonlinear_effects() - kin.passive_forces()
    rhs = S_T_tau + builder.generalized_contact_force(x)
    assert np.max(np.abs(lhs - rhs)) < 1e-6 * max(1.0, np.max(np.abs(lhs)))
    # Stance contact points do not accelerate (up to the velocity Baumgarte term).
    kd = builder.config.contact_kd
    for fid in robot.force_frame_ids[stance]:
        J = kin.frame_jacobian(fid)
        acc = J @ vdot + kin.frame_jdot_v(fid) + kd * (J @ kin.v)
        axes = [0, 2] if robot.is_planar else [0, 1, 2]
        if len(robot.force_frame_ids[stance]) == 1:
            assert np.max(np.abs(acc[axes])) < 1e-6
        else:
            # the heel's component along the blade is implied by the rigid foot up to O(v^2)
            assert np.max(np.abs(acc[axes])) < 0.5
    # Torques inside the limits.
    lim = robot.actuated.torque_limit_Nm
    assert np.all(tau >= lim[:, 0] - 1e-6) and np.all(tau <= lim[:, 1] + 1e-6)


def test_friction_pyramid_and_minimum_normal_force_hold(robot):
    builder = WholeBodyQP(robot)
    cfg = builder.config
    for seed in range(4):
        kin = _kin(robot, seed)
        problem, x = _solve(builder, kin, _target(kin, "left", phase=0.5, weight=1.0, offset=0.02))
        forces = builder.forces(x)
        for side in ("stance", "swing"):
            f = forces[side]
            fz = f[:, -1]
            assert np.all(fz >= -1e-6)
            tangential = np.abs(f[:, :-1])
            assert np.all(tangential <= cfg.friction_mu * fz[:, None] + 1e-6)
        assert np.all(forces["stance"][:, -1] >= cfg.min_normal_force_N - 1e-6)


def test_swing_forces_are_zero_in_the_air_and_ramp_in(robot):
    kin = _kin(robot, 5)
    builder = WholeBodyQP(robot, default_config(robot).with_(touchdown_blend=1.0))
    _, x = _solve(builder, kin, _target(kin, "right", phase=0.5, weight=0.0))
    assert np.max(np.abs(builder.forces(x)["swing"])) < 1e-6
    problem = builder.build(kin, _target(kin, "right", phase=0.95, weight=0.5))
    fz_cols = problem.variables["forces_swing"]
    ub = problem.ub[fz_cols][len(builder._axes) - 1 :: len(builder._axes)]
    assert np.allclose(ub, 0.5 * builder.config.max_normal_force_N)
    # touchdown_blend scales the pre-touchdown ramp; 0 keeps the foot unloaded until touchdown.
    for blend in (0.0, 0.4):
        scaled = WholeBodyQP(robot, default_config(robot).with_(touchdown_blend=blend))
        problem = scaled.build(kin, _target(kin, "right", phase=0.95, weight=0.5))
        ub = problem.ub[fz_cols][len(builder._axes) - 1 :: len(builder._axes)]
        assert np.allclose(ub, blend * 0.5 * builder.config.max_normal_force_N)
    with pytest.raises(InputError, match="touchdown_blend"):
        default_config(robot).with_(touchdown_blend=1.5)
    # Liftoff ramp: early in a step the previous stance foot may still carry load.
    problem = builder.build(kin, _target(kin, "right", phase=0.25 * builder.config.liftoff_phase, weight=0.0))
    ub = problem.ub[fz_cols][len(builder._axes) - 1 :: len(builder._axes)]
    assert np.allclose(ub, 0.75 * builder.config.max_normal_force_N)


def test_swing_pyramid_rows_are_lifted_only_while_the_box_pins_the_forces(robot):
    kin = _kin(robot, 8)
    builder = WholeBodyQP(robot)
    cfg = builder.config
    rows = dict(builder.problem.in_rows)["friction"]
    n_fric = rows.stop - rows.start
    stance_rows = slice(rows.start, rows.start + n_fric // 2)
    swing_rows = slice(rows.start + n_fric // 2, rows.stop)
    # In the air: the swing rows are unbounded, the box pins the forces to zero.
    problem, x = _solve(builder, kin, _target(kin, "left", phase=0.5))
    assert np.all(problem.u[swing_rows] == np.inf) and np.all(problem.u[stance_rows] == 0.0)
    assert np.max(np.abs(builder.forces(x)["swing"])) < 1e-6
    # During the liftoff ramp the foot may carry load: the pyramid is back and holds.
    problem, x = _solve(builder, kin, _target(kin, "left", phase=0.1 * cfg.liftoff_phase, offset=0.02))
    assert np.all(problem.u[rows] == 0.0)
    f = builder.forces(x)["swing"]
    assert np.all(np.abs(f[:, :-1]) <= cfg.friction_mu * f[:, -1:] + 1e-6)


def test_dimensions_do_not_depend_on_the_stance(robot):
    kin = _kin(robot, 6)
    builder = WholeBodyQP(robot)
    a = builder.build(kin, _target(kin, "left")).copy()
    b = builder.build(kin, _target(kin, "right")).copy()
    assert (a.n, a.n_eq, a.n_in) == (b.n, b.n_eq, b.n_in)
    nf = 2 * (2 if robot.is_planar else 6)
    assert a.n == robot.nv + nf
    # Rabbit: 3 floating-base rows + 2 contact rows; Cassie: 6 floating-base
    # rows (the passive rows determine the eliminated rigid-spring forces),
    # 5 contact rows and 4 rigid-spring rows.
    assert a.n_eq == (5 if robot.is_planar else 15)
    assert {"vdot", "forces_stance", "forces_swing"} <= set(a.variables)
    assert [name for name, _ in a.in_rows] == ["torque", "friction"]


def test_builder_reuses_its_buffers_and_copy_keeps_a_snapshot(robot):
    kin = _kin(robot, 7)
    builder = WholeBodyQP(robot)
    p1 = builder.build(kin, _target(kin, "left"))
    snap = p1.copy()
    p2 = builder.build(kin, _target(kin, "right"))
    assert p1 is p2
    assert not np.allclose(snap.A, p2.A)


def test_config_validation_and_defaults():
    cassie, rabbit = load_robot("cassie"), load_robot("rabbit")
    assert len(default_config(cassie).output_kp) == 9
    assert len(default_config(rabbit).output_kp) == 4
    with pytest.raises(InputError):
        default_config(cassie).with_(friction_mu=-0.1)
    with pytest.raises(InputError):
        default_config(cassie).with_(rigid_springs="maybe")
    with pytest.raises(InputError):
        QPConfig(output_kp=(1.0,), output_kd=(1.0, 2.0), output_weight=(1.0,))
    with pytest.raises(InputError):
        default_config(cassie).with_(min_normal_force_N=2000.0)


@pytest.mark.parametrize("stance", ["left", "right"])
def test_hip_yaw_feedback_aims_the_swing_foot_at_the_heading_whatever_the_pelvis_yaw(stance):
    import math

    import pinocchio as pin

    from amlip_qp.control.qp_formulation import CASSIE_CONFIG
    from amlip_qp.robots import CASSIE_OUTPUTS

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
    builder = WholeBodyQP(cassie, CASSIE_CONFIG.with_(hip_yaw_feedback=k))
    out = builder.hip_yaw_feedback_target(kin, target)
    e = yaw - (0.1 - 0.05)  # pelvis yaw minus its nominal D - h_d[stance_hip_yaw]
    assert out.h_d[i_sw] == pytest.approx(-k * e, abs=1e-12)
    assert out.dh_d[i_sw] == pytest.approx(-k * (0.5 + 0.2), abs=1e-12)
    others = [i for i in range(n) if i != i_sw]
    assert np.array_equal(out.h_d[others], h_d[others]) and np.array_equal(out.dh_d[others], dh_d[others])
    assert np.array_equal(target.h_d, h_d), "the caller's target is not modified"
    # build() applies the feedback in the cost: the same problem as a build
    # without feedback on the corrected target.
    plain = WholeBodyQP(cassie, CASSIE_CONFIG.with_(hip_yaw_feedback=0.0))
    with_fb = builder.build(kin, target).copy()
    without = plain.build(kin, out)
    assert np.allclose(with_fb.g, without.g, rtol=1e-12, atol=1e-9)
    assert np.array_equal(with_fb.H, without.H)
    assert not np.allclose(with_fb.g, plain.build(kin, target).g, rtol=1e-6, atol=1e-6)
    # The error wraps: a pelvis 2 pi further round is the same pelvis.
    q[3:7] = pin.Quaternion(pin.utils.rpyToMatrix(0.0, 0.0, yaw - 2 * math.pi)).coeffs()
    kin.update(q, v)
    assert builder.hip_yaw_feedback_target(kin, target).h_d[i_sw] == pytest.approx(-k * e, abs=1e-9)
    # Off by default in QPConfig, and for robots without hip-yaw outputs.
    assert WholeBodyQP(cassie, CASSIE_CONFIG.with_(hip_yaw_feedback=0.0)).hip_yaw_feedback_target(kin, target) is target
    rabbit = load_robot("rabbit")
    kr = _kin(rabbit)
    tr = _target(kr)
    assert WholeBodyQP(rabbit, default_config(rabbit).with_(hip_yaw_feedback=1.0)).hip_yaw_feedback_target(kr, tr) is tr


def test_a_build_after_the_other_stance_equals_a_fresh_build(robot):
    """The builder writes constant blocks once and refills the rest in place:
    nothing from a previous tick (other stance, other state) may leak."""
    from amlip_qp.control.qp_formulation import default_config

    cfg = default_config(robot)
    used = WholeBodyQP(robot, cfg)
    kin_a, kin_b = _kin(robot, seed=1), _kin(robot, seed=2)
    for kin, stance in ((kin_a, "right"), (kin_b, "left")):
        target = _target(kin, stance, phase=0.03, weight=0.5, offset=0.01)
        p = used.build(kin, target)
        used.limit_stance_foot_torque(p, target)
        used.add_stance_yaw_moment_cost(p, kin, target)
    fresh = WholeBodyQP(robot, cfg)
    q = fresh.build(kin_b, target)
    fresh.limit_stance_foot_torque(q, target)
    fresh.add_stance_yaw_moment_cost(q, kin_b, target)
    for name in ("H", "g", "A", "b", "C", "l", "u", "lb", "ub"):
        assert np.array_equal(getattr(p, name), getattr(q, name)), name


@pytest.mark.parametrize("mode, n_lambda", [("all", 4), ("swing", 2), ("none", 0)])
def test_eliminated_rigid_spring_forces_satisfy_every_dynamics_row(mode, n_lambda):
    """The rigid springs' constraint forces are not variables: recovered from the
    passive rows, they must close the full dynamics (all nv rows) and hold the
    springs' rate constraints, whichever legs are held rigid."""
    cassie = load_robot("cassie")
    builder = WholeBodyQP(cassie, default_config(cassie).with_(rigid_springs=mode))
    for stance in ("left", "right"):
        # At the standing springs (random spring deflections with free springs
        # can need more than the motors' torque: infeasible by the torque rows).
        kin = _kin(cassie, seed=11, scale=0.0)
        problem, x = _solve(builder, kin, _target(kin, stance, phase=0.4, weight=0.0, offset=0.01))
        assert problem.n == cassie.nv + 12
        assert problem.n_eq == 6 + (4 - n_lambda) + 5 + n_lambda
        lam = builder.rigid_forces(x)
        assert lam.shape == (n_lambda,) and np.all(np.isfinite(lam))
        vdot = x[problem.variables["vdot"]]
        S_T_tau = np.zeros(cassie.nv)
        S_T_tau[cassie.actuated.pin_v_idx] = builder.torques(x)
        lhs = kin.mass_matrix() @ vdot + kin.nonlinear_effects() - kin.passive_forces()
        rhs = S_T_tau + builder.generalized_contact_force(x)
        assert np.max(np.abs(lhs - rhs)) < 1e-6 * max(1.0, np.max(np.abs(lhs)))
        if n_lambda:
            # The held springs' rows: G vdot = -kp g - kd G v (module docstring).
            rows = dict(problem.eq_rows)
            sl = slice(rows["rigid_stance"].start, rows["rigid_swing"].stop)
            assert np.max(np.abs(problem.A[sl] @ x - problem.b[sl])) < 1e-6
            # Held springs carry load: the tendon/shin forces are not all zero.
            assert np.max(np.abs(lam)) > 1e-3


def test_rigid_springs_that_cannot_be_eliminated_are_a_clear_error():
    """A held leg needs one passive joint per held spring (its rows give the
    springs' constraint forces); otherwise the builder says what to change."""
    cassie = load_robot("cassie")
    builder = WholeBodyQP(cassie)
    G, Gq, rest = builder._leg_springs["left"]
    # A third spring on the left leg with only two passive joints (shin, tarsus).
    builder._leg_springs["left"] = (np.vstack([G, G[:1]]), np.vstack([Gq, Gq[:1]]), np.r_[rest, rest[:1]])
    builder.__dict__.pop("_rows_by_stance", None)
    with pytest.raises(InputError, match="rigid_springs='none'"):
        builder._stance_rows("left")
    # Two springs on the same pair of passive joints: square but singular.
    builder = WholeBodyQP(cassie)
    G, Gq, rest = builder._leg_springs["left"]
    shin, tarsus = (int(np.flatnonzero(G[1])[0]), int(np.flatnonzero(G[0])[-1]))
    both = np.zeros_like(G[:1])
    both[0, [shin, tarsus]] = 1.0
    builder._leg_springs["left"] = (np.vstack([both, both]), Gq, rest)
    builder.__dict__.pop("_rows_by_stance", None)
    with pytest.raises(InputError, match="singular"):
        builder._stance_rows("left")
