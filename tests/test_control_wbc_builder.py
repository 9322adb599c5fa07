"""The whole-body QP builder: the problem it assembles from its lists, its solutions, its buffers."""

import numpy as np
import pytest

from amlip_qp.control.wbc.builder import WholeBodyQP
from amlip_qp.control.wbc.config import default_config
from amlip_qp.exceptions import InputError
from amlip_qp.robots import load_robot
from robot_states import tuned_config
from wbc_cases import FIELDS, build_and_solve, kin_at, target_for

CASSIE_CONFIG = tuned_config("cassie", "qp")
RABBIT_CONFIG = tuned_config("rabbit", "qp")


@pytest.fixture(scope="module", params=["cassie", "rabbit"])
def robot(request):
    return load_robot(request.param)


@pytest.mark.parametrize("stance", ["left", "right"])
def test_solution_satisfies_the_full_dynamics_with_recovered_torques(robot, stance):
    kin = kin_at(robot)
    builder = WholeBodyQP(robot)
    problem, x = build_and_solve(builder, kin, target_for(kin, stance, phase=0.5, weight=1.0, offset=0.01))
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
    axes = [0, 2] if robot.is_planar else [0, 1, 2]
    for fid in robot.force_frame_ids[stance]:
        J = kin.frame_jacobian(fid)
        acc = J @ vdot + kin.frame_jdot_v(fid) + kd * (J @ kin.v)
        if len(robot.force_frame_ids[stance]) == 1:
            assert np.max(np.abs(acc[axes])) < 1e-6
        else:
            # the heel's component along the blade is implied by the rigid foot up to O(v^2)
            assert np.max(np.abs(acc[axes])) < 0.5
    lim = robot.actuated.torque_limit_Nm
    assert np.all(tau >= lim[:, 0] - 1e-6) and np.all(tau <= lim[:, 1] + 1e-6)
    totals = builder.normal_force_totals(x)
    forces = builder.forces(x)
    assert totals == pytest.approx((forces["stance"][:, -1].sum(), forces["swing"][:, -1].sum()))
    assert totals[0] > 0.5 * robot.mass_kg * 9.81, "the stance foot carries the robot"


def test_dimensions_do_not_depend_on_the_stance(robot):
    kin = kin_at(robot, 6)
    builder = WholeBodyQP(robot)
    a = builder.build(kin, target_for(kin, "left")).copy()
    b = builder.build(kin, target_for(kin, "right")).copy()
    assert (a.n, a.n_eq, a.n_in) == (b.n, b.n_eq, b.n_in) and a.n == builder.n_variables
    nf = 2 * (2 if robot.is_planar else 6)
    assert a.n == robot.nv + nf
    # Rabbit: 3 floating-base rows + 2 contact rows; Cassie: 6 floating-base
    # rows (the passive rows determine the eliminated rigid-spring forces),
    # 5 contact rows and 4 rigid-spring rows.
    assert a.n_eq == (5 if robot.is_planar else 15)
    assert a.n_in == len(robot.actuated.names) + (4 if robot.is_planar else 16)  # pyramid rows of every point
    assert {"vdot", "forces_stance", "forces_swing"} <= set(a.variables)


def test_builder_reuses_its_buffers_and_copy_keeps_a_snapshot(robot):
    kin = kin_at(robot, 7)
    builder = WholeBodyQP(robot)
    p1 = builder.build(kin, target_for(kin, "left"))
    snap = p1.copy()
    p2 = builder.build(kin, target_for(kin, "right"))
    assert p1 is p2 is builder.problem
    assert not np.allclose(snap.A, p2.A)


def test_a_build_after_the_other_stance_equals_a_fresh_build(robot):
    """The builder writes constant blocks once and refills the rest in place:
    nothing from a previous tick (other stance, other state) may leak. Bit for bit."""
    cfg = default_config(robot)
    used = WholeBodyQP(robot, cfg)
    kin_a, kin_b = kin_at(robot, seed=1), kin_at(robot, seed=2)
    for kin, stance in ((kin_a, "right"), (kin_b, "left")):
        target = target_for(kin, stance, phase=0.03, weight=0.5, offset=0.01)
        p = used.build(kin, target)
    fresh = WholeBodyQP(robot, cfg)
    q = fresh.build(kin_b, target)
    for name in FIELDS:
        assert np.array_equal(getattr(p, name), getattr(q, name)), name


def test_the_build_includes_every_term_without_the_caller(robot):
    """The stance foot's torque bound and the yaw-moment cost are part of the
    build: a problem straight from build() is the whole problem."""
    kin = kin_at(robot, seed=3)
    target = target_for(kin, "left")
    if robot.name == "cassie":
        plain = WholeBodyQP(robot, CASSIE_CONFIG.with_(stance_foot_torque_max_Nm=np.inf, stance_yaw_moment_weight=0.0))
        full = WholeBodyQP(robot, CASSIE_CONFIG)
    else:
        plain = WholeBodyQP(robot, RABBIT_CONFIG)
        full = WholeBodyQP(robot, RABBIT_CONFIG.with_(stance_foot_torque_max_Nm=0.0, stance_yaw_moment_weight=1.0))
    a, b = plain.build(kin, target).copy(), full.build(kin, target)
    rows = full.constraint("torque").rows
    changed_l = np.flatnonzero(a.l[rows] != b.l[rows])
    if robot.name == "cassie":
        names = list(robot.actuated.joint_names)
        assert list(changed_l) == [names.index("left-foot")]
        assert not np.array_equal(a.H, b.H)
    else:  # no foot motor, point feet: nothing to add
        assert changed_l.size == 0 and np.array_equal(a.H, b.H)


def test_wrong_configs_are_typed_errors():
    cassie, rabbit = load_robot("cassie"), load_robot("rabbit")
    with pytest.raises(InputError, match="gains for 9 outputs but rabbit has 4"):
        WholeBodyQP(rabbit, CASSIE_CONFIG)
    builder = WholeBodyQP(cassie)
    assert builder.config is CASSIE_CONFIG
    with pytest.raises(InputError, match="no constraint 'tendon'; known: dynamics"):
        builder.constraint("tendon")


@pytest.fixture(scope="module")
def sole_robot(tmp_path_factory):
    """H1 with its sole's four corners as force points (tests/sole_cases.py)."""
    from sole_cases import sole_profile

    return load_robot(sole_profile("h1", tmp_path_factory.mktemp("sole")))


def test_a_four_point_sole_has_four_pyramids_per_foot_and_six_contact_rows(sole_robot):
    robot = sole_robot
    builder = WholeBodyQP(robot)
    L = builder.layout
    assert (L.point_dim, L.n_points, L.n_force) == (3, 4, 12)
    kin = kin_at(robot, 6)
    a = builder.build(kin, target_for(kin, "left")).copy()
    b = builder.build(kin, target_for(kin, "right")).copy()
    assert (a.n, a.n_eq, a.n_in) == (b.n, b.n_eq, b.n_in) == (robot.nv + 24, 6 + 6, robot.nu + 2 * 4 * 4)
    assert builder.constraint("contact").size == 6 and builder.constraint("friction").size == 32
    yaw = next(c for c in builder.costs if c.name == "stance_yaw_moment")
    assert list(yaw.index - L.sl_f_st.start) == [0, 1, 3, 4, 6, 7, 9, 10]  # each corner's x and y


@pytest.mark.parametrize("stance", ["left", "right"])
def test_a_four_point_sole_solution_holds_the_foot_and_loads_each_corner(sole_robot, stance):
    robot = sole_robot
    kin = kin_at(robot)
    builder = WholeBodyQP(robot)
    problem, x = build_and_solve(builder, kin, target_for(kin, stance, phase=0.5, weight=1.0, offset=0.01))
    res = problem.residuals(x)
    assert res["eq"] < 1e-6 and res["in"] < 1e-6 and res["box"] < 1e-6
    tau = builder.torques(x)
    vdot = x[problem.variables["vdot"]]
    S_T_tau = np.zeros(robot.nv)
    S_T_tau[robot.actuated.pin_v_idx] = tau
    lhs = kin.mass_matrix() @ vdot + kin.nonlinear_effects() - kin.passive_forces()
    assert np.max(np.abs(lhs - S_T_tau - builder.generalized_contact_force(x))) < 1e-6 * max(1.0, np.max(np.abs(lhs)))
    kd = builder.config.contact_kd
    for fid in robot.force_frame_ids[stance]:  # every corner held, up to the rigid foot's O(v^2)
        J = kin.frame_jacobian(fid)
        assert np.max(np.abs(J @ vdot + kin.frame_jdot_v(fid) + kd * (J @ kin.v))) < 0.5
    st = builder.forces(x)["stance"]
    cfg = builder.config
    assert st.shape == (4, 3) and np.all(st[:, 2] >= cfg.min_normal_force_N - 1e-6)
    assert np.all(np.abs(st[:, :2]) <= cfg.friction_mu * st[:, 2:] + 1e-6)  # each corner's pyramid
    assert st[:, 2].sum() > 0.5 * robot.mass_kg * 9.81, "the stance foot carries the robot"


def test_normal_force_totals_are_numpys_sums_bit_for_bit(robot):
    """The totals (summed as Python floats for feet of fewer than 8 points) are NumPy's sums of the
    normal components, bit for bit, signed zeros, infinities and NaN included."""
    builder = WholeBodyQP(robot)
    L = builder.layout
    d = L.point_dim
    rng = np.random.default_rng(3)
    for i in range(2000):
        x = rng.normal(size=L.n) * 10.0 ** rng.integers(-6, 6, size=L.n)
        if i % 3 == 0:
            x[rng.integers(0, L.n, 6)] = rng.choice([0.0, -0.0, np.inf, -np.inf, np.nan], 6)
        if i % 7 == 0:
            x[:] = rng.choice([0.0, -0.0], L.n)
        want = [float(np.add.reduce(x[foot][d - 1 :: d])) for foot in (L.sl_f_st, L.sl_f_sw)]
        got = builder.normal_force_totals(x)
        assert all(type(v) is float for v in got)
        np.testing.assert_array_equal(np.array(got), np.array(want))
        assert np.array_equal(np.signbit(got), np.signbit(want))
