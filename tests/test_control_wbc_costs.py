"""The cost objects: the rows each writes, the objective they add up to, numpy and CasADi alike."""

import casadi as ca
import numpy as np
import pytest

from amlip_qp.control.wbc import costs as W
from amlip_qp.control.wbc.builder import WholeBodyQP
from amlip_qp.control.wbc.config import default_config
from amlip_qp.control.wbc.inputs import PackedInput, SymbolicInputs
from amlip_qp.robots import load_robot
from robot_states import tuned_config
from wbc_cases import corrected_target, kin_at, target_for

CASSIE_CONFIG = tuned_config("cassie", "qp")


@pytest.fixture(scope="module", params=["cassie", "rabbit"])
def robot(request):
    return load_robot(request.param)


def _built(robot, config=None, stance="left", seed=0, phase=0.5):
    builder = WholeBodyQP(robot, config)
    kin = kin_at(robot, seed=seed)
    target = target_for(kin, stance, phase=phase, offset=0.02, heading=0.2)
    problem = builder.build(kin, target)
    return builder, kin, target, problem


def _cost(builder, kind):
    found = [c for c in builder.costs if isinstance(c, kind)]
    return found[0] if found else None


def test_the_cost_list(robot):
    builder = WholeBodyQP(robot)
    names = [c.name for c in builder.costs]
    expected = ["regularization", "outputs", "posture"] + (["springs"] if robot.name == "cassie" else [])
    expected += ["torque_regularization", "rigid_spring_force_regularization"]
    expected += ["stance_yaw_moment"] if robot.name == "cassie" else []
    assert names == expected
    # Rows of E: the output task, then the torques, then the rigid-spring forces; the others fold or add to H.
    sizes = {c.name: c.size for c in builder.costs}
    n_lambda = builder.layout.n_lambda
    assert sizes["outputs"] == builder.output_task.size and sizes["torque_regularization"] == len(robot.actuated.names)
    assert sizes["rigid_spring_force_regularization"] == n_lambda
    assert sum(sizes.values()) == builder.output_task.size + len(robot.actuated.names) + n_lambda
    assert builder.costs[1].rows.start == 0


@pytest.mark.parametrize("stance", ["left", "right"])
def test_the_objective_is_the_sum_of_the_documented_costs(robot, stance):
    """1/2 x'Hx + g'x must equal 1/2 (sum of the weighted squared task errors,
    regularisations and the yaw moment) up to a constant: compared on
    differences between random points."""
    config = default_config(robot).with_(hip_yaw_feedback=0.0)
    builder, kin, target, P = _built(robot, config, stance, seed=2)
    cfg, L = builder.config, builder.layout
    fids = robot.force_frame_ids[stance]

    def objective(x):
        vdot, f = x[L.sl_vdot], x[L.sl_forces]
        total = cfg.reg_vdot * vdot @ vdot + cfg.reg_force * f @ f
        for task in builder.tasks:
            J, r = task.least_squares(kin, target)
            total += task.gains.weight @ (J @ vdot + r) ** 2
        total += cfg.reg_torque * np.sum(builder.torques(x) ** 2)
        total += cfg.reg_coupling * np.sum(builder.rigid_forces(x) ** 2)
        if len(fids) == 2 and not robot.is_planar:
            p = [kin.frame_position(fid) for fid in fids]
            mid = 0.5 * (p[0] + p[1])
            fs = x[L.sl_f_st].reshape(2, 3)
            mz = sum(np.cross(pi - mid, fi)[2] for pi, fi in zip(p, fs))
            total += cfg.stance_yaw_moment_weight * mz**2
        return 0.5 * total

    def qp(x):
        return 0.5 * x @ P.H @ x + P.g @ x

    rng = np.random.default_rng(3)
    x0 = rng.normal(0.0, 1.0, L.n)
    for _ in range(3):
        x = rng.normal(0.0, 1.0, L.n)
        assert qp(x) - qp(x0) == pytest.approx(objective(x) - objective(x0), rel=1e-9, abs=1e-9)


def test_each_cost_writes_its_rows_of_the_stacked_least_squares(robot):
    builder, kin, target, _ = _built(robot, stance="right", seed=5, phase=0.03)
    L, inp, dyn = builder.layout, builder.inputs, builder.dynamics
    n_rows = sum(c.size for c in builder.costs)
    E, e = np.full((n_rows, L.n), 777.0), np.full(n_rows, 777.0)
    x = np.random.default_rng(4).normal(0.0, 1.0, L.n)
    for cost in builder.costs:
        if cost.size:
            cost.write(inp, dyn, E[cost.rows], e[cost.rows])
    out = _cost(builder, W.OutputTaskCost)
    sw = np.sqrt(builder.output_task.gains.weight)
    J, r = builder.output_task.least_squares(kin, target)
    want = r * sw
    if inp.feedback is not None:  # Cassie: the pelvis-yaw feedback lowers the swing hip-yaw residual
        i = inp.feedback.swing_index
        want[i] -= sw[i] * inp.residual_shift
        assert inp.residual_shift != 0.0
    assert np.array_equal(E[out.rows, L.sl_vdot], J * sw[:, None]) and np.array_equal(e[out.rows], want)
    assert np.all(E[out.rows, L.sl_forces] == 777.0), "the force columns are the builder's constant zeros"
    tau = _cost(builder, W.TorqueRegularization)
    scale = np.sqrt(builder.config.reg_torque)
    assert np.allclose(E[tau.rows] @ x + e[tau.rows], scale * builder.torques(x), rtol=1e-12, atol=1e-12)
    lam = _cost(builder, W.RigidSpringForceRegularization)
    scale = np.sqrt(builder.config.reg_coupling)
    assert np.allclose(E[lam.rows] @ x + e[lam.rows], scale * builder.rigid_forces(x), rtol=1e-12, atol=1e-12)
    assert out.size + tau.size + lam.size == n_rows


def test_constant_parts_are_folded_once(robot):
    builder = WholeBodyQP(robot)
    L, cfg, cc = builder.layout, builder.config, builder.constant_cost
    fresh = W.ConstantCost(L.n, L.nv, robot.nq)
    W.Regularization(L, cfg.reg_vdot, cfg.reg_force).fold(fresh)
    assert np.array_equal(np.diag(fresh.H0), np.r_[np.full(L.nv, cfg.reg_vdot), np.full(L.n - L.nv, cfg.reg_force)])
    assert np.count_nonzero(fresh.H0 - np.diag(np.diag(fresh.H0))) == 0
    posture = builder.posture_task
    W.JointTaskCost(L, posture).fold(fresh)
    C = posture.jacobian()
    assert np.allclose(
        fresh.H0[L.sl_vdot, L.sl_vdot] - cfg.reg_vdot * np.eye(L.nv), C.T @ np.diag(posture.gains.weight) @ C
    )
    # The folded gradient is W C^T r at any state.
    kin = kin_at(robot, seed=7)
    _, r = posture.least_squares(kin, None)
    g = fresh.Kq @ kin.q + fresh.Kv @ kin.v + fresh.k0
    assert np.allclose(g, C.T @ (posture.gains.weight * r), rtol=1e-10, atol=1e-12)
    # The builder's constant part is exactly these folds (and the spring task's, if any).
    if builder.spring_task is not None:
        W.JointTaskCost(L, builder.spring_task).fold(fresh)
    for name in ("H0", "Kq", "Kv", "k0"):
        assert np.array_equal(getattr(fresh, name), getattr(cc, name)), name


@pytest.mark.parametrize("stance", ["left", "right"])
def test_yaw_moment_cost_is_the_square_of_the_stance_force_yaw_moment(stance):
    cassie = load_robot("cassie")
    w = 2.5
    _, kin, _, P = _built(cassie, CASSIE_CONFIG.with_(stance_yaw_moment_weight=w), stance, seed=3)
    without, _, _, P0 = _built(cassie, CASSIE_CONFIG.with_(stance_yaw_moment_weight=0.0), stance, seed=3)
    assert _cost(without, W.StanceYawMomentCost) is None
    dH = P.H - P0.H
    assert np.allclose(dH, dH.T) and np.array_equal(P.g, P0.g)
    sl = P.variables["forces_stance"]
    mask = np.zeros_like(dH, dtype=bool)
    mask[sl, sl] = True
    assert np.all(dH[~mask] == 0.0), "only the stance force block changes"
    rng = np.random.default_rng(1)
    x = np.zeros(P.n)
    x[sl] = rng.normal(0.0, 50.0, sl.stop - sl.start)
    pts = [kin.frame_position(f) for f in cassie.force_frame_ids[stance]]
    mid = 0.5 * (pts[0] + pts[1])
    mz = sum(np.cross(p - mid, fi)[2] for p, fi in zip(pts, x[sl].reshape(2, 3)))
    assert x @ dH @ x == pytest.approx(w * mz**2, rel=1e-9)
    assert not W.StanceYawMomentCost.applies(WholeBodyQP(load_robot("rabbit")).layout, 1.0)


def _symbolic_rows(builder, cost):
    inp, L = builder.inputs, builder.layout
    sym = SymbolicInputs.create(inp.stance, builder.robot.nq, L, builder.output_task.size)
    rows = cost.symbolic(sym, builder.dynamics.symbolic(sym))
    if not rows:
        return None
    fn = ca.Function(
        "f",
        list(sym.arguments),
        [ca.densify(ca.vertcat(*(E for E, _ in rows))), ca.densify(ca.vertcat(*(e for _, e in rows)))],
    )
    packed = PackedInput(builder.robot.nq, L, builder.output_task.size)
    packed.pack(inp)
    u = packed.array
    E, e = fn(inp.mass_upper, inp.hp, inp.Jf.T, inp.output_jacobian.T, u)
    return np.asarray(E), np.asarray(e).ravel()


def test_symbolic_rows_equal_the_numeric_terms(robot):
    config = default_config(robot).with_(hip_yaw_feedback=1.0)  # the shift of r on Cassie
    builder, *_ = _built(robot, config, stance="right", seed=6)
    inp, dyn, L = builder.inputs, builder.dynamics, builder.layout
    for cost in builder.costs:
        sym = _symbolic_rows(builder, cost)
        if isinstance(cost, (W.Regularization, W.JointTaskCost)) or (
            not cost.size and not isinstance(cost, W.StanceYawMomentCost)
        ):
            assert sym is None, cost.name  # folded, or no rows: nothing per tick
        elif isinstance(cost, W.StanceYawMomentCost):
            E, e = sym
            H = np.zeros((L.n, L.n))
            cost.add_to_hessian(inp, H)
            assert E.shape == (1, L.n) and np.all(e == 0.0)
            assert np.allclose(E.T @ E, H, rtol=1e-12, atol=1e-12)
        else:
            E_num, e_num = np.zeros((cost.size, L.n)), np.zeros(cost.size)
            cost.write(inp, dyn, E_num, e_num)
            E, e = sym
            assert np.allclose(E, E_num, rtol=1e-12, atol=1e-12), cost.name
            assert np.allclose(e, e_num, rtol=1e-12, atol=1e-9), cost.name


def test_pelvis_yaw_feedback_enters_the_output_cost_as_the_corrected_reference():
    """A build with the feedback equals a build without it on the corrected target."""
    cassie = load_robot("cassie")
    kin = kin_at(cassie, seed=8)
    target = target_for(kin, "left", heading=0.3)
    with_fb = WholeBodyQP(cassie, CASSIE_CONFIG.with_(hip_yaw_feedback=0.8))
    plain = WholeBodyQP(cassie, CASSIE_CONFIG.with_(hip_yaw_feedback=0.0))
    assert with_fb.feedback is not None
    corrected = corrected_target(with_fb.feedback, kin, target)
    a = with_fb.build(kin, target).copy()
    b = plain.build(kin, corrected)
    assert np.allclose(a.g, b.g, rtol=1e-12, atol=1e-9)
    assert np.array_equal(a.H, b.H)
    assert not np.allclose(a.g, plain.build(kin, target).g, rtol=1e-6, atol=1e-6)
