"""The solvers of ``amlip-qp bench qp`` that take sparse (CSC) matrices, and any other ``qpsolvers`` backend.

OSQP and QPALM solve ``min 1/2 x'Px + q'x  s.t.  l <= M x <= u`` with one
stacked matrix ``M = [A; C; I]``. Both keep a workspace whose sparsity pattern
is fixed at set-up, so :class:`StackedPattern` fixes one pattern for all the
recorded problems (the union of their nonzeros, as a tracker written for
these solvers would fix its layout's pattern); each problem then only brings
new values in that pattern. Clarabel's cones must not hold infinite bounds,
and which bounds are infinite (or fixed) changes from problem to problem, so
it is set up afresh for every problem (timed: that is its cost per tick).
The other ``qpsolvers`` backends go through ``qpsolvers.solve_problem``.

The dense solvers and the :class:`~amlip_qp.experiments.qp_runners.Runner` interface
are in :mod:`amlip_qp.experiments.qp_runners`.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from amlip_qp.experiments.qp_runners import Runner
from amlip_qp.qp.problem import QPProblem


def _csc_pattern(mask: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(rows, cols, indptr)`` of the nonzeros of ``mask`` in CSC order (column by column)."""
    cols, rows = np.nonzero(mask.T)
    indptr = np.concatenate([[0], np.cumsum(np.bincount(cols, minlength=mask.shape[1]))])
    return rows, cols, indptr


class StackedPattern:
    """One CSC pattern for the upper triangle of the cost matrix (which OSQP and QPALM read) and for
    ``[A; C; I]``: the union of the nonzeros of ``problems`` (all of one shape)."""

    def __init__(self, problems: list[QPProblem]):
        p0 = problems[0]
        self.n, self.m = p0.n, p0.n_eq + p0.n_in + p0.n
        cost = np.zeros((self.n, self.n), dtype=bool)
        rows = np.zeros((self.m, self.n), dtype=bool)
        for p in problems:
            cost |= p.H != 0
            rows |= self.stacked(p) != 0
        self.cost = _csc_pattern(np.triu(cost))
        self.rows = _csc_pattern(rows)

    def stacked(self, p: QPProblem) -> np.ndarray:
        """``[A; C; I]`` of ``p``, dense."""
        return np.vstack([p.A, p.C, np.eye(p.n)])

    def values(self, p: QPProblem) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """``(P values, q, M values, l, u)`` of ``p`` in this pattern."""
        (pr, pc, _), (mr, mc, _) = self.cost, self.rows
        l = np.concatenate([p.b, p.l, p.lb])
        u = np.concatenate([p.b, p.u, p.ub])
        return p.H[pr, pc], np.array(p.g), self.stacked(p)[mr, mc], l, u

    def matrices(self, P_values: np.ndarray, M_values: np.ndarray) -> tuple[Any, Any]:
        """The CSC matrices ``(P, M)`` of these values (explicit zeros kept in the pattern)."""
        import scipy.sparse as sp

        (pr, _, pp), (mr, _, mp) = self.cost, self.rows
        return (
            sp.csc_matrix((P_values, pr, pp), shape=(self.n, self.n)),
            sp.csc_matrix((M_values, mr, mp), shape=(self.m, self.n)),
        )


class OSQPRunner(Runner):
    """OSQP (ADMM) through one persistent ``osqp.OSQP``: set up on the first problem, then ``update``
    of every value + ``solve``, warm-started from the previous x, y (OSQP's ``warm_starting``). Given
    the tracker's absolute tolerance (relative 0) on OSQP's unscaled residuals."""

    name = "osqp"
    start = "warm: previous x, y"
    timed = "OSQP.update (all values) + solve"

    def __init__(self, eps_abs: float):
        super().__init__()
        import osqp

        self._osqp = osqp
        self.settings = {"eps_abs": eps_abs, "eps_rel": 0.0, "verbose": False, "warm_starting": True}
        self._pattern: StackedPattern | None = None
        self._solver: Any = None

    def setup(self, problems: list[QPProblem]) -> None:
        self._pattern = StackedPattern(problems)

    def prepare(self, p: QPProblem) -> tuple:
        assert self._pattern is not None, "setup() first"
        return self._pattern.values(p)

    def solve(self, data: tuple) -> np.ndarray | None:
        Px, q, Mx, l, u = data
        if self._solver is None:
            assert self._pattern is not None, "setup() first"
            self._solver = self._osqp.OSQP()
            P, M = self._pattern.matrices(Px, Mx)
            self._solver.setup(P, q, M, l, u, **self.settings)
        else:
            self._solver.update(q=q, l=l, u=u, Px=Px, Ax=Mx)
        result = self._solver.solve()
        if result.info.status_val != self._osqp.SolverStatus.OSQP_SOLVED:
            self.failures += 1
            return None
        return np.array(result.x)


class QPALMRunner(Runner):
    """QPALM (proximal augmented Lagrangian) through one persistent ``qpalm.Solver``: set up on the
    first problem, then ``update_Q_A``, ``update_q``, ``update_bounds``, ``warm_start`` from the
    previous x, y, and ``solve``. Given the tracker's absolute tolerance (relative 0)."""

    name = "qpalm"
    start = "warm: previous x, y"
    timed = "update_Q_A + update_q + update_bounds + warm_start + solve"

    def __init__(self, eps_abs: float):
        super().__init__()
        import qpalm

        self._qpalm = qpalm
        self.eps_abs = eps_abs
        self._pattern: StackedPattern | None = None
        self._solver: Any = None

    def setup(self, problems: list[QPProblem]) -> None:
        self._pattern = StackedPattern(problems)

    def prepare(self, p: QPProblem) -> tuple:
        assert self._pattern is not None, "setup() first"
        Qx, q, Mx, l, u = self._pattern.values(p)
        # QPALM reads +-1e20 as infinite bounds.
        return Qx, q, Mx, np.maximum(l, -1e20), np.minimum(u, 1e20)

    def solve(self, data: tuple) -> np.ndarray | None:
        Qx, q, Mx, l, u = data
        solver = self._solver
        if solver is None:
            assert self._pattern is not None, "setup() first"
            qp = self._qpalm.Data(self._pattern.n, self._pattern.m)
            qp.Q, qp.A = self._pattern.matrices(Qx, Mx)
            qp.q, qp.bmin, qp.bmax = q, l, u
            settings = self._qpalm.Settings()
            settings.verbose, settings.eps_abs, settings.eps_rel = 0, self.eps_abs, 0.0
            solver = self._solver = self._qpalm.Solver(qp, settings)
        else:
            solver.update_Q_A(Qx, Mx)
            solver.update_q(q)
            solver.update_bounds(l, u)
            solver.warm_start(solver.solution.x, solver.solution.y)
        solver.solve()
        if solver.info.status != "solved":
            self.failures += 1
            self._solver = None
            return None
        return np.array(solver.solution.x)


class ClarabelRunner(Runner):
    """Clarabel (interior point, conic): set up afresh for every problem (see the module doc), fixed
    variables in the zero cone with the equalities, infinite bounds dropped; its default tolerances."""

    name = "clarabel"
    start = "none: an interior-point method has no warm start; set up every problem"
    timed = "DefaultSolver(...) set-up + solve"

    def __init__(self) -> None:
        super().__init__()
        import clarabel

        self._clarabel = clarabel
        self._settings = clarabel.DefaultSettings()
        self._settings.verbose = False

    def prepare(self, p: QPProblem) -> tuple:
        import scipy.sparse as sp

        eye = np.eye(p.n)
        fixed = p.lb == p.ub
        fu, fl = np.isfinite(p.u), np.isfinite(p.l)
        bu, bl = np.isfinite(p.ub) & ~fixed, np.isfinite(p.lb) & ~fixed
        # Clarabel: A x + s = b, s in the cones (zero cone: equalities; nonnegative cone: A x <= b).
        A = np.vstack([p.A, eye[fixed], p.C[fu], -p.C[fl], eye[bu], -eye[bl]])
        b = np.concatenate([p.b, p.lb[fixed], p.u[fu], -p.l[fl], p.ub[bu], -p.lb[bl]])
        n_zero = p.n_eq + int(fixed.sum())
        cones = [self._clarabel.ZeroConeT(n_zero), self._clarabel.NonnegativeConeT(b.size - n_zero)]
        return sp.csc_matrix(np.triu(p.H)), np.array(p.g), sp.csc_matrix(A), b, cones

    def solve(self, data: tuple) -> np.ndarray | None:
        P, q, A, b, cones = data
        solution = self._clarabel.DefaultSolver(P, q, A, b, cones, self._settings).solve()
        if solution.status != self._clarabel.SolverStatus.Solved:
            self.failures += 1
            return None
        return np.array(solution.x)


class QPSolversRunner(Runner):
    """Any ``qpsolvers`` backend, no state kept: fixed variables substituted and the
    ``qpsolvers.Problem`` built in :meth:`prepare`; ``qpsolvers.solve_problem`` timed (it converts
    to the backend's own format, sets it up and solves); the backend's default settings.
    ``box_as_rows``: the finite box bounds as inequality rows and no box (for a backend that takes
    no infinite bound)."""

    start = "none: a new problem every call"
    timed = "qpsolvers.solve_problem (conversion to the backend's format + set-up + solve)"

    def __init__(self, backend: str, box_as_rows: bool = False):
        super().__init__()
        import qpsolvers

        self.name = self.backend = backend
        self.box_as_rows = box_as_rows
        self._solve_problem = qpsolvers.solve_problem

    def prepare(self, p: QPProblem) -> tuple:
        reduced, free, x_fixed = p.without_fixed_variables()
        problem = reduced.to_qpsolvers()
        if self.box_as_rows:
            eye = np.eye(reduced.n)
            up, low = np.isfinite(reduced.ub), np.isfinite(reduced.lb)
            G = [M for M in (problem.G, eye[up], -eye[low]) if M is not None]
            h = [v for v in (problem.h, reduced.ub[up], -reduced.lb[low]) if v is not None]
            problem.G, problem.h = np.vstack(G), np.concatenate(h)
            problem.lb = problem.ub = None
        return problem, free, x_fixed

    def solve(self, data: tuple) -> np.ndarray | None:
        problem, free, x_fixed = data
        try:
            solution = self._solve_problem(problem, solver=self.backend)
        except Exception:  # each backend raises its own types (licence, numerics, qpsolvers' errors)
            solution = None
        if solution is None or not solution.found or solution.x is None:
            self.failures += 1
            return None
        x = np.empty(free.size)
        x[free] = solution.x
        x[~free] = x_fixed
        return x
