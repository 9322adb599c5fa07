"""ProxQPSolver: persistence, warm start, agreement with another backend, failures."""

import numpy as np
import pytest

from amlip_qp.exceptions import QPError
from amlip_qp.qp import ProxQPSolver
from amlip_qp.qp.solver import MAX_SHAPES
from test_qp_problem import random_problem


def test_matches_quadprog_on_random_problems():
    solver = ProxQPSolver(eps_abs=1e-9)
    for seed in range(10):
        p = random_problem(seed)
        x = solver.solve(p).x
        x_ref = p.solve_with("quadprog")
        assert np.max(np.abs(x - x_ref)) < 1e-6
        assert max(p.residuals(x).values()) < 1e-7


def test_one_init_for_a_sequence_of_same_size_problems():
    solver = ProxQPSolver()
    base = random_problem(0)
    for k in range(20):
        p = base.copy()
        p.g = base.g + 0.01 * k
        solver.solve(p)
    assert solver.n_init == 1


def test_one_persistent_qp_per_problem_shape():
    """Two shapes in turn (the tracker's airborne and loaded swing foot): one init each, then warm updates."""
    solver = ProxQPSolver(eps_abs=1e-9)
    big = random_problem(3, n=10, n_eq=2, n_in=5)
    small = random_problem(4, n=7, n_eq=2, n_in=3)
    for k in range(6):
        for p in (big, small):
            q = p.copy()
            q.g = p.g + 0.01 * k
            x = solver.solve(q).x
            assert np.max(np.abs(x - q.solve_with("quadprog"))) < 1e-6
    assert solver.n_init == 2
    solver.reset()
    solver.solve(small)
    assert solver.n_init == 3


def test_at_most_max_shapes_are_kept_the_oldest_dropped_first():
    solver = ProxQPSolver()
    sizes = [(6 + k, 2, 3) for k in range(MAX_SHAPES + 1)]
    for n, n_eq, n_in in sizes:
        solver.solve(random_problem(n, n=n, n_eq=n_eq, n_in=n_in))
    assert solver.n_init == MAX_SHAPES + 1
    for n, n_eq, n_in in sizes[1:]:  # still kept: warm updates, no init
        solver.solve(random_problem(n, n=n, n_eq=n_eq, n_in=n_in))
    assert solver.n_init == MAX_SHAPES + 1
    n, n_eq, n_in = sizes[0]  # dropped: initialised again
    solver.solve(random_problem(n, n=n, n_eq=n_eq, n_in=n_in))
    assert solver.n_init == MAX_SHAPES + 2


def test_warm_start_needs_fewer_iterations_on_a_slowly_varying_sequence():
    def run(warm: bool) -> int:
        solver = ProxQPSolver(warm_start=warm, eps_abs=1e-8)
        base = random_problem(7, n=30, n_eq=5, n_in=20)
        total = 0
        for k in range(30):
            p = base.copy()
            p.g = base.g + 1e-3 * np.sin(0.1 * k)
            total += solver.solve(p).iterations
        return total

    warm, cold = run(True), run(False)
    assert warm < cold


def test_infeasible_problem_raises_with_the_problem_attached():
    p = random_problem(3)
    # x0 = 1 and x0 = -1 at once
    p.A = np.vstack([np.eye(p.n)[0], np.eye(p.n)[0]])
    p.b = np.array([0.5, -0.5])
    solver = ProxQPSolver(max_iter=100)
    with pytest.raises(QPError) as info:
        solver.solve(p)
    assert info.value.problem is p
    assert info.value.status != "PROXQP_SOLVED"


def test_a_failed_solve_reinitialises_only_its_own_shape():
    """After a failure that shape starts cold again; the other shape keeps its warm ProxQP."""
    solver = ProxQPSolver(max_iter=100)
    ok = random_problem(4, n=7, n_eq=2, n_in=3)
    bad = random_problem(3)
    bad.A = np.vstack([np.eye(bad.n)[0], np.eye(bad.n)[0]])  # x0 = 0.5 and x0 = -0.5 at once
    bad.b = np.array([0.5, -0.5])
    solver.solve(ok)
    with pytest.raises(QPError):
        solver.solve(bad)
    assert solver.n_init == 2
    solver.solve(ok)  # still warm
    assert solver.n_init == 2
    with pytest.raises(QPError):
        solver.solve(bad)  # cold again, not from the failed iterate
    assert solver.n_init == 3
