"""DAQP's hot path as one compiled call: the data in, DAQP's update and solve, and the check.

Two solvers drive DAQP through its C API (:mod:`amlip_qp.qp.daqp_model`): the step-timing MPC's
:class:`~amlip_qp.qp.small_qp.SmallQPSolver` and the QP tracker's
:class:`~amlip_qp.qp.daqp_solver.DAQPSolver`. Around DAQP's two C calls their Python stacks or
copies the problem in, clamps the bounds and checks the solution against the constraints, a
dozen numpy calls that cost about as much as DAQP's own work. ``daqp_step.c`` (beside this
module) does the same in one C function each, calling DAQP through the addresses
:meth:`CModel.c_handles <amlip_qp.qp.daqp_model.CModel.c_handles>` hands over: the same DAQP
calls on the same data, so the same solutions bit for bit (the rows' products of the check are
summed in a plain loop rather than by numpy's ``dot``: the same check, its value may differ in
the last bits).

- ``amlip_daqp_step`` (:meth:`DAQPStep.bind`): a problem of fixed shape given as one array in
  DAQP's order, copied in; or, with a producer, a compiled CasADi kernel
  (:meth:`Kernels.c_kernel <amlip_qp.codegen.kernels.Kernels.c_kernel>`; the MPC's
  ``alip_mpc_qp``), the step's input is the kernel's input and the kernel writes the problem
  straight into the workspace's arrays: the MPC's matrices, solve and check in one call
  (:meth:`SmallQPSolver.solve_inputs <amlip_qp.qp.small_qp.SmallQPSolver.solve_inputs>`).
- ``amlip_daqp_rows`` (:meth:`DAQPStep.bind_rows`): the QP tracker's allocated problem read where
  its builder wrote it; the bounds stacked and clamped into DAQP's arrays. On request it first
  tests the problem as :meth:`QPProblem.validate <amlip_qp.qp.problem.QPProblem.validate>` does
  (every matrix and vector entry finite, no lower bound above its upper bound), so that the
  tracker's validation is part of the same call.

:func:`load_daqp_step` compiles both once into the codegen cache
(:func:`~amlip_qp.codegen.runtime.compile_library`) and returns a :class:`DAQPStep`, the
``fast_step`` both solvers take; without a C compiler it returns ``None`` (the Python paths, the
same solutions) and one :class:`~amlip_qp.codegen.runtime.CodegenFallbackWarning` says so.
"""

from __future__ import annotations

import ctypes
import warnings
from importlib import resources
from typing import Any

import numpy as np

from amlip_qp.codegen.kernels import CKernel
from amlip_qp.exceptions import CompilerUnavailableError, InputError

SOURCE_FILE = "amlip_daqp_step.c"
LIBRARY_FILE = "libamlip_daqp_step.so"


def _pointers(*names: str) -> list:
    return [(name, ctypes.c_void_p) for name in names]


#: The fields both C structures begin with: DAQP's two functions and its three structures.
_DAQP_FIELDS = _pointers("update", "solve", "work", "problem", "result")


class _Context(ctypes.Structure):
    """``amlip_daqp_step_t`` of ``daqp_step.c`` (the same fields in the same order)."""

    _fields_ = [
        *_DAQP_FIELDS,
        *_pointers("data", "x", "hard"),
        ("n", ctypes.c_int),
        ("m", ctypes.c_int),
        ("update_mask", ctypes.c_int),
        ("exitflag_offset", ctypes.c_int),
        ("big", ctypes.c_double),
        ("violation", ctypes.c_double),
        *_pointers("producer", "producer_arg", "producer_res", "producer_iw", "producer_w"),
    ]


class _RowsContext(ctypes.Structure):
    """``amlip_daqp_rows_t`` of ``daqp_step.c`` (the same fields in the same order)."""

    _fields_ = [
        *_DAQP_FIELDS,
        *_pointers("lower", "upper", "b", "bl", "bu", "rows"),
        ("x", ctypes.c_void_p),
        ("data", ctypes.c_void_p),
        ("n", ctypes.c_int),
        ("n_in", ctypes.c_int),
        ("n_eq", ctypes.c_int),
        ("update_mask", ctypes.c_int),
        ("exitflag_offset", ctypes.c_int),
        ("n_data", ctypes.c_int),
        ("check_problem", ctypes.c_int),
        ("big", ctypes.c_double),
        ("gap", ctypes.c_double),
    ]


#: The exit flag of ``amlip_daqp_rows`` when its check finds the problem invalid (a non-finite
#: entry of ``H, g, C, A, b`` or a lower bound not at most its upper bound); DAQP is not called.
INVALID_PROBLEM = -200


class BoundStep:
    """``step(src) -> (exit flag, largest violation)`` for one workspace (module doc); ``src`` is the
    problem as one C-contiguous float64 array in DAQP's order. The violation is meaningful only
    when the flag is 1 or 2 (solved)."""

    __slots__ = ("_fn", "_context", "_context_address", "_keep", "_src", "_src_address", "_size")

    def __init__(self, fn, context: _Context, keep: tuple, size: int):
        self._fn = fn
        self._context = context
        self._context_address = ctypes.addressof(context)
        self._keep = keep  # the arrays the context points into, and the model whose workspace it drives
        self._src: np.ndarray | None = None
        self._src_address = 0
        self._size = size

    def __call__(self, src: np.ndarray) -> tuple[int, float]:
        if src is not self._src:
            if src.dtype != np.float64 or not src.flags.c_contiguous or src.size != self._size:
                raise InputError(f"the step's input must be a C-contiguous float64 array of {self._size} entries")
            self._src, self._src_address = src, src.ctypes.data
        flag = self._fn(self._context_address, self._src_address)
        return flag, self._context.violation


class BoundRows:
    """``step(check=False) -> (exit flag, largest gap)`` for one workspace and one problem's arrays
    (the QP tracker's, :meth:`DAQPStep.bind_rows`); the gap is meaningful only when the flag is 1
    or 2. With ``check``, the problem is first tested as :meth:`QPProblem.validate
    <amlip_qp.qp.problem.QPProblem.validate>` tests it; a problem that fails returns
    :data:`INVALID_PROBLEM` without a solve."""

    __slots__ = ("_fn", "_context", "_context_address", "_keep", "_check")

    def __init__(self, fn, context: _RowsContext, keep: tuple):
        self._fn = fn
        self._context = context
        self._context_address = ctypes.addressof(context)
        self._keep = keep  # the arrays the context points into, and the model whose workspace it drives
        self._check = False

    def __call__(self, check: bool = False) -> tuple[int, float]:
        if check is not self._check:
            check = bool(check)
            self._context.check_problem = int(check)
            self._check = check
        flag = self._fn(self._context_address)
        return flag, self._context.gap


def _checked(name: str, a: np.ndarray, size: int) -> np.ndarray:
    if a.dtype != np.float64 or not a.flags.c_contiguous or a.size != size:
        raise InputError(f"{name} must be a C-contiguous float64 array of {size} entries")
    return a


class DAQPStep:
    """The compiled ``amlip_daqp_step`` and ``amlip_daqp_rows`` (module doc); :meth:`bind` and
    :meth:`bind_rows` them to a set-up workspace."""

    def __init__(self, library: ctypes.CDLL):
        self._fn = library.amlip_daqp_step
        self._fn.argtypes = [ctypes.c_void_p, ctypes.c_void_p]
        self._fn.restype = ctypes.c_int
        self._rows_fn = library.amlip_daqp_rows
        self._rows_fn.argtypes = [ctypes.c_void_p]
        self._rows_fn.restype = ctypes.c_int

    def bind_rows(
        self,
        handles: Any,
        lower: np.ndarray,
        upper: np.ndarray,
        b: np.ndarray,
        bl: np.ndarray,
        bu: np.ndarray,
        rows: np.ndarray,
        x: np.ndarray,
        big: float,
        data: np.ndarray,
    ) -> BoundRows:
        """A :class:`BoundRows` on the workspace of ``handles``, set up on ``H``, ``f``, ``rows``
        (``[C; A]``, ``(n_in + n_eq, n)``), ``bu`` and ``bl`` (``n + n_in + n_eq``), which it
        fills from ``lower``, ``upper`` (``n + n_in``, clamped to ``+-big``) and ``b`` (``n_eq``);
        its solution in ``x`` (``n``). ``data``: the problem's ``H, g, C, A, b`` in one buffer
        (:meth:`QPProblem.buffers <amlip_qp.qp.problem.QPProblem.buffers>`), which the check reads."""
        n, n_eq = x.size, b.size
        n_in = lower.size - n
        n_data = n * n + n + (n_in + n_eq) * n + n_eq
        arrays = {"lower": (lower, n + n_in), "upper": (upper, n + n_in), "b": (b, n_eq),
                  "bl": (bl, n + n_in + n_eq), "bu": (bu, n + n_in + n_eq), "rows": (rows, (n_in + n_eq) * n),
                  "x": (x, n), "data": (data, n_data)}  # fmt: skip
        for name, (a, size) in arrays.items():
            _checked(name, a, size)
        context = _RowsContext(
            update=handles.update_fn,
            solve=handles.solve_fn,
            work=handles.work,
            problem=handles.problem,
            result=handles.result,
            n=n,
            n_in=n_in,
            n_eq=n_eq,
            update_mask=handles.update_mask,
            exitflag_offset=handles.exitflag_offset,
            n_data=n_data,
            check_problem=0,
            big=big,
            gap=0.0,
        )
        for name, (a, _) in arrays.items():
            setattr(context, name, a.ctypes.data)
        return BoundRows(self._rows_fn, context, (*(a for a, _ in arrays.values()), handles.owner))

    def bind(
        self,
        handles: Any,
        data: np.ndarray,
        x: np.ndarray,
        hard: np.ndarray,
        n: int,
        m: int,
        big: float,
        producer: CKernel | None = None,
    ) -> BoundStep:
        """A :class:`BoundStep` on the workspace of ``handles``, set up on ``data`` (``H, f, A, lower,
        upper`` of ``n`` variables and ``m`` rows, contiguous), its solution in ``x``, ``hard``
        (``n + m``: 1 checked, 0 not), bounds clamped to ``+-big``. With ``producer`` (a compiled
        kernel whose output is that problem), the step's input is the kernel's input."""
        size = n * n + n + m * n + 2 * (n + m)
        if producer is not None and producer.n_out != size:
            raise InputError(f"the producer {producer.name} writes {producer.n_out} values, the problem has {size}")
        for name, a, want in (("data", data, size), ("x", x, n), ("hard", hard, n + m)):
            if a.dtype != np.float64 or not a.flags.c_contiguous or a.size != want:
                raise ValueError(f"{name} must be a C-contiguous float64 array of {want} entries")
        context = _Context(
            update=handles.update_fn,
            solve=handles.solve_fn,
            work=handles.work,
            problem=handles.problem,
            result=handles.result,
            data=data.ctypes.data,
            x=x.ctypes.data,
            hard=hard.ctypes.data,
            n=n,
            m=m,
            update_mask=handles.update_mask,
            exitflag_offset=handles.exitflag_offset,
            big=big,
            violation=0.0,
        )
        keep: tuple = (data, x, hard, handles.owner)
        if producer is not None:
            work = (
                (ctypes.c_void_p * max(producer.sz_arg, 1))(),
                (ctypes.c_void_p * max(producer.sz_res, 1))(),
                (ctypes.c_longlong * max(producer.sz_iw, 1))(),
                (ctypes.c_double * max(producer.sz_w, 1))(),
            )
            context.producer = producer.function
            context.producer_arg, context.producer_res, context.producer_iw, context.producer_w = (
                ctypes.addressof(w) for w in work
            )
            keep += work
        return BoundStep(self._fn, context, keep, size if producer is None else producer.n_in)


_loaded: DAQPStep | None = None
_unavailable: str | None = None


def load_daqp_step(cache_dir=None, refresh: bool = False) -> DAQPStep | None:
    """The compiled step (compiled once into the cache), or ``None`` without a C compiler (with one
    :class:`~amlip_qp.codegen.runtime.CodegenFallbackWarning` per process; ``refresh``: forget the
    last outcome and try again)."""
    global _loaded, _unavailable
    if refresh:
        _loaded = _unavailable = None
    if _loaded is not None or _unavailable is not None:
        return _loaded
    from amlip_qp.codegen.runtime import CodegenFallbackWarning, compile_library

    source = resources.files("amlip_qp.codegen").joinpath("daqp_step.c").read_bytes()
    try:
        path = compile_library(source, SOURCE_FILE, LIBRARY_FILE, cache_dir)
    except CompilerUnavailableError as exc:
        _unavailable = str(exc)
        warnings.warn(
            f"the small QP's compiled step is unavailable ({exc}): its Python path solves it (the same solutions)",
            CodegenFallbackWarning,
            stacklevel=2,
        )
        return None
    _loaded = DAQPStep(ctypes.CDLL(str(path)))
    return _loaded
