"""DAQPSolver: agreement with quadprog on random problems and on the tracker's own, the hot start,
determinism, failures, and the QP tracker walking with it."""

import numpy as np
import pytest

from amlip_qp.control.wbc.tracker import QPTracker
from amlip_qp.exceptions import InputError, QPError
from amlip_qp.experiments.bench_qp import record_walk
from amlip_qp.qp import DAQPSolver, ProxQPSolver, QPProblem
from amlip_qp.robots import load_robot
from amlip_qp.sim.reports.summary import summarize
from amlip_qp.sim.scenarios.factory import build_simulation
from amlip_qp.sim.scenarios.named import get_scenario
from test_qp_problem import allocated_problem, random_problem


@pytest.fixture(scope="module")
def walk_problems():
    """80 consecutive QPs of the QP tracker walking cassie-1mps (after 0.6 s of start-up)."""
    problems, _, fell = record_walk(n_ticks=80, scenario="cassie-1mps", t_skip_s=0.6)
    assert not fell
    return problems


def test_matches_quadprog_on_random_problems():
    solver = DAQPSolver()
    for seed in range(10):
        p = random_problem(seed)
        x = solver.solve(p).x
        assert np.max(np.abs(x - p.solve_with("quadprog"))) < 1e-8
        assert max(p.residuals(x).values()) < 1e-9


def test_the_solution_check_measures_the_problems_own_residuals():
    """The check of every reported solution (on the stacked rows DAQP solved, an infinite bound held
    as 1e30) gives the problem's largest residual, for points inside and outside the constraints."""
    from amlip_qp.qp.daqp_solver import _Shape

    rng = np.random.default_rng(5)
    for seed in range(6):
        p = random_problem(seed)
        p.u[0], p.lb[1] = np.inf, -np.inf  # an infinite bound of each kind
        shape = _Shape(p)
        shape.fill(p)
        for scale in (0.0, 0.1, 10.0):
            x = p.solve_with("quadprog") + scale * rng.normal(size=p.n)
            expected = max(max(p.residuals(x).values()), 0.0)
            assert shape.violation(x) == pytest.approx(expected, rel=1e-12, abs=1e-12)
            assert (shape.violation(x) > 1e-4) == (expected > 1e-4)


def test_finds_the_trackers_optimum_exactly(walk_problems):
    """quadprog's solution (both are exact active-set methods) to 1e-7 in x (N, m/s^2), constraints held
    to 1e-6; and never a higher cost than ProxQP even at 1e-10 (on these problems ProxQP's is up to
    2e-6 relative above it)."""
    daqp, prox = DAQPSolver(), ProxQPSolver(eps_abs=1e-10, max_iter=10_000, eps_primal_inf=1e-12)
    for p in walk_problems:
        x = daqp.solve(p).x
        assert np.max(np.abs(x - p.solve_with("quadprog"))) < 1e-7
        assert max(p.residuals(x).values()) < 1e-6
        f, f_prox = p.objective(x), p.objective(prox.solve(p).x)
        assert f <= f_prox + 1e-9 * abs(f_prox)
    assert daqp.n_init == 1  # one set-up, every later problem hot-started


def test_hot_and_cold_starts_find_the_same_solutions(walk_problems):
    hot, cold = DAQPSolver(), DAQPSolver(warm_start=False)
    for p in walk_problems:
        assert np.max(np.abs(hot.solve(p).x - cold.solve(p).x)) < 1e-7
    assert hot.n_init == 1 and cold.n_init == len(walk_problems)


def test_the_same_problems_in_the_same_order_give_bit_identical_solutions(walk_problems):
    a, b = DAQPSolver(), DAQPSolver()
    for p in walk_problems:
        assert np.array_equal(a.solve(p).x, b.solve(p).x)


def test_a_failure_raises_with_the_problem_and_the_next_solve_starts_afresh():
    ok, bad = random_problem(4), random_problem(4)
    bad.A = np.vstack([np.eye(bad.n)[0], np.eye(bad.n)[0]])  # x0 = 0.5 and x0 = -0.5 at once
    bad.b = np.array([0.5, -0.5])
    solver = DAQPSolver()
    solver.solve(ok)
    with pytest.raises(QPError) as info:
        solver.solve(bad)
    assert info.value.problem is bad and info.value.status.startswith("DAQP_EXIT_")
    solver.solve(ok)
    assert solver.n_init == 2  # set up again after the failure


def test_the_tracker_refuses_an_unknown_solver():
    with pytest.raises(InputError, match="qp_solver must be one of proxqp, daqp"):
        QPTracker(load_robot("cassie"), qp_solver="gurobi")


def test_the_profile_chooses_the_solver_and_the_argument_overrides_it():
    """Each bundled profile names its solver (``[trackers.qp] qp_solver``); an explicit name overrides it."""
    for name in ("cassie", "g1"):
        assert isinstance(QPTracker(load_robot(name)).solver, DAQPSolver), name
    for name in ("rabbit", "h1"):  # DAQP falls under pushes ProxQP survives on these two
        assert isinstance(QPTracker(load_robot(name)).solver, ProxQPSolver), name
    forced = QPTracker(load_robot("cassie"), qp_solver="proxqp")
    assert forced.qp_solver == "proxqp" and isinstance(forced.solver, ProxQPSolver)
    chosen = QPTracker(load_robot("h1"), qp_solver="daqp")
    assert chosen.qp_solver == "daqp" and isinstance(chosen.solver, DAQPSolver)


def test_the_qp_tracker_walks_with_daqp_at_the_commanded_speed():
    sc = get_scenario("cassie-1mps").with_(duration_s=6.0)
    tracker = QPTracker(load_robot("cassie"), qp_solver="daqp")
    assert isinstance(tracker.solver, DAQPSolver)
    s = summarize(build_simulation(sc, tracker).run(sc.duration_s, log="summary"))
    assert not s["fell"] and s["fallback_ticks"] == 0
    assert s["mean_velocity"][0] == pytest.approx(s["commanded_velocity"][0], abs=0.1)


def test_a_hot_start_on_a_contradictory_row_is_refused_not_reported_solved():
    """0 = 1 in an equality row after a good problem of the same shape: a QPError, never that x."""
    ok, bad = random_problem(4), random_problem(4)
    bad.A[0] = 0.0
    bad.b[0] = 1.0
    solver = DAQPSolver()
    solver.solve(ok)
    with pytest.raises(QPError):
        solver.solve(bad)


def _allocated_copy(p):
    """``p`` in an allocated problem (its rows and bounds stacked: DAQP reads them in place)."""
    a = QPProblem.allocate(p.n, p.n_eq, p.n_in)
    for name in ("H", "g", "A", "b", "C", "l", "u", "lb", "ub"):
        getattr(a, name)[...] = getattr(p, name)
    assert a.stacked() is not None
    return a


def test_an_allocated_problem_read_in_place_gives_the_bits_of_the_same_problem_apart(walk_problems):
    """The tracker's problems are allocated (rows and bounds stacked): the solutions, hot-started in
    order, are bit for bit those of the same problems held in separate arrays."""
    apart, in_place = DAQPSolver(), DAQPSolver()
    for p in walk_problems:
        assert p.stacked() is None  # recorded copies
        np.testing.assert_array_equal(in_place.solve(_allocated_copy(p)).x, apart.solve(p).x)


def test_the_stacked_path_checks_solutions_and_refuses_a_contradictory_row():
    """An allocated problem: the solution check gives the problem's residual (an infinite bound of each
    kind), and a hot start on 0 = 1 is refused."""
    from amlip_qp.qp.daqp_solver import _Shape

    p = allocated_problem(6, 2, 3)
    p.u[0], p.lb[1] = np.inf, -np.inf
    shape = _Shape(p)
    shape.fill(p)
    x0 = p.solve_with("quadprog")
    for x in (x0, x0 + 0.5):
        assert shape.violation(x) == pytest.approx(max(max(p.residuals(x).values()), 0.0), rel=1e-12, abs=1e-12)
    solver = DAQPSolver()
    solver.solve(p)
    p.A[0] = 0.0
    p.b[0] = 1.0
    with pytest.raises(QPError):
        solver.solve(p)


def test_the_one_pass_check_bounds_the_violation_and_flags_non_finite_points():
    """The solve's one-pass check (the largest gap of both bound sides) is the violation where that is
    positive, and NaN or above any tolerance at a point with a NaN or an infinite entry, so a solution it
    passes is finite and within the tolerance."""
    from amlip_qp.qp.daqp_solver import RESIDUAL_CHECK, _Shape

    p = allocated_problem(6, 2, 3)
    p.u[0], p.lb[1] = np.inf, -np.inf
    shape = _Shape(p)
    shape.fill(p)
    x0 = p.solve_with("quadprog")
    for x in (x0, x0 + 0.5, x0 - 3.0):
        assert max(shape.largest_gap(x), 0.0) == shape.violation(x)
    for bad in (np.nan, np.inf, -np.inf):
        for i in range(p.n):
            x = x0.copy()
            x[i] = bad
            assert not shape.largest_gap(x) <= RESIDUAL_CHECK


def test_a_replaced_array_of_the_same_problem_is_solved_with_its_new_values():
    """The solver keeps the shape of the allocated problem it solved last; a problem whose array was
    replaced (no longer stacked) is read apart, with the same solution as a fresh solver's."""
    p = _allocated_copy(random_problem(3))
    solver = DAQPSolver()
    x_first = solver.solve(p).x
    np.testing.assert_array_equal(solver.solve(p).x, x_first)
    p.g = p.g + 1.0  # a replaced array: the problem is no longer read in place
    assert p.stacked() is None
    np.testing.assert_allclose(solver.solve(p).x, DAQPSolver().solve(p).x, atol=1e-9)
    assert max(p.residuals(solver.solve(p).x).values()) < 1e-9


def test_a_fast_step_without_bind_rows_is_refused_at_construction():
    with pytest.raises(InputError, match="fast_step must have a bind_rows"):
        DAQPSolver(fast_step=object())
