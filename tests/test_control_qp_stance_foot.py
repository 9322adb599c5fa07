"""The stance-foot terms of the QP: passive stance toe and the yaw-moment cost."""

import math

import numpy as np
import pytest

from amlip_qp.control.qp_formulation import CASSIE_CONFIG, RABBIT_CONFIG, WholeBodyQP
from amlip_qp.control.qp_tracker import QPTracker
from amlip_qp.control.tracker import TrackingTarget
from amlip_qp.exceptions import InputError
from amlip_qp.qp.solver import ProxQPSolver
from amlip_qp.robots import load_robot
from amlip_qp.robots.kinematics import RobotKinematics


@pytest.fixture(scope="module")
def cassie():
    return load_robot("cassie")


def _kin(robot, seed=0):
    rng = np.random.default_rng(seed)
    q = robot.q_stand.copy()
    q[robot.state_map.scalar_pin_q] += rng.normal(0.0, 0.02, robot.state_map.scalar_pin_q.size)
    kin = RobotKinematics(robot)
    kin.update(q, rng.normal(0.0, 0.2, robot.nv))
    return kin


def _target(kin, stance, offset=0.01):
    y, _, _ = kin.outputs(stance, 0.0)
    n = y.size
    return TrackingTarget(stance, 0.5, 0.0, y + offset, np.zeros(n), np.zeros(n))


def _solve(problem):
    return ProxQPSolver(eps_abs=1e-9, warm_start=False, eps_primal_inf=1e-9).solve(problem).x


def test_cassie_default_leaves_the_stance_toe_passive_and_penalises_yaw_moment():
    assert 0.0 <= CASSIE_CONFIG.stance_foot_torque_max_Nm <= 0.05  # passive up to a solver-friendly band
    assert CASSIE_CONFIG.stance_yaw_moment_weight > 0.0
    assert math.isinf(RABBIT_CONFIG.stance_foot_torque_max_Nm)  # point feet: no foot motor anyway
    with pytest.raises(InputError):
        CASSIE_CONFIG.with_(stance_foot_torque_max_Nm=-1.0)
    with pytest.raises(InputError):
        CASSIE_CONFIG.with_(stance_foot_torque_max_Nm=math.nan)
    with pytest.raises(InputError):
        CASSIE_CONFIG.with_(stance_yaw_moment_weight=-1.0)


@pytest.mark.parametrize("stance", ["left", "right"])
@pytest.mark.parametrize("limit", [0.0, 5.0])
def test_stance_foot_torque_bound_holds_and_the_swing_foot_stays_free(cassie, stance, limit):
    kin = _kin(cassie)
    builder = WholeBodyQP(cassie, CASSIE_CONFIG.with_(stance_foot_torque_max_Nm=limit))
    target = _target(kin, stance)
    problem = builder.build(kin, target)
    builder.limit_stance_foot_torque(problem, target)
    x = _solve(problem)
    tau = builder.torques(x)
    names = list(cassie.actuated.joint_names)
    swing = "right" if stance == "left" else "left"
    assert abs(tau[names.index(f"{stance}-foot")]) <= limit + 1e-6
    # The swing toe keeps its motor limit only.
    rows = dict(problem.in_rows)["torque"]
    i_sw = names.index(f"{swing}-foot")
    lim = cassie.actuated.torque_limit_Nm[i_sw]
    assert problem.u[rows.start + i_sw] == pytest.approx(lim[1] - builder._tau0[i_sw])


def test_no_bound_and_no_foot_motor_are_no_ops(cassie):
    kin = _kin(cassie)
    builder = WholeBodyQP(cassie, CASSIE_CONFIG.with_(stance_foot_torque_max_Nm=math.inf))
    target = _target(kin, "left")
    problem = builder.build(kin, target)
    before = (problem.l.copy(), problem.u.copy())
    builder.limit_stance_foot_torque(problem, target)
    assert np.array_equal(problem.l, before[0]) and np.array_equal(problem.u, before[1])
    rabbit = load_robot("rabbit")
    kr = _kin(rabbit)
    br = WholeBodyQP(rabbit, RABBIT_CONFIG.with_(stance_foot_torque_max_Nm=0.0, stance_yaw_moment_weight=1.0))
    tr = _target(kr, "left")
    pr = br.build(kr, tr)
    snapshot = pr.copy()
    br.limit_stance_foot_torque(pr, tr)
    br.add_stance_yaw_moment_cost(pr, kr, tr)
    assert np.array_equal(pr.l, snapshot.l) and np.array_equal(pr.u, snapshot.u) and np.array_equal(pr.H, snapshot.H)


@pytest.mark.parametrize("stance", ["left", "right"])
def test_yaw_moment_cost_is_the_square_of_the_stance_force_yaw_moment(cassie, stance):
    kin = _kin(cassie, seed=3)
    w = 2.5
    builder = WholeBodyQP(cassie, CASSIE_CONFIG.with_(stance_yaw_moment_weight=w))
    target = _target(kin, stance)
    problem = builder.build(kin, target)
    H0 = problem.H.copy()
    builder.add_stance_yaw_moment_cost(problem, kin, target)
    dH = problem.H - H0
    assert np.allclose(dH, dH.T)
    # Only the stance force block changes.
    sl = problem.variables["forces_stance"]
    mask = np.zeros_like(dH, dtype=bool)
    mask[sl, sl] = True
    assert np.all(dH[~mask] == 0.0)
    # x^T dH x = w * Mz^2 for random stance forces, Mz about the points' midpoint.
    rng = np.random.default_rng(1)
    x = np.zeros(problem.n)
    x[sl] = rng.normal(0.0, 50.0, sl.stop - sl.start)
    pts = [kin.frame_position(f) for f in cassie.force_frame_ids[stance]]
    mid = 0.5 * (pts[0] + pts[1])
    f = x[sl].reshape(2, 3)
    Mz = sum(np.cross(p - mid, fi)[2] for p, fi in zip(pts, f))
    assert x @ dH @ x == pytest.approx(w * Mz**2, rel=1e-9)
    # The same term on a problem whose H is not C-contiguous (a user's copy).
    other = problem.copy()
    other.H = np.asfortranarray(H0)
    builder.add_stance_yaw_moment_cost(other, kin, target)
    assert np.allclose(other.H, problem.H, rtol=0, atol=1e-12)


def test_tracker_applies_both_terms(cassie):
    kin = _kin(cassie)
    tracker = QPTracker(cassie, CASSIE_CONFIG)
    res = tracker.compute(kin, _target(kin, "left"))
    assert res.ok
    i = list(cassie.actuated.joint_names).index("left-foot")
    assert abs(res.tau_Nm[i]) <= CASSIE_CONFIG.stance_foot_torque_max_Nm + 1e-6
