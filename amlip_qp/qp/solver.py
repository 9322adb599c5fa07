"""One persistent ProxQP solver, updated every tick and warm-started.

TSID re-initialises ProxQP at every control tick; here one
``proxsuite.proxqp.dense.QP`` lives as long as the tracker and is
``update``-d with the new matrices, starting from the previous solution.
That works because the tracker's problems keep fixed dimensions. The solver
keeps one ``QP`` per problem shape (at most :data:`MAX_SHAPES`, the oldest
dropped first): the tracker with ``airborne_reduction`` solves two shapes (all
variables, and without the swing foot's force variables while they are pinned
to zero), each warm-started from its own previous solution.

Determinism: ProxSuite is imported through :mod:`amlip_qp.qp._proxsuite`,
which loads its portable build (the vectorised builds are not bit-reproducible).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from amlip_qp.exceptions import QPError
from amlip_qp.qp._proxsuite import proxqp
from amlip_qp.qp.problem import QPProblem

_OK = (proxqp.QPSolverOutput.PROXQP_SOLVED,)

#: Problem shapes a :class:`ProxQPSolver` keeps a warm-started ProxQP for.
MAX_SHAPES = 4


@dataclass
class QPSolution:
    """A solved QP.

    Attributes:
        x: The primal solution.
        status: Solver status name, e.g. ``"PROXQP_SOLVED"``.
        iterations: Solver iterations.
        solve_time_us: Wall time of the ``update`` + ``solve`` calls, µs.
    """

    x: np.ndarray
    status: str
    iterations: int
    solve_time_us: float


class ProxQPSolver:
    """A persistent dense ProxQP solver with warm start.

    Args:
        eps_abs: Absolute primal/dual tolerance.
        max_iter: Iteration cap per solve.
        warm_start: Start each solve from the previous solution (default). With
            ``False`` the solver is re-initialised at every call, as TSID does;
            that mode exists for benchmarks and comparisons.
        eps_primal_inf: ProxQP's primal infeasibility threshold (its default
            1e-4). Problems with forces of hundreds of newtons can trip it
            falsely; the whole-body tracker uses 1e-9.
        mu_eq: Initial proximal parameter of the equality constraints given
            to every ``init``/``update`` (``None``: ProxQP's default, 1e-3).
        mu_in: The same for the inequalities (``None``: ProxQP's default, 1e-1).
        update_preconditioner: Recompute ProxQP's Ruiz equilibration at every
            warm ``update`` (``False`` keeps the one of the first ``init``).

    On 1200 consecutive Cassie tracker QPs (32 variables, 15 equalities, 26
    inequalities, box bounds; ``eps_abs=1e-5``), ``mu_eq=1e-4, mu_in=1e-3``
    and no preconditioner update took 3.6 iterations on average with no
    failure, against 4.1 iterations and 47 spurious infeasibility reports
    with ProxQP's defaults (the tracker's ``eps_abs=1e-3`` takes 2.05). To
    measure on your machine, replay the problems of
    :func:`amlip_qp.experiments.bench_qp.record_walk` (or run ``amlip-qp bench qp``).
    """

    def __init__(
        self,
        eps_abs: float = 1e-6,
        max_iter: int = 200,
        warm_start: bool = True,
        eps_primal_inf: float = 1e-4,
        mu_eq: float | None = None,
        mu_in: float | None = None,
        update_preconditioner: bool = True,
    ):
        self.eps_abs = eps_abs
        self.max_iter = max_iter
        self.warm_start = warm_start
        self.eps_primal_inf = eps_primal_inf
        self._mu: dict[str, float] = {}
        if mu_eq is not None:
            self._mu["mu_eq"] = float(mu_eq)
        if mu_in is not None:
            self._mu["mu_in"] = float(mu_in)
        self.update_preconditioner = bool(update_preconditioner)
        #: One ProxQP per problem shape ``(n, n_eq, n_in)``, each warm-started from its own last solution.
        self._qps: dict[tuple[int, int, int], proxqp.dense.QP] = {}
        #: Number of (re-)initialisations so far (1 per problem shape in steady warm-started use).
        self.n_init = 0

    @property
    def options(self) -> dict:
        """The constructor arguments of this solver (to build another one alike)."""
        return {
            "eps_abs": self.eps_abs,
            "max_iter": self.max_iter,
            "warm_start": self.warm_start,
            "eps_primal_inf": self.eps_primal_inf,
            "mu_eq": self._mu.get("mu_eq"),
            "mu_in": self._mu.get("mu_in"),
            "update_preconditioner": self.update_preconditioner,
        }

    @property
    def primal_tol(self) -> float:
        """Largest constraint violation a solution may have: the absolute tolerance ``eps_abs``."""
        return float(self.eps_abs)

    def _new_qp(self, problem: QPProblem) -> proxqp.dense.QP:
        qp = proxqp.dense.QP(problem.n, problem.n_eq, problem.n_in, True)
        qp.settings.eps_abs = self.eps_abs
        qp.settings.eps_rel = 0.0
        qp.settings.max_iter = self.max_iter
        qp.settings.eps_primal_inf = self.eps_primal_inf
        qp.settings.verbose = False
        qp.settings.initial_guess = (
            proxqp.InitialGuess.WARM_START_WITH_PREVIOUS_RESULT
            if self.warm_start
            else proxqp.InitialGuess.EQUALITY_CONSTRAINED_INITIAL_GUESS
        )
        return qp

    def reset(self) -> None:
        """Forget the previous solutions; the next solve of each shape re-initialises."""
        self._qps.clear()

    def solve(self, problem: QPProblem, check: bool = False) -> QPSolution:
        """Solve ``problem``; raise :class:`QPError` (carrying it) on failure. ``check``: first
        validate ``problem`` (:meth:`QPProblem.validate <amlip_qp.qp.problem.QPProblem.validate>`:
        an invalid one raises its :class:`~amlip_qp.exceptions.InvalidQPError`)."""
        if check:
            problem.validate()
        H, A, C = problem.H, problem.A, problem.C
        dims = (H.shape[0], A.shape[0], C.shape[0])
        t0 = time.perf_counter_ns()
        args = (H, problem.g, A, problem.b, C, problem.l, problem.u, problem.lb, problem.ub)
        qp = self._qps.get(dims)
        if qp is None or not self.warm_start:
            if dims not in self._qps and len(self._qps) >= MAX_SHAPES:
                del self._qps[next(iter(self._qps))]  # the oldest shape
            qp = self._qps[dims] = self._new_qp(problem)
            qp.init(*args, **self._mu)
            self.n_init += 1
        else:
            qp.update(*args, update_preconditioner=self.update_preconditioner, **self._mu)
        qp.solve()
        elapsed_us = (time.perf_counter_ns() - t0) * 1e-3
        results = qp.results
        info = results.info
        status = info.status
        x = results.x
        # A sum of finite numbers is finite (NaN and inf propagate); a sum of
        # Python floats is cheaper than a numpy reduction at this size.
        if status not in _OK or not math.isfinite(sum(x.tolist())):
            name = getattr(status, "name", str(status))
            # Do not warm-start the next solve of this shape from a failed iterate (other shapes stay warm).
            del self._qps[dims]
            raise QPError(
                f"ProxQP failed with status {name} after {info.iter} iterations", problem=problem, status=name
            )
        return QPSolution(x=np.array(x), status=status.name, iterations=int(info.iter), solve_time_us=elapsed_us)
