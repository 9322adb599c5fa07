"""The constraint objects: each writes exactly the block it claims, with the right numbers, numpy and CasADi alike."""

import math

import casadi as ca
import numpy as np
import pytest

from amlip_qp.control.wbc.builder import WholeBodyQP
from amlip_qp.control.wbc.config import default_config
from amlip_qp.control.wbc.inputs import PackedInput, SymbolicInputs
from amlip_qp.robots import load_robot
from robot_states import tuned_config
from wbc_cases import FIELDS, build_and_solve, kin_at, solve, target_for

CASSIE_CONFIG = tuned_config("cassie", "qp")

#: The problem arrays of each kind of block.
BLOCK_FIELDS = {"eq": ("A", "b"), "in": ("C", "l", "u"), "box": ("lb", "ub")}


@pytest.fixture(scope="module", params=["cassie", "rabbit"])
def robot(request):
    return load_robot(request.param)


def _cases(robot):
    yield default_config(robot)
    if robot.name == "cassie":
        yield CASSIE_CONFIG.with_(rigid_springs="swing", stance_foot_torque_max_Nm=math.inf)


def test_blocks_tile_the_problem(robot):
    builder = WholeBodyQP(robot)
    P = builder.problem
    for kind, total in (("eq", P.n_eq), ("in", P.n_in), ("box", P.n)):
        covered = [i for c in builder.constraints if c.kind == kind for i in range(c.rows.start, c.rows.stop)]
        assert sorted(covered) == list(range(total)) and len(set(covered)) == total, kind
    assert [n for n, _ in P.eq_rows] == ["dynamics", "contact", "rigid_stance", "rigid_swing"]
    assert [n for n, _ in P.in_rows] == ["torque", "friction"]
    assert builder.constraint("torque").kind == "in"


@pytest.mark.parametrize("stance", ["left", "right"])
def test_each_constraint_writes_its_whole_block_and_nothing_else(robot, stance):
    """On a problem filled with a sentinel, a constraint's initialize + write
    must restore its block of the full build exactly and leave the rest."""
    for config in _cases(robot):
        builder = WholeBodyQP(robot, config)
        kin = kin_at(robot, seed=1)
        ref = builder.build(kin, target_for(kin, stance, phase=0.03, offset=0.01)).copy()
        for c in builder.constraints:
            P = ref.copy()
            for name in FIELDS:
                getattr(P, name)[...] = 777.0
            c.initialize(P)
            c.write(builder.inputs, builder.dynamics, P)
            for name in FIELDS:
                got, want = getattr(P, name), getattr(ref, name)
                inside = np.zeros(got.shape[0], dtype=bool)
                if name in BLOCK_FIELDS[c.kind]:
                    inside[c.rows] = True
                assert np.array_equal(got[inside], want[inside]), (c.name, name)
                assert np.all(got[~inside] == 777.0), (c.name, name)


def _symbolic_block(builder, c):
    """The constraint's symbolic entries evaluated at the last build's inputs."""
    inp, L = builder.inputs, builder.layout
    sym = SymbolicInputs.create(inp.stance, builder.robot.nq, L, builder.output_task.size)
    parts = {k: v for k, v in c.symbolic(sym, builder.dynamics.symbolic(sym)).items() if v is not None}
    fn = ca.Function("f", list(sym.arguments), [ca.densify(v) for v in parts.values()])
    packed = PackedInput(builder.robot.nq, L, builder.output_task.size)
    packed.pack(inp)
    u = packed.array
    values = fn(inp.mass_upper, inp.hp, inp.Jf.T, inp.output_jacobian.T, u)
    values = values if isinstance(values, (list, tuple)) else [values]
    return {k: np.asarray(v) for k, v in zip(parts, values)}


@pytest.mark.parametrize("phase", [0.5, 0.02])
def test_symbolic_entries_equal_the_numeric_ones(robot, phase):
    for config in _cases(robot):
        builder = WholeBodyQP(robot, config)
        kin = kin_at(robot, seed=4)
        P = builder.build(kin, target_for(kin, "right", phase=phase, offset=0.02))
        for c in builder.constraints:
            if not c.size:
                assert c.symbolic(None, None) == {}
                continue
            for key, value in _symbolic_block(builder, c).items():
                want = getattr(P, key)[c.rows]
                got = value.ravel()[c.rows] if c.kind == "box" else value.reshape(want.shape)
                finite = np.isfinite(want)
                assert np.array_equal(finite, np.isfinite(got)) and np.array_equal(got[~finite], want[~finite])
                assert np.allclose(got[finite], want[finite], rtol=1e-12, atol=1e-9), (c.name, key)
                if c.kind == "box":  # zero outside its variables (the problem's box is the sum)
                    outside = np.ones(value.size, dtype=bool)
                    outside[c.rows] = False
                    assert np.all(value.ravel()[outside] == 0.0), (c.name, key)


@pytest.mark.parametrize("stance", ["left", "right"])
def test_contact_rows_are_the_stance_points_accelerations(robot, stance):
    builder = WholeBodyQP(robot)
    kin = kin_at(robot, seed=3)
    P = builder.build(kin, target_for(kin, stance))
    c = builder.constraint("contact")
    vdot = np.random.default_rng(0).normal(0.0, 3.0, robot.nv)
    got = P.A[c.rows, : robot.nv] @ vdot - P.b[c.rows]
    kd = builder.config.contact_kd
    acc = [kin.frame_jacobian(f) @ (vdot + kd * kin.v) + kin.frame_jdot_v(f) for f in robot.force_frame_ids[stance]]
    if robot.is_planar:
        assert np.allclose(got, acc[0][[0, 2]], rtol=1e-12, atol=1e-9)
        return
    # Toe: all 3 components. Heel: the 2 directions orthogonal to the blade.
    assert np.allclose(got[:3], acc[0], rtol=1e-12, atol=1e-9)
    toe, heel = (kin.frame_position(f) for f in robot.force_frame_ids[stance])
    axis = (toe - heel) / np.linalg.norm(toe - heel)
    n1 = np.array([0.0, 0.0, 1.0]) - axis[2] * axis  # the vertical made orthogonal to the blade
    n1 /= np.linalg.norm(n1)
    N = np.array([n1, np.cross(axis, n1)])
    assert np.allclose(got[3:], N @ acc[1], rtol=1e-12, atol=1e-9)


@pytest.mark.parametrize("stance", ["left", "right"])
def test_rigid_spring_rows_are_the_spring_rate_law(stance):
    cassie = load_robot("cassie")
    builder = WholeBodyQP(cassie)
    kin = kin_at(cassie, seed=6)
    P = builder.build(kin, target_for(kin, stance))
    c, cfg = builder.constraint("rigid_springs"), builder.config
    springs = builder.dynamics.elimination.leg_springs
    swing = "right" if stance == "left" else "left"
    vdot = np.random.default_rng(1).normal(0.0, 3.0, cassie.nv)
    got = P.A[c.rows, : cassie.nv] @ vdot - P.b[c.rows]
    want = []
    for side, kp, kd in (
        (stance, cfg.stance_coupling_kp, cfg.stance_coupling_kd),
        (swing, cfg.coupling_kp, cfg.coupling_kd),
    ):
        s = springs[side]
        want.append(s.G @ vdot + kp * (s.Gq @ kin.q - s.rest) + kd * (s.G @ kin.v))
    assert np.allclose(got, np.concatenate(want), rtol=1e-12, atol=1e-9)
    assert dict(P.eq_rows)["rigid_stance"].stop - dict(P.eq_rows)["rigid_stance"].start == len(springs[stance].G)


@pytest.mark.parametrize("stance", ["left", "right"])
@pytest.mark.parametrize("limit", [0.0, 5.0])
def test_stance_foot_torque_bound_holds_and_the_swing_foot_stays_free(stance, limit):
    cassie = load_robot("cassie")
    builder = WholeBodyQP(cassie, CASSIE_CONFIG.with_(stance_foot_torque_max_Nm=limit))
    kin = kin_at(cassie)
    _, x = build_and_solve(builder, kin, target_for(kin, stance, offset=0.01))
    P = builder.problem
    names = list(cassie.actuated.joint_names)
    tau = builder.torques(x)
    assert abs(tau[names.index(f"{stance}-foot")]) <= limit + 1e-6
    rows = builder.constraint("torque").rows
    lim, tau0 = cassie.actuated.torque_limit_Nm, builder.dynamics.tau0
    for i, name in enumerate(names):
        lo, hi = (max(lim[i, 0], -limit), min(lim[i, 1], limit)) if name == f"{stance}-foot" else lim[i]
        assert P.l[rows.start + i] == lo - tau0[i] and P.u[rows.start + i] == hi - tau0[i], name
    assert np.all(tau >= lim[:, 0] - 1e-6) and np.all(tau <= lim[:, 1] + 1e-6)


def test_torque_bounds_are_the_motor_limits_without_a_foot_motor_or_a_bound(robot):
    config = default_config(robot).with_(stance_foot_torque_max_Nm=math.inf if robot.name == "cassie" else 0.0)
    torque = WholeBodyQP(robot, config).constraint("torque")
    for side in robot.foot_sides:
        lo, hi = torque.bounds[side]
        assert np.array_equal(lo, robot.actuated.torque_limit_Nm[:, 0])
        assert np.array_equal(hi, robot.actuated.torque_limit_Nm[:, 1])


def test_friction_pyramid_and_minimum_normal_force_hold_in_solutions(robot):
    builder = WholeBodyQP(robot)
    cfg = builder.config
    for seed in range(4):
        kin = kin_at(robot, seed)
        _, x = build_and_solve(builder, kin, target_for(kin, "left", weight=1.0, offset=0.02))
        forces = builder.forces(x)
        for f in forces.values():
            assert np.all(f[:, -1] >= -1e-6)
            assert np.all(np.abs(f[:, :-1]) <= cfg.friction_mu * f[:, -1:] + 1e-6)
        assert np.all(forces["stance"][:, -1] >= cfg.min_normal_force_N - 1e-6)
        assert np.all(forces["stance"][:, -1] <= cfg.max_normal_force_N + 1e-6)


def test_friction_rows_are_the_pyramid_and_lifted_only_while_the_box_pins_the_swing_forces(robot):
    builder = WholeBodyQP(robot)
    cfg, L, fric = builder.config, builder.layout, builder.constraint("friction")
    kin = kin_at(robot, 8)
    P = builder.build(kin, target_for(kin, "left", phase=0.5))
    # C f for one force point: +-f_t - mu f_z per tangential axis.
    f = np.random.default_rng(2).normal(0.0, 10.0, L.n)
    d = L.point_dim
    pts = f[L.sl_forces].reshape(-1, d)
    want = [s * p[t] - cfg.friction_mu * p[-1] for p in pts for t in range(d - 1) for s in (1.0, -1.0)]
    assert np.allclose(P.C[fric.rows] @ f, want, rtol=1e-15)
    stance_rows = slice(fric.rows.start, fric.swing_rows.start)
    # In the air: the swing rows are unbounded, the box pins the forces to zero.
    assert np.all(P.u[fric.swing_rows] == np.inf) and np.all(P.u[stance_rows] == 0.0)
    x = solve(P)
    assert np.max(np.abs(builder.forces(x)["swing"])) < 1e-6
    # During the liftoff ramp the foot may carry load: the pyramid is back and holds.
    P, x = build_and_solve(builder, kin, target_for(kin, "left", phase=0.1 * cfg.liftoff_phase, offset=0.02))
    assert np.all(P.u[fric.rows] == 0.0) and np.all(P.l[fric.rows] == -np.inf)
    sw = builder.forces(x)["swing"]
    assert np.all(np.abs(sw[:, :-1]) <= cfg.friction_mu * sw[:, -1:] + 1e-6)


@pytest.mark.parametrize("stance", ["left", "right"])
def test_joint_limits_stop_the_swing_leg_inside_its_range_within_the_horizon(robot, stance):
    builder = WholeBodyQP(robot)
    cfg = builder.config
    kin = kin_at(robot, seed=9, v_scale=2.0)
    P = builder.build(kin, target_for(kin, stance))
    swing = "right" if stance == "left" else "left"
    hz, rec = cfg.joint_limit_horizon_s, cfg.joint_limit_max_recovery
    m = robot.pin_model
    for i, name in enumerate(robot.actuated.joint_names):
        vi, qi = robot.actuated.pin_v_idx[i], robot.actuated.pin_q_idx[i]
        if not name.startswith(swing):
            assert (P.lb[vi], P.ub[vi]) == (-np.inf, np.inf), name
            continue
        lo, hi = m.lowerPositionLimit[qi], m.upperPositionLimit[qi]
        q, v = kin.q[qi], kin.v[vi]
        # Decelerating at ub from (q, v) for hz stays below q_hi: q + v hz + ub hz^2 / 2 <= q_hi.
        assert P.ub[vi] == pytest.approx(max(2.0 * (hi - q - v * hz) / hz**2, -rec), rel=1e-12), name
        assert P.lb[vi] == pytest.approx(min(2.0 * (lo - q - v * hz) / hz**2, rec), rel=1e-12), name
    free = np.setdiff1d(np.arange(robot.nv), robot.actuated.pin_v_idx)
    assert np.all(P.lb[free] == -np.inf) and np.all(P.ub[free] == np.inf)


def test_swing_force_box_follows_the_ramp(robot):
    kin = kin_at(robot, 5)
    fmax = default_config(robot).max_normal_force_N
    builder = WholeBodyQP(robot, default_config(robot).with_(touchdown_blend=1.0))
    L = builder.layout
    fz_sw, ft_sw = L.normal_index(L.sl_f_sw), L.tangential_index(L.sl_f_sw)
    _, x = build_and_solve(builder, kin, target_for(kin, "right", phase=0.5))
    assert np.max(np.abs(builder.forces(x)["swing"])) < 1e-6
    P = builder.build(kin, target_for(kin, "right", phase=0.95, weight=0.5))
    assert np.allclose(P.ub[fz_sw], 0.5 * fmax) and np.all(P.lb[fz_sw] == 0.0)
    mu = builder.config.friction_mu
    assert np.allclose(P.ub[ft_sw], 0.5 * mu * fmax) and np.allclose(P.lb[ft_sw], -0.5 * mu * fmax)
    # touchdown_blend scales the pre-touchdown ramp; 0 keeps the foot unloaded until touchdown.
    for blend in (0.0, 0.4):
        scaled = WholeBodyQP(robot, default_config(robot).with_(touchdown_blend=blend))
        P = scaled.build(kin, target_for(kin, "right", phase=0.95, weight=0.5))
        assert np.allclose(P.ub[fz_sw], blend * 0.5 * fmax)
    # Liftoff ramp: early in a step the previous stance foot may still carry load.
    P = builder.build(kin, target_for(kin, "right", phase=0.25 * builder.config.liftoff_phase))
    assert np.allclose(P.ub[fz_sw], 0.75 * fmax)
    fz_st = L.normal_index(L.sl_f_st)
    assert np.all(P.lb[fz_st] == builder.config.min_normal_force_N) and np.all(P.ub[fz_st] == fmax)


@pytest.mark.parametrize(("pitch_deg", "heading_deg"), [(-15.0, 0.0), (20.0, 30.0)])
def test_tilted_stance_pyramid_is_the_cone_about_the_ground_normal(pitch_deg, heading_deg):
    robot = load_robot("cassie")
    builder = WholeBodyQP(robot)
    L, mu, fric, P = builder.layout, builder.config.friction_mu, builder.constraint("friction"), builder.problem
    flat = P.C[fric.rows].copy()
    fric.tilt_stance_rows(P, 0.0, 0.0)
    assert np.array_equal(P.C[fric.rows], flat)
    a, D = -math.radians(pitch_deg), math.radians(heading_deg)
    t1 = np.array([math.cos(a) * math.cos(D), math.cos(a) * math.sin(D), math.sin(a)])
    n = np.cross(t1, [-math.sin(D), math.cos(D), 0.0])
    assert n[2] > 0.0 and np.isclose(np.linalg.norm(n), 1.0)
    fric.tilt_stance_rows(P, math.radians(pitch_deg), D)
    stance_rows = slice(fric.rows.start, fric.swing_rows.start)
    assert np.array_equal(P.C[fric.swing_rows], flat[fric.swing_rows.start - fric.rows.start :])
    for ratio, inside in ((0.95 * mu, True), (1.05 * mu, False)):
        # every stance point pushes along the normal with a tangential part up or down the slope
        x = np.zeros(L.n)
        x[L.sl_f_st] = np.tile(100.0 * (n + ratio * t1), L.n_points)
        assert np.all(P.C[stance_rows] @ x <= 1e-9) == inside
    # a vertical force on a slope steeper than the pyramid's angle slips
    x = np.zeros(L.n)
    x[L.sl_f_st] = np.tile([0.0, 0.0, 100.0], L.n_points)
    assert np.all(P.C[stance_rows] @ x <= 0.0) == (math.tan(abs(a)) <= mu)
