"""The planner kernels, compiled once and called with microsecond overhead.

Use::

    from amlip_qp.codegen import load_kernels

    kernels = load_kernels()          # compiles on first use, then cached
    y = kernels.alip_plan(u16)        # 16 inputs -> 8 outputs
    h = kernels.swing_reference(u15)  # 15 inputs -> 30 outputs
    q = kernels.alip_mpc_qp(u62)      # the step-timing MPC's QP: 62 inputs -> 568 outputs
    kernels.backend                   # "c" (compiled) or "casadi" (fallback)

Layouts and units are those of :mod:`amlip_qp.alip.kernels`. The library is
built from the committed (or regenerated) source by
:func:`~amlip_qp.codegen.runtime.compile_and_load` (module
:mod:`amlip_qp.codegen.runtime`: source, compiler, cache). Without a C
compiler the kernels are evaluated by the CasADi SX Functions (backend
``"casadi"``: same numbers, a few times slower) and exactly one
:class:`~amlip_qp.codegen.runtime.CodegenFallbackWarning` says so and why.

**Fast path.** The compiled functions are loaded with ``casadi.external`` and
evaluated through ``Function.buffer()``, bound once to preallocated numpy
input and output arrays (measured faster than ctypes on the same library:
~0.13 µs versus ~0.6 µs for the bare call). A call copies ``u`` into the
input array, evaluates, and returns the output array.
"""

from __future__ import annotations

import ctypes
import os
import warnings
from dataclasses import dataclass
from pathlib import Path

import casadi as ca
import numpy as np

from amlip_qp.codegen import runtime, symbolic
from amlip_qp.codegen.runtime import CodegenFallbackWarning
from amlip_qp.exceptions import CodegenError, CompilerUnavailableError, InputError
from amlip_qp.paths import CODEGEN_DIR


def _check_kernel_signatures(functions: dict[str, ca.Function], lib: Path) -> None:
    """Raise :class:`CodegenError` if a loaded kernel's sizes differ from its spec."""
    for kernel in symbolic.KERNEL_SPECS:
        fn = functions[kernel.name]
        if fn.n_in() != 1 or fn.n_out() != 1 or fn.nnz_in(0) != kernel.n_in or fn.nnz_out(0) != kernel.n_out:
            raise CodegenError(f"{lib}: {kernel.name} has the wrong signature; delete {lib.parent} to rebuild")


class FastFunction:
    """One kernel, callable as ``y = f(u)`` with preallocated buffers.

    ``u`` must be a 1-D array-like of ``n_in`` numbers (SI units, layout in
    :mod:`amlip_qp.alip.kernels`); anything else raises
    :class:`~amlip_qp.exceptions.InputError`. NaN checks are the caller's job.

    The return value is this object's preallocated, **read-only output array
    of shape** ``(n_out,)``: the same array on every call, overwritten by the
    next call. Copy it (``y.copy()``) to keep a result across calls. One
    instance is not thread-safe; give each thread its own :class:`Kernels`.

    Attributes:
        name: ``"alip_plan"`` or ``"swing_reference"``.
        n_in, n_out: dense input and output sizes.
        backend: ``"c"`` (compiled library) or ``"casadi"`` (SX fallback).
        function: the underlying ``casadi.Function``.
    """

    __slots__ = ("name", "n_in", "n_out", "backend", "function", "input_names",
                 "_u", "_y", "_buffer", "_eval", "_shape")  # fmt: skip

    def __init__(self, function: ca.Function, kernel: symbolic.KernelSpec, backend: str):
        self.name = kernel.name
        self.n_in = kernel.n_in
        self.n_out = kernel.n_out
        self.input_names = kernel.input_names
        self.backend = backend
        self.function = function
        self._shape = (kernel.n_in,)
        self._u = np.zeros(kernel.n_in)
        self._y = np.zeros(kernel.n_out)
        self._buffer, self._eval = function.buffer()
        # Stub limits: casadi's FunctionBuffer.set_arg/set_res stubs demand a size (the binding takes
        # it from the buffer); numpy's stubs declare ndarray a Buffer only for Python >= 3.12.
        self._buffer.set_arg(0, memoryview(self._u))  # type: ignore[call-arg, arg-type]
        self._buffer.set_res(0, memoryview(self._y))  # type: ignore[call-arg, arg-type]
        self._y.flags.writeable = False

    def __call__(self, u: np.ndarray) -> np.ndarray:
        """Evaluate on ``u`` (shape ``(n_in,)``); return the shared output array (see class doc)."""
        if type(u) is not np.ndarray or u.shape != self._shape:
            u = self._coerce(u)
        try:
            self._u[:] = u
        except (TypeError, ValueError) as exc:
            raise InputError(f"{self.name}: inputs must be {self.n_in} real numbers ({exc})") from None
        self._eval()
        return self._y

    def _coerce(self, u) -> np.ndarray:
        try:
            arr = np.asarray(u, dtype=float)
        except (TypeError, ValueError) as exc:
            raise InputError(f"{self.name}: inputs must be {self.n_in} real numbers ({exc})") from None
        if arr.shape != self._shape:
            raise InputError(
                f"{self.name} expects a 1-D array of {self.n_in} inputs "
                f"({', '.join(self.input_names)}), got shape {arr.shape}; pass an array of shape ({self.n_in},)"
            )
        return arr

    def __repr__(self) -> str:
        return f"FastFunction({self.name!r}, {self.n_in}->{self.n_out}, backend={self.backend!r})"


@dataclass(frozen=True)
class CKernel:
    """A compiled kernel's C entry point, for compiled code that calls it itself (addresses as ints).

    ``function`` is CasADi's ``int name(const double** arg, double** res, long long* iw, double* w,
    int mem)``, writing its one dense output from its one dense input; ``sz_arg``, ``sz_res``,
    ``sz_iw``, ``sz_w`` are the work sizes its ``name_work`` reports."""

    name: str
    function: int
    n_in: int
    n_out: int
    sz_arg: int
    sz_res: int
    sz_iw: int
    sz_w: int


class Kernels:
    """The planner kernels, compiled (backend ``"c"``) or on CasADi (``"casadi"``).

    Attributes:
        alip_plan: :class:`FastFunction` ``u[16] -> y[8]``.
        swing_reference: :class:`FastFunction` ``u[15] -> y[30]``.
        alip_mpc_qp: :class:`FastFunction` ``u[62] -> y[568]``, the step-timing MPC's QP
            (:mod:`amlip_qp.alip.step_mpc`).
        backend: ``"c"`` or ``"casadi"``.
        library_path: the compiled library, or ``None`` on the fallback.
        fallback_reason: why the fallback is used, or ``None``.

    Args:
        cache_dir: overrides :func:`~amlip_qp.codegen.runtime.cache_root` for the compiled library.
        committed_dir: the folder of committed sources to check (default
            :data:`amlip_qp.paths.CODEGEN_DIR`).
    """

    def __init__(self, cache_dir: str | os.PathLike | None = None, committed_dir: str | os.PathLike = CODEGEN_DIR):
        self.library_path: Path | None = None
        self.fallback_reason: str | None = None
        source = runtime.library_source(Path(committed_dir))
        try:
            self.library_path, functions = runtime.compile_and_load(source, symbolic.KERNEL_NAMES, cache_dir=cache_dir)
            _check_kernel_signatures(functions, self.library_path)
            self.backend = "c"
        except CompilerUnavailableError as exc:
            self.fallback_reason = str(exc)
            warnings.warn(
                f"amlip_qp.codegen: no C compiler: {self.fallback_reason}; evaluating the planner kernels "
                "with CasADi SX Functions instead of the generated C (same results, slower)",
                CodegenFallbackWarning,
                stacklevel=2,
            )
            functions, self.backend = symbolic.functions(), "casadi"
        self.alip_plan = FastFunction(functions["alip_plan"], symbolic.spec("alip_plan"), self.backend)
        self.swing_reference = FastFunction(
            functions["swing_reference"], symbolic.spec("swing_reference"), self.backend
        )
        self.alip_mpc_qp = FastFunction(functions["alip_mpc_qp"], symbolic.spec("alip_mpc_qp"), self.backend)

    def c_kernel(self, name: str) -> CKernel | None:
        """The compiled kernel ``name``'s C entry point (:class:`CKernel`), ``None`` on the CasADi backend."""
        kernel = self[name]
        if self.library_path is None:
            return None
        lib = ctypes.CDLL(str(self.library_path))
        sizes = [ctypes.c_longlong(0) for _ in range(4)]
        getattr(lib, f"{name}_work")(*(ctypes.byref(v) for v in sizes))
        address = ctypes.cast(getattr(lib, name), ctypes.c_void_p).value
        return CKernel(name, int(address or 0), kernel.n_in, kernel.n_out, *(int(v.value) for v in sizes))

    def __getitem__(self, name: str) -> FastFunction:
        """The kernel called ``name`` (one of ``symbolic.KERNEL_NAMES``)."""
        if name not in symbolic.KERNEL_NAMES:
            raise KeyError(f"unknown kernel {name!r}; expected one of {symbolic.KERNEL_NAMES}")
        return getattr(self, name)

    def __repr__(self) -> str:
        where = self.library_path if self.library_path is not None else self.fallback_reason
        return f"Kernels(backend={self.backend!r}, {where})"


def load_kernels(cache_dir: str | os.PathLike | None = None) -> Kernels:
    """Return a new :class:`Kernels` (compiling on first use; see the module doc)."""
    return Kernels(cache_dir=cache_dir)
