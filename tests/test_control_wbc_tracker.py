"""The QP tracker: persistent warm-started ProxQP, cross-check with quadprog, fallbacks."""

import numpy as np
import pytest

from amlip_qp.control.tracker import TrackingTarget
from amlip_qp.control.walking.controller import WalkingController
from amlip_qp.control.wbc.tracker import QPTracker
from amlip_qp.exceptions import InputError
from amlip_qp.qp.solver import ProxQPSolver
from amlip_qp.robots import load_robot
from amlip_qp.robots.kinematics import RobotKinematics
from amlip_qp.sim.loop.harness import Simulation
from amlip_qp.sim.scenarios.named import SCENARIOS
from robot_states import tuned_config

CASSIE_CONFIG = tuned_config("cassie", "qp")


@pytest.fixture(
    scope="module", params=[("cassie", False), ("rabbit", False), ("cassie", True), ("rabbit", True)], ids=str
)
def walk(request):
    """A short recorded walk (the full problem solved every tick, or its leading
    block while the swing foot is airborne): (robot, tracker, run result)."""
    name, airborne_reduction = request.param
    robot = load_robot(name)
    tracker = QPTracker(robot, record=True, airborne_reduction=airborne_reduction)
    assert tracker.airborne_reduction == airborne_reduction
    ctrl = WalkingController(robot, tracker)
    scenario = SCENARIOS["cassie-1mps" if name == "cassie" else "rabbit-0.5mps"]
    result = Simulation(robot, ctrl, scenario.command).run(0.4)
    return robot, tracker, result


def test_one_persistent_solver_warm_started(walk):
    _, tracker, result = walk
    assert not result.fell
    assert len(tracker.recorded) == len(result.log["t"])
    # One initialisation per problem shape (with airborne_reduction: the swing foot's
    # forces loaded, and airborne, solved without them), plus one per cold retry.
    airborne = [p.lb[p.variables["forces_swing"]] for p, _ in tracker.recorded]
    assert any(np.all(b == 0.0) for b in airborne) and not all(np.all(b == 0.0) for b in airborne)
    shapes = 2 if tracker.airborne_reduction else 1
    assert tracker.solver.n_init == shapes + tracker.cold_retries
    assert tracker.cold_retries <= 0.02 * len(tracker.recorded)
    assert tracker.fallbacks == 0
    assert np.all(np.isfinite(result.log["tau"]))


def test_agrees_with_quadprog_on_recorded_problems(walk):
    robot, tracker, _ = walk
    checked = 0
    for problem, x in tracker.recorded[::25]:
        assert np.all(np.isfinite(x))
        x_ref = problem.solve_with("quadprog")
        assert max(problem.residuals(x_ref).values()) < 1e-6
        # Same optimum: objective and the physically meaningful parts (vdot, forces).
        obj, obj_ref = problem.objective(x), problem.objective(x_ref)
        assert abs(obj - obj_ref) <= 1e-3 * max(1.0, abs(obj_ref))
        nv = robot.nv
        assert np.max(np.abs(x[:nv] - x_ref[:nv])) < 0.05 * max(1.0, np.max(np.abs(x_ref[:nv])))
        checked += 1
    assert checked >= 8


def test_recorded_solutions_satisfy_the_constraints(walk):
    _, tracker, _ = walk
    for problem, x in tracker.recorded[::10]:
        res = problem.residuals(x)
        tol = tracker.solver.primal_tol  # the solver's absolute primal tolerance
        assert res["eq"] <= tol and res["in"] <= tol and res["box"] <= tol


def test_swing_forces_are_zero_while_the_foot_is_in_the_air(walk):
    _, tracker, result = walk
    phase = result.log["phase"]
    tol = tracker.solver.primal_tol  # the bound holds to the solver's tolerance, N
    seen = 0
    for k, (problem, x) in enumerate(tracker.recorded):
        if 0.2 < phase[k] < 0.8:
            assert np.max(np.abs(x[problem.variables["forces_swing"]])) <= tol
            seen += 1
    assert seen > 50


def _stand(robot):
    kin = RobotKinematics(robot)
    kin.update(robot.q_stand, np.zeros(robot.nv))
    y, _, _ = kin.outputs("left", 0.0)
    n = y.size
    return kin, TrackingTarget("left", 0.5, 0.0, y, np.zeros(n), np.zeros(n), swing_contact_weight=1.0)


@pytest.mark.parametrize("name", ["cassie", "rabbit"])
def test_nan_reference_falls_back_to_finite_damped_torques(name):
    robot = load_robot(name)
    tracker = QPTracker(robot)
    kin, target = _stand(robot)
    good = tracker.compute(kin, target)
    assert good.ok and np.all(np.isfinite(good.tau_Nm))
    target.h_d = target.h_d.copy()
    target.h_d[0] = np.nan
    bad = tracker.compute(kin, target)
    assert not bad.ok and "NaN" in bad.fallback
    assert np.all(np.isfinite(bad.tau_Nm))
    assert np.allclose(bad.tau_Nm, tracker.fallback_decay * good.tau_Nm)
    assert tracker.fallbacks == 1 and bad.info["fallbacks"] == 1
    again = tracker.compute(kin, target)
    assert np.allclose(again.tau_Nm, tracker.fallback_decay**2 * good.tau_Nm)


def test_infeasible_problem_falls_back_and_recovers():
    robot = load_robot("cassie")
    tracker = QPTracker(robot)
    kin, target = _stand(robot)
    good = tracker.compute(kin, target)
    build = tracker.build_problem

    def contradictory(kin, target):
        problem = build(kin, target)
        problem.A[0] = 0.0
        problem.b[0] = 1.0  # 0 = 1: infeasible whatever the bounds
        return problem

    tracker.build_problem = contradictory
    bad = tracker.compute(kin, target)
    assert not bad.ok and bad.fallback.startswith("solver")
    assert np.all(np.isfinite(bad.tau_Nm))
    assert np.allclose(bad.tau_Nm, tracker.fallback_decay * good.tau_Nm)
    tracker.build_problem = build
    recovered = tracker.compute(kin, target)
    assert recovered.ok and np.allclose(recovered.tau_Nm, good.tau_Nm, atol=1e-2)


def test_nan_state_through_the_controller_never_gives_nan_torques():
    robot = load_robot("rabbit")
    kin = RobotKinematics(robot)
    tracker = QPTracker(robot)
    kin.update(robot.q_stand, np.zeros(robot.nv))
    kin.v = kin.v.copy()
    kin.v[0] = np.nan  # a corrupted state reaching the tracker
    y, _, _ = kin.outputs("left", 0.0)
    n = y.size
    res = tracker.compute(kin, TrackingTarget("left", 0.5, 0.0, y, np.zeros(n), np.zeros(n)))
    assert not res.ok and res.fallback
    assert np.all(np.isfinite(res.tau_Nm))


def test_bench_reports_every_solver_on_recorded_problems(walk):
    from amlip_qp.experiments import qp_solver_list
    from amlip_qp.experiments.bench_qp import bench_solvers, format_report

    _, tracker, _ = walk
    problems = [p for p, _ in tracker.recorded[::20]]
    out = bench_solvers(problems, qp_solver_list.select("proxsuite-init,quadprog"))
    stats = out["solvers"]
    assert {"proxsuite-warm", "proxsuite-init", "quadprog"} == set(stats)
    assert stats["proxsuite-warm"]["ratio_to_warm"] == pytest.approx(1.0)
    for s in stats.values():
        assert s["n"] == len(problems) and s["median_us"] > 0 and s["p99_us"] >= s["median_us"]
    assert stats["proxsuite-warm"]["failures"] == 0 and stats["quadprog"]["failures"] == 0
    text = format_report({**out, "scenario": "x", "n_problems": len(problems), "tick_us": {"median": 1.0, "p99": 2.0}})
    assert "proxsuite-warm" in text and "controller tick" in text


def test_replaying_the_recorded_problems_is_bit_identical(walk):
    """Determinism, with the tracker's solver and with ProxQP: amlip_qp loads ProxSuite's portable
    build (the AVX-512 and AVX2 builds gave different solutions for the same problems from one fresh
    solver to the next, up to 3e-6)."""
    from amlip_qp.qp import _proxsuite

    _, tracker, _ = walk
    assert _proxsuite.REPRODUCIBLE, f"ProxSuite build {_proxsuite.PROXSUITE_BUILD} is not reproducible"
    problems = [p for p, x in tracker.recorded]
    proxqp = QPTracker(tracker.robot, qp_solver="proxqp").solver
    for make in (lambda: type(tracker.solver)(**tracker.solver.options), lambda: ProxQPSolver(**proxqp.options)):
        runs = []
        for _ in range(3):
            solver = make()
            runs.append(np.array([solver.solve(p).x for p in problems]))
        assert np.array_equal(runs[0], runs[1]) and np.array_equal(runs[0], runs[2])


def test_bad_arguments_and_targets_are_typed_errors():
    cassie, rabbit = load_robot("cassie"), load_robot("rabbit")
    with pytest.raises(InputError, match="gains for 9 outputs but rabbit has 4"):
        QPTracker(rabbit, CASSIE_CONFIG)
    for kwargs in (
        {"fallback_decay": -5.0},
        {"fallback_damping_Nms": -1.0},
        {"eps_abs": -1.0},
        {"max_iter": 0},
        {"airborne_reduction": "yes"},
    ):
        with pytest.raises(InputError):
            QPTracker(cassie, **kwargs)
    tracker = QPTracker(cassie)
    kin, target = _stand(cassie)
    target.stance = "up"
    with pytest.raises(InputError, match="stance"):
        tracker.compute(kin, target)
    kin, target = _stand(cassie)
    target.h_d = target.h_d[:5]
    with pytest.raises(InputError, match="h_d"):
        tracker.compute(kin, target)


def test_an_infeasible_fresh_solve_is_not_repeated():
    """Re-initialising solver: a failed solve is already cold, so no cold retry."""
    robot = load_robot("cassie")
    tracker = QPTracker(robot, warm_start=False)
    kin, target = _stand(robot)
    build = tracker.build_problem

    def contradictory(kin, target):
        problem = build(kin, target)
        problem.A[0] = 0.0
        problem.b[0] = 1.0
        return problem

    tracker.build_problem = contradictory
    before = tracker.solver.n_init
    bad = tracker.compute(kin, target)
    assert not bad.ok
    assert tracker.cold_retries == 0
    assert tracker.solver.n_init - before == 2  # the solve, then the relaxed solve; no repeat


@pytest.mark.parametrize("name", ["cassie", "rabbit"])
def test_an_invalid_problem_falls_back_without_a_retry_and_the_solver_stays_warm(name):
    """A NaN the assembly writes into the cost (after the first tick, so that a hot-started DAQP
    checks the problem inside its compiled call) is an invalid problem: the fallback names the
    field, without a cold retry or a relaxed solve, and the next tick is solved by the same warm
    solver with the torques of a tracker that never saw the NaN."""
    robot = load_robot(name)
    tracker, twin = QPTracker(robot), QPTracker(robot)
    kin, target = _stand(robot)
    first = tracker.compute(kin, target)
    assert first.ok and np.array_equal(twin.compute(kin, target).tau_Nm, first.tau_Nm)
    build = tracker.build_problem

    def poisoned(kin, target):
        problem = build(kin, target)
        problem.H[1, 1] = np.nan
        return problem

    tracker.build_problem = poisoned
    n_init = tracker.solver.n_init
    bad = tracker.compute(kin, target)
    assert not bad.ok and bad.fallback.startswith("invalid problem: QP field H contains NaN")
    assert np.allclose(bad.tau_Nm, tracker.fallback_decay * first.tau_Nm)
    assert (tracker.fallbacks, tracker.cold_retries, tracker.relaxed_solves) == (1, 0, 0)
    tracker.build_problem = build
    again = tracker.compute(kin, target)
    assert again.ok and tracker.solver.n_init == n_init
    assert np.array_equal(again.tau_Nm, twin.compute(kin, target).tau_Nm)
    if tracker.qp_solver == "daqp":
        assert tracker.solver.n_compiled == twin.solver.n_compiled + 1  # the check ran in the compiled call


def test_tracker_keeps_the_stance_toe_passive_and_reports_the_force_ramp():
    cassie = load_robot("cassie")
    tracker = QPTracker(cassie, CASSIE_CONFIG)
    kin, target = _stand(cassie)
    target.phase = 0.25 * CASSIE_CONFIG.liftoff_phase
    res = tracker.compute(kin, target)
    assert res.ok
    i = list(cassie.actuated.joint_names).index("left-foot")
    assert abs(res.tau_Nm[i]) <= CASSIE_CONFIG.stance_foot_torque_max_Nm + 1e-3  # the solver's tolerance, N m
    assert res.info["swing_force_weight"] == pytest.approx(0.75)


@pytest.mark.parametrize("name", ["h1", "g1"])
def test_a_four_point_robot_at_stand_gives_finite_torques_within_limits(name, tmp_path):
    """The humanoids with four-point soles (tests/sole_cases.py), the default (in-place compiled)
    build: at the stand pose in single support the torques are finite, within the motor limits, the
    passive stance ankle within its band, and the stance corners carry the weight."""
    from sole_cases import sole_profile

    robot = load_robot(sole_profile(name, tmp_path))
    tracker = QPTracker(robot, eps_abs=1e-9, warm_start=False)
    kin, target = _stand(robot)
    res = tracker.compute(kin, target)
    assert res.ok and tracker.fallbacks == 0 and np.all(np.isfinite(res.tau_Nm))
    lim = robot.actuated.torque_limit_Nm
    assert np.all(res.tau_Nm >= lim[:, 0] - 1e-6) and np.all(res.tau_Nm <= lim[:, 1] + 1e-6)
    names = list(robot.actuated.joint_names)
    band = tracker.config.stance_foot_torque_max_Nm
    for joint in robot.passive_in_stance("left"):
        assert abs(res.tau_Nm[names.index(joint)]) <= band + 1e-6
    stance = tracker.builder.forces(tracker.last_solution)["stance"]
    assert np.all(stance[:, 2] >= tracker.config.min_normal_force_N - 1e-6)
    assert res.info["stance_fz_N"] == pytest.approx(robot.mass_kg * 9.81, rel=0.15)
    # mid-swing the airborne swing foot's 12 forces and 16 pyramid rows may be left out: the same optimum
    assert res.info["swing_force_weight"] == 0.0
    reduced = QPTracker(robot, eps_abs=1e-9, warm_start=False, airborne_reduction=True)
    assert reduced.airborne_reduction
    np.testing.assert_allclose(reduced.compute(kin, target).tau_Nm, res.tau_Nm, atol=1e-5)


def test_the_airborne_problem_in_place_gets_the_relaxed_solve_and_the_full_solution():
    """Mid-swing with ``airborne_reduction``: the in-place assembly returns its airborne problem,
    the solution comes back at the full problem's size with the swing forces zero, and a tick
    whose torque rows cannot be met is solved again without them (a relaxed solve, still full size)."""
    robot = load_robot("cassie")
    tracker = QPTracker(robot, airborne_reduction=True, record=True)
    kin, target = _stand(robot)
    target.swing_contact_weight = 0.0  # the swing foot in the air
    good = tracker.compute(kin, target)
    assert good.ok and good.info["swing_force_weight"] == 0.0
    air = tracker.last_problem
    assert air is not None and air.n < tracker.builder.problem.n
    x = tracker.last_solution
    assert x is not None and x.shape == (tracker.builder.problem.n,)
    assert np.all(x[tracker.builder.problem.variables["forces_swing"]] == 0.0)
    # recorded as the full problem, which the full solution satisfies
    problem, x_rec = tracker.recorded[-1]
    assert problem.n == x_rec.size == x.size and max(problem.residuals(x_rec).values()) < 1e-6
    build = tracker.build_problem

    def torque_band_out_of_reach(kin, target):
        problem = build(kin, target)
        rows = dict(problem.in_rows)["torque"]
        problem.l[rows.start] = problem.u[rows.start] = 1e5  # a torque no joint can give
        return problem

    tracker.build_problem = torque_band_out_of_reach
    relaxed = tracker.compute(kin, target)
    assert relaxed.ok and tracker.relaxed_solves == 1 and tracker.fallbacks == 0
    x_relaxed = tracker.last_solution
    assert x_relaxed is not None and x_relaxed.shape == x.shape
    assert np.all(x_relaxed[tracker.builder.problem.variables["forces_swing"]] == 0.0)
    assert np.all(np.isfinite(relaxed.tau_Nm))
    # the same problem but for the torque rows: the same stance forces to within the dropped rows' effect
    st = tracker.builder.problem.variables["forces_stance"]
    assert abs(x_relaxed[st][2::3].sum() - x[st][2::3].sum()) < 0.05 * abs(x[st][2::3].sum())


def test_the_tracker_solves_the_airborne_problem_by_default():
    """By default, mid-swing, the tracker solves the problem without the airborne swing foot's
    variables; ``airborne_reduction=False`` solves the full problem."""
    robot = load_robot("cassie")
    kin, target = _stand(robot)
    target.swing_contact_weight = 0.0  # the swing foot in the air
    default = QPTracker(robot)
    full = QPTracker(robot, airborne_reduction=False)
    assert default.airborne_reduction and not full.airborne_reduction
    assert default.compute(kin, target).ok and full.compute(kin, target).ok
    assert default.last_problem is not None and full.last_problem is not None
    assert full.last_problem.n == full.builder.problem.n
    assert default.last_problem.n < default.builder.problem.n
