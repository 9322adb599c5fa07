"""amlip_qp.qp.equality_elimination: the reduced QP has the full QP's optimum; its basis spans the
equalities' null space; dependent or over-determined equalities are refused."""

import numpy as np
import pytest

from amlip_qp.exceptions import QPError
from amlip_qp.qp.daqp_solver import DAQPSolver
from amlip_qp.qp.equality_elimination import eliminate_equalities
from amlip_qp.qp.problem import QPProblem


def _problem(seed: int, n: int = 14, n_eq: int = 5, n_in: int = 8, n_fixed: int = 3) -> QPProblem:
    """A strictly convex QP with equalities, two-sided and one-sided rows, a box, free rows
    (both bounds infinite) and fixed variables, feasible at a known point."""
    rng = np.random.default_rng(seed)
    M = rng.normal(size=(n, n))
    H = M @ M.T + 0.1 * np.eye(n)
    x_feasible = rng.normal(size=n)
    fixed = rng.choice(n, n_fixed, replace=False)
    lb, ub = x_feasible - rng.uniform(0.05, 0.5, n), x_feasible + rng.uniform(0.05, 0.5, n)
    lb[fixed] = ub[fixed] = x_feasible[fixed]
    lb[np.setdiff1d(np.arange(n), fixed)[0]] = -np.inf  # one free variable without a lower bound
    A = rng.normal(size=(n_eq, n))
    C = rng.normal(size=(n_in, n))
    Cx = C @ x_feasible
    l, u = Cx - rng.uniform(0.01, 0.3, n_in), Cx + rng.uniform(0.01, 0.3, n_in)
    l[1], u[2] = -np.inf, np.inf
    l[3], u[3] = -np.inf, np.inf  # a row with no bound
    return QPProblem(
        H=H, g=rng.normal(size=n) * 10, A=A, b=A @ x_feasible, C=C, l=l, u=u, lb=lb, ub=ub,
        eq_rows=[("first", slice(0, 2)), ("second", slice(2, n_eq))], in_rows=[("rows", slice(0, n_in))],
    )  # fmt: skip


@pytest.mark.parametrize("seed", range(6))
def test_the_reduced_problem_has_the_full_problems_optimum(seed):
    p = _problem(seed)
    x_full = DAQPSolver().solve(p).x
    e = eliminate_equalities(p)
    q = e.problem
    assert q.n == p.n - 3 - p.n_eq and q.n_eq == 0
    # the rows with a bound, then the free variables with a finite box bound (each free variable but one)
    assert q.n_in == (p.n_in - 1) + (p.n - 3)
    x = e.recover(DAQPSolver().solve(q).x)
    assert np.max(np.abs(x - x_full)) < 1e-8 * (1 + np.max(np.abs(x_full)))
    assert np.max(np.abs(p.A @ x - p.b)) < 1e-10
    assert max(p.residuals(x).values()) < 1e-8
    fixed = p.lb == p.ub
    assert np.array_equal(x[fixed], p.lb[fixed])


def test_the_basis_is_orthonormal_and_spans_the_equalities_null_space():
    p = _problem(7)
    e = eliminate_equalities(p)
    Z = e.basis
    assert np.allclose(Z.T @ Z, np.eye(Z.shape[1]), atol=1e-13)
    A_free = p.A[:, e.free]
    assert np.max(np.abs(A_free @ Z)) < 1e-12
    # every point of the affine set is reached: x0 plus the basis has full rank with A's rows
    assert np.linalg.matrix_rank(np.vstack([A_free, Z.T])) == e.free.size
    y = np.arange(Z.shape[1], dtype=float)
    assert np.max(np.abs(p.A @ e.recover(y) - p.b)) < 1e-10


def test_a_problem_without_equalities_keeps_its_variables():
    p = _problem(3, n_eq=0)
    e = eliminate_equalities(p)
    assert e.problem.n == p.n - 3
    x = e.recover(DAQPSolver().solve(e.problem).x)
    assert np.max(np.abs(x - DAQPSolver().solve(p).x)) < 1e-8 * (1 + np.max(np.abs(x)))


def test_dependent_equalities_are_refused_naming_their_block():
    p = _problem(4)
    p.A[4] = p.A[0] + 2 * p.A[1]
    p.b[4] = p.b[0] + 2 * p.b[1]
    with pytest.raises(QPError, match=r"equality rows are dependent \(row 4, block 'second'\)"):
        eliminate_equalities(p)


def test_equalities_that_leave_no_freedom_are_refused():
    p = _problem(5, n=6, n_eq=3, n_in=4, n_fixed=3)
    with pytest.raises(QPError, match="3 equality rows leave none of the 3 free variables"):
        eliminate_equalities(p)


def test_equalities_dependent_once_the_fixed_variables_are_out_are_refused():
    p = _problem(6, n=8, n_eq=3, n_in=4, n_fixed=3)
    # the free variables' columns span only 2 of the 3 rows' directions once the fixed ones are out
    # (the full rows stay independent; with this b they are also inconsistent)
    free = np.flatnonzero(p.lb != p.ub)
    p.A[2, free] = p.A[0, free] + p.A[1, free]
    p.b[2] += 1.0
    assert np.linalg.matrix_rank(p.A) == 3
    with pytest.raises(QPError, match=r"equality rows are dependent \(row 2, block 'second'\)"):
        eliminate_equalities(p)
