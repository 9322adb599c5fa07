"""The solvers of ``amlip-qp bench qp`` that take dense matrices, each driven through its own interface.

A runner turns a recorded :class:`~amlip_qp.qp.problem.QPProblem` into its
solver's own format in :meth:`Runner.prepare` (not timed: a tracker written
for that solver would build its matrices in that format in place) and solves
it in :meth:`Runner.solve` (timed). A runner whose solver keeps a workspace
between problems (``persistent``) sets it up on its first problem and then
only updates the data, as the tracker does with ProxQP; ``start`` says what
each solve starts from. :attr:`Runner.timed` says what the timed call does.

The sparse solvers (OSQP, QPALM, Clarabel) and the other ``qpsolvers``
backends are in :mod:`amlip_qp.experiments.qp_runners_sparse`.
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from amlip_qp.exceptions import QPError
from amlip_qp.qp.daqp_model import make_model
from amlip_qp.qp.problem import QPProblem
from amlip_qp.qp.solver import ProxQPSolver

_copyto = np.copyto

#: Infinite bounds as the C solvers that take no ``inf`` (DAQP) read them.
BIG_BOUND = 1e30


class Runner:
    """One solver as the bench runs it: :meth:`prepare` untimed, :meth:`solve` timed.

    Attributes:
        name: The name in the report.
        start: What each solve starts from (warm/hot start, or none and why).
        timed: What the timed :meth:`solve` call does.
        failures: Problems the solver returned no solution for.
    """

    name = ""
    start = ""
    timed = ""

    def __init__(self) -> None:
        self.failures = 0

    def setup(self, problems: list[QPProblem]) -> None:
        """Fix what stays the same from problem to problem (not timed; e.g. a sparsity pattern)."""

    def prepare(self, problem: QPProblem) -> Any:
        """``problem`` in the solver's own format (not timed)."""
        return problem

    def load(self, data: Any) -> None:
        """Just before the timed :meth:`solve` of ``data`` (not timed): e.g. write the problem into
        the buffers the solver reads in place, as a tracker's builder does."""

    def solve(self, data: Any) -> np.ndarray | None:
        """Solve prepared data (timed): the full-size ``x``, or ``None`` when the solver found none."""
        raise NotImplementedError


class ProxSuiteRunner(Runner):
    """The tracker's :class:`~amlip_qp.qp.solver.ProxQPSolver` with the tracker's options: after a
    failure it retries once from scratch, as the tracker does (the retry timed too)."""

    timed = "ProxQPSolver.solve: update (or init) + solve, status check"

    def __init__(self, warm: bool, options: dict):
        super().__init__()
        self.name = "proxsuite-warm" if warm else "proxsuite-init"
        self.start = "warm: previous x, y, z (the tracker's path)" if warm else "cold: re-initialised every problem"
        self.solver = ProxQPSolver(**{**options, "warm_start": warm})
        self.retries = 0

    def solve(self, data: QPProblem) -> np.ndarray | None:
        try:
            return self.solver.solve(data).x
        except QPError:
            self.retries += 1
            try:
                return self.solver.solve(data).x
            except QPError:
                self.failures += 1
                return None


def _daqp_data(p: QPProblem) -> tuple:
    """DAQP's ``(H, f, A, bupper, blower, sense)``: the box first, then ``C``, then ``A`` (sense 5: equality)."""
    A = np.ascontiguousarray(np.vstack([p.C, p.A]))
    bu = np.minimum(np.concatenate([p.ub, p.u, p.b]), BIG_BOUND)
    bl = np.maximum(np.concatenate([p.lb, p.l, p.b]), -BIG_BOUND)
    sense = np.zeros(bu.size, dtype=np.intc)
    sense[p.n + p.n_in :] = 5
    return np.ascontiguousarray(p.H), np.array(p.g), A, bu, bl, sense


class DAQPRunner(Runner):
    """DAQP (dual active set). ``hot``: one workspace, set up on the first problem, then updated
    and solved, starting from the previous problem's working set: through DAQP's C API as the
    tracker's :class:`~amlip_qp.qp.daqp_solver.DAQPSolver` drives it
    (:func:`~amlip_qp.qp.daqp_model.make_model`), or with ``model=True`` through ``daqp.Model``
    (the same solutions); otherwise ``daqp.solve``, from the empty working set. A fixed variable
    (``lb == ub``) stays a bound. Hot, each problem is copied (timed) into the arrays the workspace
    was set up on, as a tracker's builder writes into its own buffers, which DAQP reads in place.
    Hot, the update and the solve are also timed apart (:attr:`update_ns`, :attr:`solve_ns`)."""

    def __init__(self, hot: bool, model: bool = False):
        super().__init__()
        import daqp

        self._daqp = daqp
        self.hot = hot
        self.use_c_api = hot and not model
        self.name = ("daqp-hot-model" if model else "daqp-hot") if hot else "daqp-cold"
        self.start = "hot: previous working set" if hot else "cold: empty working set"
        if not hot:
            self.timed = "daqp.solve (set-up + solve)"
        else:
            self.timed = "daqp.Model.update + solve" if model else "DAQP's C API: daqp_update_ldp + daqp_solve"
        self._model: Any = None
        self._buffers: tuple = ()
        #: Hot: per problem after the first, DAQP's update (``H``'s Cholesky factor and its inverse, the
        #: rows through it, the working set factored again) and its solve, each timed alone, ns (inside
        #: the timed call).
        self.update_ns: list[int] = []
        self.solve_ns: list[int] = []

    def prepare(self, p: QPProblem) -> tuple:
        return _daqp_data(p)

    def solve(self, data: tuple) -> np.ndarray | None:
        H, f, A, bu, bl, sense = data
        if not self.hot:
            x, _, flag, _ = self._daqp.solve(H, f, A, bu, bl, sense)
        else:
            if self._model is None:
                self._buffers = tuple(a.copy() for a in (H, f, A, bu, bl))
                self._model = make_model(H.shape[0], bu.size, H.shape[0], use_c_api=self.use_c_api)
                if self._model.setup(*self._buffers, sense) < 0:
                    self._model = None
                    self.failures += 1
                    return None
            else:
                for buffer, value in zip(self._buffers, (H, f, A, bu, bl), strict=True):
                    _copyto(buffer, value)
                t0 = time.perf_counter_ns()
                self._model.update(*self._buffers)
                self.update_ns.append(time.perf_counter_ns() - t0)
            t0 = time.perf_counter_ns()
            flag = self._model.solve()
            if len(self.solve_ns) < len(self.update_ns):  # a solve after an update (not after the set-up)
                self.solve_ns.append(time.perf_counter_ns() - t0)
            x = self._model.x.copy()
        if flag <= 0:
            self.failures += 1
            if self.hot:
                self._model = None  # start the next one afresh
            return None
        return x


class DAQPTrackerRunner(Runner):
    """The QP tracker's own :class:`~amlip_qp.qp.daqp_solver.DAQPSolver` on an allocated problem (one
    per shape), into which each recorded problem is written before its timed solve, as the tracker's
    builder writes its problem in place: hot-started through DAQP's C API, after the first solve as
    one compiled call (:func:`~amlip_qp.codegen.daqp_step.load_daqp_step`)."""

    name = "daqp-tracker"
    start = "hot: previous working set (the tracker's path)"
    timed = "DAQPSolver.solve (the compiled call: bounds, DAQP's update and solve, the check)"
    _FIELDS = ("H", "g", "A", "b", "C", "l", "u", "lb", "ub")

    def __init__(self):
        super().__init__()
        from amlip_qp.codegen.daqp_step import load_daqp_step
        from amlip_qp.qp.daqp_solver import DAQPSolver

        self.solver = DAQPSolver(fast_step=load_daqp_step())
        self._targets: dict[tuple[int, int, int], QPProblem] = {}
        self._target: QPProblem | None = None

    def load(self, data: QPProblem) -> None:
        dims = (data.n, data.n_eq, data.n_in)
        target = self._targets.get(dims)
        if target is None:
            target = self._targets[dims] = QPProblem.allocate(*dims)
        for name in self._FIELDS:
            getattr(target, name)[...] = getattr(data, name)
        self._target = target

    def solve(self, data: QPProblem) -> np.ndarray | None:
        if self._target is None:
            raise RuntimeError("DAQPTrackerRunner.solve called before load")
        try:
            return self.solver.solve(self._target).x
        except QPError:
            self.failures += 1
            return None


class DAQPEliminatedRunner(Runner):
    """DAQP on the problem with its equalities and fixed variables eliminated
    (:func:`~amlip_qp.qp.equality_elimination.eliminate_equalities`): one ``daqp.Model`` per reduced
    shape (the swing forces fixed or free), hot-started as ``daqp-hot``, then ``x = x_0 + Z y``.

    The elimination runs in :meth:`prepare`, untimed, as a tracker whose build wrote the reduced
    problem would have it; its own NumPy and LAPACK time is measured there and reported in
    :attr:`timed`, so the two can be added."""

    name = "daqp-eliminated"
    start = "hot: previous working set of the same reduced shape"

    def __init__(self) -> None:
        super().__init__()
        import daqp

        self._daqp = daqp
        self._models: dict[tuple[int, int], Any] = {}
        #: The elimination's time per problem (µs), measured in :meth:`prepare`.
        self.elimination_us: list[float] = []

    @property
    def timed(self) -> str:  # type: ignore[override]
        median = f"{np.median(self.elimination_us):.1f}" if self.elimination_us else "n/a"
        return (
            "Model.update + Model.solve on the eliminated problem + x = x0 + Z y (the elimination, "
            f"untimed, took a median {median} µs in NumPy and LAPACK)"
        )

    def prepare(self, p: QPProblem) -> tuple | None:
        """The eliminated problem and its DAQP data; ``None`` (counted as a failure when solved)
        for a problem whose equalities cannot be eliminated (rows dependent over its free variables)."""
        from amlip_qp.qp.equality_elimination import eliminate_equalities

        t0 = time.perf_counter_ns()
        try:
            reduced = eliminate_equalities(p)
        except QPError:
            return None
        self.elimination_us.append((time.perf_counter_ns() - t0) * 1e-3)
        return reduced, _daqp_data(reduced.problem)

    def solve(self, data: tuple | None) -> np.ndarray | None:
        if data is None:
            self.failures += 1
            return None
        reduced, (H, f, A, bu, bl, sense) = data
        key = A.shape
        model = self._models.get(key)
        if model is None:
            model = self._daqp.Model()
            if model.setup(H, f, A, bu, bl, sense)[0] < 0:
                self.failures += 1
                return None
            self._models[key] = model
        else:
            model.update(H=H, f=f, A=A, bupper=bu, blower=bl)
        y, _, flag, _ = model.solve()
        if flag <= 0:
            self.failures += 1
            del self._models[key]  # start the next one of this shape afresh
            return None
        return reduced.recover(y)


class QuadprogRunner(Runner):
    """quadprog (Goldfarb-Idnani, dense, no state kept): fixed variables become equality rows, rows
    and bounds at infinity are dropped (in :meth:`prepare`)."""

    name = "quadprog"
    start = "none: no warm start in its interface"
    timed = "quadprog.solve_qp (factorisation + solve)"

    def __init__(self) -> None:
        super().__init__()
        from quadprog import solve_qp

        self._solve_qp = solve_qp

    def prepare(self, p: QPProblem) -> tuple:
        eye = np.eye(p.n)
        fixed = p.lb == p.ub
        fu, fl = np.isfinite(p.u), np.isfinite(p.l)
        bu, bl = np.isfinite(p.ub) & ~fixed, np.isfinite(p.lb) & ~fixed
        # quadprog: min 1/2 x'Gx - a'x  s.t.  C'x >= b, the first meq rows equalities.
        C = np.vstack([p.A, eye[fixed], -p.C[fu], p.C[fl], -eye[bu], eye[bl]])
        b = np.concatenate([p.b, p.lb[fixed], -p.u[fu], p.l[fl], -p.ub[bu], p.lb[bl]])
        return np.array(p.H), -p.g, np.asfortranarray(C.T), b, p.n_eq + int(fixed.sum())

    def solve(self, data: tuple) -> np.ndarray | None:
        try:
            return self._solve_qp(*data)[0]
        except ValueError:  # "constraints are inconsistent, no solution", "matrix G is not positive definite"
            self.failures += 1
            return None


class QPMADRunner(Runner):
    """qpmad (Goldfarb-Idnani, dense) through one persistent ``pyqpmad.Solver`` (its workspace kept);
    equalities are rows with equal bounds. Its ``solve`` factorises ``H`` in place: :meth:`prepare`
    hands it a copy."""

    name = "qpmad"
    start = "none: the solver starts from the unconstrained optimum"
    timed = "Solver.solve (factorisation + solve)"

    def __init__(self) -> None:
        super().__init__()
        import pyqpmad

        self._ok = pyqpmad.ReturnStatus.OK
        self._solver = pyqpmad.Solver()
        self._params = pyqpmad.SolverParameters()

    def prepare(self, p: QPProblem) -> tuple:
        A = np.asfortranarray(np.vstack([p.A, p.C]))  # qpmad takes column-major matrices
        H = np.array(p.H, order="F")
        return H, np.array(p.g), p.lb, p.ub, A, np.concatenate([p.b, p.l]), np.concatenate([p.b, p.u])

    def solve(self, data: tuple) -> np.ndarray | None:
        H, h, lb, ub, A, Alb, Aub = data
        x = np.zeros(h.size)
        if self._solver.solve(x, H, h, lb, ub, A, Alb, Aub, self._params) != self._ok:
            self.failures += 1
            return None
        return x


class PIQPRunner(Runner):
    """PIQP (proximal interior point) through one persistent ``piqp.DenseSolver``: set up on the
    first problem, then ``update`` + ``solve``. Given the tracker's absolute tolerance (relative 0) and
    its primal infeasibility threshold (PIQP's default, 1e-4, reported spurious infeasibility on 4
    of 1200 recorded problems, as ProxQP's does)."""

    name = "piqp"
    start = "none: an interior-point method has no warm start (workspace kept)"
    timed = "DenseSolver.update + solve"

    def __init__(self, eps_abs: float, eps_primal_inf: float):
        super().__init__()
        import piqp

        self._piqp = piqp
        self.eps_abs, self.eps_primal_inf = eps_abs, eps_primal_inf
        self._solver: Any = None

    def prepare(self, p: QPProblem) -> tuple:
        # A row free on both sides becomes the row 0 in [-1, 1] (PIQP warns on every call about
        # infinite pairs, then zeroes such rows itself).
        free = ~(np.isfinite(p.l) | np.isfinite(p.u))
        G = np.asfortranarray(p.C)
        G[free] = 0.0
        h_l, h_u = np.where(free, -1.0, p.l), np.where(free, 1.0, p.u)
        f = np.asfortranarray
        return f(p.H), np.array(p.g), f(p.A), np.array(p.b), G, h_l, h_u, p.lb, p.ub

    def solve(self, data: tuple) -> np.ndarray | None:
        if self._solver is None:
            self._solver = self._piqp.DenseSolver()
            s = self._solver.settings
            s.verbose, s.eps_abs, s.eps_rel, s.eps_primal_inf = False, self.eps_abs, 0.0, self.eps_primal_inf
            self._solver.setup(*data)
        else:
            P, c, A, b, G, h_l, h_u, x_l, x_u = data
            self._solver.update(P=P, c=c, A=A, b=b, G=G, h_l=h_l, h_u=h_u, x_l=x_l, x_u=x_u)
        if self._solver.solve() != self._piqp.PIQP_SOLVED:
            self.failures += 1
            self._solver = None
            return None
        return np.array(self._solver.result.x)
