"""One persistent DAQP solver (a dual active-set method), hot-started from the last working set.

DAQP (Arnström, Bemporad and Axehill, IEEE TAC 2022) solves a dense QP with
a positive definite ``H`` to its own tolerances (an active-set
method: no iteration-count tolerance trade-off). On the whole-body QP
tracker's recorded problems its median solve took 0.39-0.45x warm ProxQP's
time (``amlip-qp bench qp``, docs/BENCH_QP.md). :class:`DAQPSolver` has
:class:`~amlip_qp.qp.solver.ProxQPSolver`'s interface, so the tracker takes
either (``QPTracker(qp_solver="daqp")``).

The problem is handed over as DAQP takes it: the bounds ``lb <= x <= ub`` as
its simple bounds, then ``l <= C x <= u``, then ``A x = b`` (sense 5: an
equality), each infinite bound replaced by :data:`BIG_BOUND`. A problem made
by :meth:`QPProblem.allocate <amlip_qp.qp.problem.QPProblem.allocate>` (the
QP tracker's) already holds ``[C; A]`` as one block (:meth:`QPProblem.stacked
<amlip_qp.qp.problem.QPProblem.stacked>`): DAQP reads it in place, and the
bounds are stacked with two clamps and two copies of ``b``. One
DAQP workspace per problem shape (:func:`~amlip_qp.qp.daqp_model.make_model`:
DAQP's C API, or ``daqp.Model``) lives as long as the solver; each solve
``update``-s it and starts from the previous solve's working set (a hot
start). DAQP is a deterministic sequence of floating-point operations: the
same problems in the same order give the same solutions.
"""

from __future__ import annotations

import math
import time
from typing import Any

import numpy as np

from amlip_qp.exceptions import InputError, QPError
from amlip_qp.qp.daqp_model import CModel, make_model
from amlip_qp.qp.problem import QPProblem
from amlip_qp.qp.solver import MAX_SHAPES, QPSolution

#: An infinite bound as DAQP sees it (its own default for "no bound" is 1e30).
BIG_BOUND = 1e30
#: DAQP's sense flag of an equality row (active and immutable).
SENSE_EQUALITY = 5
#: DAQP's primal feasibility tolerance (its default, set explicitly), in the rows' units.
PRIMAL_TOL = 1e-6
#: Largest constraint violation a reported solution may have before it is refused (100x PRIMAL_TOL).
RESIDUAL_CHECK = 1e-4
#: The exit flag given to a reported solution that violates its constraints by more than RESIDUAL_CHECK.
_VIOLATED = -100
#: DAQP's exit flags that mean solved (1: optimal; 2: optimal, soft constraints violated, none here).
_SOLVED = (1, 2)


_max_reduce = np.maximum.reduce
_minimum, _maximum, _subtract, _dot, _copyto = np.minimum, np.maximum, np.subtract, np.dot, np.copyto


class _Shape:
    """The stacked arrays and the ``daqp.Model`` of one problem shape.

    The blocks of the stacked arrays are views made once: per call, slicing would cost more than
    the small copies themselves."""

    def __init__(self, problem: QPProblem):
        n, n_in, n_eq = problem.n, problem.n_in, problem.n_eq
        m = n + n_in + n_eq
        self.A = np.zeros((n_in + n_eq, n))
        # The residual check's buffers: ``lo = (bl, z)`` and ``hi = (z, bu)`` with ``z = (x, C x, A x)``,
        # so that one subtraction gives both violations ``lo - hi = (bl - z, z - bu)``; the bounds
        # DAQP reads are their halves.
        self._lo, self._hi = np.zeros(2 * m), np.zeros(2 * m)
        self.bl, self.bu = self._lo[:m], self._hi[m:]
        self.sense = np.zeros(m, dtype=np.intc)
        self.sense[n + n_in :] = SENSE_EQUALITY
        self.model: Any = None
        self.z, self._z_hi = self._lo[m:], self._hi[:m]
        self.gap = np.zeros(2 * m)
        self._gap_below, self._gap_above = self.gap[:m], self.gap[m:]
        self._A_in, self._A_eq = self.A[:n_in], self.A[n_in:]
        self._bu_box, self._bu_in, self._bu_eq = self.bu[:n], self.bu[n : n + n_in], self.bu[n + n_in :]
        self._bl_box, self._bl_in, self._bl_eq = self.bl[:n], self.bl[n : n + n_in], self.bl[n + n_in :]
        self._z_x, self._z_rows = self.z[:n], self.z[n:]
        self._bu_rows, self._bl_rows = self.bu[: n + n_in], self.bl[: n + n_in]
        #: The rows ``[C; A]`` DAQP solves: the problem's own block when it is stacked, else :attr:`A`.
        self.rows = self.A
        #: The compiled call bound to :attr:`model` and to the arrays of :attr:`compiled_for`, or ``None``.
        self.compiled: Any = None
        self.compiled_for: QPProblem | None = None

    def largest_gap(self, x: np.ndarray) -> float:
        """The largest of ``bl - z`` and ``z - bu`` at ``x`` (``z = (x, C x, A x)``, the problem last
        :meth:`fill`-ed), in one product and one pass; NaN if ``x`` has a NaN, and above any
        tolerance if it has an infinite entry (against a finite box bound). Its
        buffer :attr:`gap` then holds both violations (:meth:`violation`)."""
        _copyto(self._z_x, x)
        _dot(self.rows, x, out=self._z_rows)
        _copyto(self._z_hi, self.z)
        _subtract(self._lo, self._hi, out=self.gap)
        return _max_reduce(self.gap)

    def violation(self, x: np.ndarray) -> float:
        """Largest violation at ``x`` of the problem last :meth:`fill`-ed (bounds, inequalities,
        equalities; the stacked rows and bounds DAQP solved, so an infinite bound, held as
        :data:`BIG_BOUND`, is never violated): :meth:`QPProblem.residuals
        <amlip_qp.qp.problem.QPProblem.residuals>`' largest entry (NaN if either the violations
        below or those above are NaN throughout, as a NaN ``x`` makes them)."""
        self.largest_gap(x)
        return max(_max_reduce(self._gap_below), _max_reduce(self._gap_above), 0.0)

    def fill(self, p: QPProblem, stacked: tuple | None = None) -> None:
        """Stack ``p``'s rows and bounds as DAQP takes them (:attr:`rows`, :attr:`bu`, :attr:`bl`);
        ``stacked``: ``p.stacked()`` when the caller has it (else it is asked here)."""
        if stacked is None:
            stacked = p.stacked()
        if stacked is not None:
            # the rows in place; the box and inequality bounds lie stacked already (the same clamps)
            self.rows, lower, upper = stacked
            _minimum(upper, BIG_BOUND, out=self._bu_rows)
            _copyto(self._bu_eq, p.b)
            _maximum(lower, -BIG_BOUND, out=self._bl_rows)
            _copyto(self._bl_eq, p.b)
            return
        self.rows = self.A
        _copyto(self._A_in, p.C)
        _copyto(self._A_eq, p.A)
        _minimum(p.ub, BIG_BOUND, out=self._bu_box)
        _minimum(p.u, BIG_BOUND, out=self._bu_in)
        _copyto(self._bu_eq, p.b)
        _maximum(p.lb, -BIG_BOUND, out=self._bl_box)
        _maximum(p.l, -BIG_BOUND, out=self._bl_in)
        _copyto(self._bl_eq, p.b)


class DAQPSolver:
    """A persistent DAQP solver, hot-started (module doc).

    Args:
        warm_start: Start each solve from the previous working set of the same shape (default);
            ``False`` sets the model up afresh at every call, from the empty working set.
        iter_limit: DAQP's iteration cap per solve.
        use_c_api: drive DAQP through its C API when it loads (:mod:`amlip_qp.qp.daqp_model`:
            the same solutions, less Python per solve); ``False``: through ``daqp.Model``.
        fast_step: for a problem made by :meth:`QPProblem.allocate
            <amlip_qp.qp.problem.QPProblem.allocate>` solved hot on DAQP's C API, the bounds'
            stacking, DAQP's update and solve and the solution's check in one compiled call: an
            object with :meth:`~amlip_qp.codegen.daqp_step.DAQPStep.bind_rows`
            (:func:`amlip_qp.codegen.daqp_step.load_daqp_step`); the same solutions.

    Raises:
        ImportError: DAQP is not installed (``pip install daqp``).
    """

    def __init__(self, warm_start: bool = True, iter_limit: int = 1000, use_c_api: bool = True, fast_step: Any = None):
        import daqp  # noqa: F401 - the ImportError is raised here, at construction

        self.use_c_api = bool(use_c_api)
        if fast_step is not None and not callable(getattr(fast_step, "bind_rows", None)):
            raise InputError(f"fast_step must have a bind_rows(...) method (a DAQPStep), got {fast_step!r}")
        self._fast_step = fast_step
        self.warm_start = bool(warm_start)
        self.iter_limit = int(iter_limit)
        self._shapes: dict[tuple[int, int, int], _Shape] = {}
        # the allocated problem solved last and its shape (an allocated problem's shapes are fixed)
        self._last: tuple[QPProblem, _Shape] | None = None
        #: Number of model set-ups so far (1 per problem shape in steady hot-started use).
        self.n_init = 0
        #: Number of solves run as the compiled call of ``fast_step``.
        self.n_compiled = 0

    @property
    def options(self) -> dict:
        """The constructor arguments of this solver (to build another one alike)."""
        return {
            "warm_start": self.warm_start,
            "iter_limit": self.iter_limit,
            "use_c_api": self.use_c_api,
            "fast_step": self._fast_step,
        }

    @property
    def primal_tol(self) -> float:
        """Largest constraint violation a solution may have: DAQP's ``primal_tol`` setting (1e-6)."""
        return PRIMAL_TOL

    def reset(self) -> None:
        """Forget the working sets; the next solve of each shape sets its model up afresh."""
        self._shapes.clear()
        self._last = None

    def solve(self, problem: QPProblem, check: bool = False) -> QPSolution:
        """Solve ``problem``; raise :class:`QPError` (carrying it) on failure. ``check``: first
        validate ``problem`` (:meth:`QPProblem.validate
        <amlip_qp.qp.problem.QPProblem.validate>`: an invalid one raises its
        :class:`~amlip_qp.exceptions.InvalidQPError` and leaves the solver as it was), inside the
        compiled call when there is one."""
        t0 = time.perf_counter_ns()
        stacked = problem.stacked()
        last = self._last
        if stacked is not None and last is not None and last[0] is problem:
            # the same allocated problem as the last solve, its views still in place: the same shape
            shape = last[1]
            if shape.compiled is not None and shape.compiled_for is problem and shape.model is not None:
                return self._solve_compiled(problem, shape, t0, check)
            if check:
                problem.validate()
        else:
            if check:  # before the solver's state changes
                problem.validate()
            dims = (problem.n, problem.n_eq, problem.n_in)
            found = self._shapes.get(dims)
            if found is None:
                if len(self._shapes) >= MAX_SHAPES:
                    del self._shapes[next(iter(self._shapes))]  # the oldest shape
                found = self._shapes[dims] = _Shape(problem)
            shape = found
            self._last = (problem, shape) if stacked is not None else None
        shape.fill(problem, stacked)
        if stacked is not None:  # an allocated problem's H and g: contiguous views of its buffer
            H, f = problem.H, problem.g
        else:
            H, f = np.ascontiguousarray(problem.H), np.ascontiguousarray(problem.g)
        rows = shape.rows if shape.rows.flags.c_contiguous else np.ascontiguousarray(shape.rows)
        model = shape.model
        if model is None or not self.warm_start:
            model = shape.model = make_model(problem.n, len(shape.sense), problem.n, use_c_api=self.use_c_api)
            shape.compiled = shape.compiled_for = None
            code = model.setup(H, f, rows, shape.bu, shape.bl, shape.sense)
            model.set_settings(self.iter_limit, PRIMAL_TOL)
            self.n_init += 1
            if code < 0:
                shape.model = None
                status = f"DAQP_SETUP_{code}"
                raise QPError(f"DAQP set-up failed with code {code}", problem=problem, status=status)
        else:
            model.update(H, f, rows, shape.bu, shape.bl)
        flag = model.solve()
        x = model.x.copy()
        elapsed_us = (time.perf_counter_ns() - t0) * 1e-3
        # A hot-started update skips the set-up's checks (a zero constraint row that contradicts its
        # bound is then reported solved): the solution is checked against the constraints here. Within
        # the tolerance, x is also finite (a NaN gives a NaN gap, an infinite entry an infinite one).
        if flag not in _SOLVED or not shape.largest_gap(x) <= RESIDUAL_CHECK:
            if flag in _SOLVED and shape.violation(x) > RESIDUAL_CHECK:
                flag = _VIOLATED
            if flag not in _SOLVED or not math.isfinite(sum(x.tolist())):
                # the next solve of this shape starts afresh (other shapes stay hot)
                shape.model = shape.compiled = shape.compiled_for = None
                raise QPError(f"DAQP failed with exit flag {flag}", problem=problem, status=f"DAQP_EXIT_{flag}")
        if self._fast_step is not None and stacked is not None and self.warm_start and isinstance(model, CModel):
            if shape.compiled_for is not problem:
                rows, lower, upper = stacked
                buffers = problem.buffers()
                assert buffers is not None  # stacked: an allocated problem's views
                try:
                    bounds = (lower, upper, problem.b, shape.bl, shape.bu)
                    shape.compiled = self._fast_step.bind_rows(
                        model.c_handles(), *bounds, rows, model.x, BIG_BOUND, buffers[0]
                    )
                    shape.compiled_for = problem
                except InputError:  # arrays the compiled call cannot read in place: the Python path
                    shape.compiled, shape.compiled_for = None, None
        return QPSolution(x=x, status="DAQP_SOLVED", iterations=model.iterations, solve_time_us=elapsed_us)

    def _solve_compiled(self, problem: QPProblem, shape: _Shape, t0: int, check: bool) -> QPSolution:
        """The hot solve of the problem ``shape.compiled`` is bound to, as one compiled call (class doc);
        with ``check``, the call validates the problem first and returns a failure flag without a
        solve if it is invalid."""
        flag, gap = shape.compiled(check)
        self.n_compiled += 1
        model = shape.model
        x = model.x.copy()
        elapsed_us = (time.perf_counter_ns() - t0) * 1e-3
        if flag not in _SOLVED or not gap <= RESIDUAL_CHECK:  # as in solve: the same checks, the same order
            if check and flag not in _SOLVED:
                problem.validate()  # an invalid problem (the compiled check's failure): its named error
            if flag in _SOLVED and shape.violation(x) > RESIDUAL_CHECK:
                flag = _VIOLATED
            if flag not in _SOLVED or not math.isfinite(sum(x.tolist())):
                shape.model = shape.compiled = shape.compiled_for = None
                raise QPError(f"DAQP failed with exit flag {flag}", problem=problem, status=f"DAQP_EXIT_{flag}")
        return QPSolution(x=x, status="DAQP_SOLVED", iterations=model.iterations, solve_time_us=elapsed_us)
