"""A small dense QP of fixed shape solved by one hot-started DAQP model, with little overhead.

For problems of a few variables solved every control tick (the step-timing MPC of
:mod:`amlip_qp.alip.mpc_planner`): :class:`SmallQPSolver` is called as
``x = solver(H, g, C, lower, upper)`` for

.. math::

    \\min_x \\tfrac12 x^T H x + g^T x \\quad \\text{s.t.}\\quad l \\le C x \\le u,\\; lb \\le x \\le ub

with ``lower = (lb, l)`` and ``upper = (ub, u)`` stacked (DAQP's layout: the bounds of
``x``, then the rows'), and keeps DAQP's model (and so its working set) from one call to the next, like
:class:`~amlip_qp.qp.daqp_solver.DAQPSolver` but without a :class:`~amlip_qp.qp.problem.QPProblem`:
the arrays are copied into the solver's own buffers, which the model reads in place
(:func:`~amlip_qp.qp.daqp_model.make_model`: DAQP's C API when it loads). Bounds beyond
``+-BIG_BOUND`` are DAQP's "no bound".

:meth:`SmallQPSolver.solve_stacked` takes the same problem as one array in DAQP's own
order, ``(H row-major, g, C row-major, lower, upper)`` (the layout of
:func:`~amlip_qp.alip.step_mpc.mpc_qp`'s output): one copy instead of five. Given a
``producer`` (the function making that array of some inputs), :meth:`SmallQPSolver.solve_inputs`
takes the inputs. Given a ``fast_step`` (:mod:`amlip_qp.codegen.daqp_step`), once the model is
set up either runs as one compiled call (the producer's compiled kernel inside it): the same
solutions, bit for bit.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from amlip_qp.exceptions import InputError, QPError
from amlip_qp.qp.daqp_model import CModel, make_model
from amlip_qp.qp.daqp_solver import BIG_BOUND, PRIMAL_TOL

_max_reduce = np.maximum.reduce  # the ufunc's reduce: ndarray.max's Python layer costs more on these sizes
#: DAQP's sense flag of a soft row.
SENSE_SOFT = 8
#: Largest constraint violation (in the rows' units) a reported solution may have.
RESIDUAL_CHECK = 1e-4


class SmallQPSolver:
    """A hot-started DAQP model for QPs of ``n`` variables and ``m`` two-sided rows (module doc).

    Args:
        n: number of variables (> 0).
        m: number of rows of ``C`` (>= 0).
        soft_rows: rows of ``C`` that are soft (DAQP's soft constraints: violated, with a
            slack of cost ``slack^2 / rho_soft``, ``rho_soft = 1e-6``, only when the hard
            ones leave no other choice); not checked against :data:`RESIDUAL_CHECK`.
        iter_limit: DAQP's iteration cap per solve.
        use_c_api: drive DAQP through its C API when it loads (the same solutions, less overhead);
            ``False``: through ``daqp.Model``.
        fast_step: for :meth:`solve_stacked` on DAQP's C API, the copy, the clamps, DAQP's update
            and solve and the check in one compiled call: an object whose ``bind(handles, data, x,
            hard, n, m, big)`` returns ``step(src) -> (exit flag, largest violation)``
            (:class:`amlip_qp.codegen.daqp_step.DAQPStep`); the same solutions.
        producer: for :meth:`solve_inputs`, the function making the stacked problem of its inputs
            (the step-timing MPC's ``alip_mpc_qp`` kernel); ``producer_c``: its compiled C entry
            point (:meth:`Kernels.c_kernel <amlip_qp.codegen.kernels.Kernels.c_kernel>`), which
            the fast path then calls itself.

    Attributes:
        solves: calls so far; failures: calls that raised; last_solve_us: the last call's time, µs.
    """

    def __init__(
        self,
        n: int,
        m: int,
        soft_rows: tuple[int, ...] = (),
        iter_limit: int = 200,
        use_c_api: bool = True,
        fast_step: Any = None,
        producer: Callable[[np.ndarray], np.ndarray] | None = None,
        producer_c: Any = None,
    ):
        if (
            isinstance(n, bool)
            or not isinstance(n, int)
            or n < 1
            or isinstance(m, bool)
            or not isinstance(m, int)
            or m < 0
        ):
            raise QPError(f"SmallQPSolver(n={n!r}, m={m!r}): n must be an integer > 0 and m an integer >= 0")
        self.n, self.m = n, m
        self.iter_limit = int(iter_limit)
        self.use_c_api = bool(use_c_api)
        # one buffer in DAQP's order (solve_stacked copies into it at once): H, f, A, lower, upper
        sizes = np.cumsum([0, n * n, n, m * n, n + m, n + m])
        self._data = np.zeros(int(sizes[-1]))
        d = self._data
        self._H = d[sizes[0] : sizes[1]].reshape(n, n)
        self._f = d[sizes[1] : sizes[2]]
        self._A = d[sizes[2] : sizes[3]].reshape(m, n)
        self._bl = d[sizes[3] : sizes[4]]
        self._bu = d[sizes[4] : sizes[5]]
        self._sense = np.zeros(n + m, dtype=np.intc)
        self._z = np.zeros(n + m)
        self._z_x, self._z_rows = self._z[:n], self._z[n:]
        self._big = np.full(n + m, BIG_BOUND)  # DAQP's "no bound", one array (no scalar broadcast per call)
        self._neg_big = -self._big
        self._t1, self._t2 = np.zeros(n + m), np.zeros(n + m)
        self._hard = np.ones(n + m)  # 1: checked (the bounds of x, the hard rows), 0: soft
        for i in soft_rows:
            if isinstance(i, bool) or not isinstance(i, int) or not 0 <= i < m:
                raise QPError(f"soft_rows must be row indices in [0, {m}), got {soft_rows!r}")
            self._sense[n + i] = SENSE_SOFT
            self._hard[n + i] = 0.0
        self._model: Any = None
        if fast_step is not None and not callable(getattr(fast_step, "bind", None)):
            raise InputError(f"fast_step must have a bind(...) method (a DAQPStep), got {fast_step!r}")
        if producer is not None and not callable(producer):
            raise InputError(f"producer must be callable (inputs -> the stacked QP), got {producer!r}")
        self._fast_step = fast_step
        self._bound_step: Any = None  # fast_step bound to the current model
        #: The function making the stacked problem of :meth:`solve_inputs`' inputs, or ``None``.
        self.producer = producer
        self._producer_c = producer_c if producer is not None else None
        self.solves = 0
        self.failures = 0
        self.last_solve_us = 0.0

    @property
    def fast_path(self) -> bool:
        """Whether :meth:`solve_stacked` (without a producer) or :meth:`solve_inputs` (with one) runs
        as the one compiled call of ``fast_step`` (bound once the model is set up through DAQP's C API)."""
        return self._bound_step is not None

    def reset(self) -> None:
        """Forget the working set: the next call sets the model up afresh."""
        self._model = self._bound_step = None

    def __call__(self, H, g, C, lower, upper) -> np.ndarray:
        """Solve; return ``x`` (a new array). ``lower``, ``upper``: ``n + m`` bounds each (module doc).
        Raises :class:`QPError` when DAQP fails or the solution violates a hard row or a bound
        by more than :data:`RESIDUAL_CHECK`."""
        t0 = time.perf_counter_ns()
        self._H[:] = H
        self._f[:] = g
        self._A[:] = C
        self._bl[:] = lower
        self._bu[:] = upper
        return self._solve(t0)

    def solve_stacked(self, data: np.ndarray) -> np.ndarray:
        """As calling the solver, with the problem as one 1-D array ``(H row-major, g, C
        row-major, lower, upper)`` of ``n^2 + n + m n + 2 (n + m)`` entries (module doc)."""
        t0 = time.perf_counter_ns()
        if self._bound_step is not None and self.producer is None:
            return self._solve_fast(data, t0)
        return self._solve_python(data, t0)

    def solve_inputs(self, inputs: np.ndarray) -> np.ndarray:
        """The QP ``producer`` makes of ``inputs``: as ``solve_stacked(producer(inputs))``, on the fast
        path one compiled call that also runs the producer's compiled kernel (``producer_c``)."""
        if self.producer is None:
            raise InputError("solve_inputs needs a SmallQPSolver made with a producer")
        t0 = time.perf_counter_ns()
        if self._bound_step is not None:
            return self._solve_fast(inputs, t0)
        return self._solve_python(self.producer(inputs), t0)

    def _solve_fast(self, src: np.ndarray, t0: int) -> np.ndarray:
        flag, violation = self._bound_step(src)
        self.solves += 1
        self.last_solve_us = (time.perf_counter_ns() - t0) * 1e-3
        if flag not in (1, 2) or not violation <= RESIDUAL_CHECK:  # NaN fails, as in the Python check
            self._fail(flag)
        return self._model.x.copy()

    def _solve_python(self, data: np.ndarray, t0: int) -> np.ndarray:
        if np.shape(data) != self._data.shape:
            size, shape = self._data.size, np.shape(data)
            raise InputError(f"the stacked QP must be a 1-D array of {size} entries, got shape {shape}")
        self._data[:] = data
        x = self._solve(t0)
        if self._fast_step is not None and isinstance(self._model, CModel):
            self._bound_step = self._fast_step.bind(
                self._model.c_handles(),
                self._data,
                self._model.x,
                self._hard,
                self.n,
                self.m,
                BIG_BOUND,
                producer=self._producer_c,
            )
        return x

    def _fail(self, flag: int):
        self.failures += 1
        self._model = self._bound_step = None
        raise QPError(f"DAQP failed on the small QP (exit flag {flag})", status=f"DAQP_EXIT_{flag}")

    def _solve(self, t0: int) -> np.ndarray:
        np.minimum(self._bu, self._big, out=self._bu)
        np.maximum(self._bl, self._neg_big, out=self._bl)
        self.solves += 1
        model = self._model
        if model is None:
            model = make_model(self.n, self.n + self.m, self.n, use_c_api=self.use_c_api)
            code = model.setup(self._H, self._f, self._A, self._bu, self._bl, self._sense)
            if code < 0:
                self.failures += 1
                raise QPError(f"DAQP set-up failed with code {code}", status=f"DAQP_SETUP_{code}")
            model.set_settings(self.iter_limit, PRIMAL_TOL)
            self._model = model
        else:
            model.update(self._H, self._f, self._A, self._bu, self._bl)
        flag = model.solve()
        x = model.x.copy()
        ok = flag in (1, 2) and math.isfinite(sum(x.tolist()))
        if ok:
            z = self._z
            self._z_x[:] = x
            np.dot(self._A, x, out=self._z_rows)
            t1, t2 = self._t1, self._t2
            np.subtract(self._bl, z, out=t1)
            np.subtract(z, self._bu, out=t2)
            np.maximum(t1, t2, out=t1)
            t1 *= self._hard
            ok = float(_max_reduce(t1)) <= RESIDUAL_CHECK  # NaN (a NaN row) fails it, as with ndarray.max
        self.last_solve_us = (time.perf_counter_ns() - t0) * 1e-3
        if not ok:
            self._fail(flag)
        return x
