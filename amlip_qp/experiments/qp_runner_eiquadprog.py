"""eiquadprog-fast, the QP solver of TSID, in ``amlip-qp bench qp``: a compiled C++ shim over its library.

The ``eiquadprog`` wheel on PyPI ships the C++ library (``libeiquadprog.so``) and its headers,
and no Python binding. :func:`load_shim` compiles ``eiquadprog_shim.cpp`` (beside this module)
once into the codegen cache (:func:`~amlip_qp.codegen.runtime.compile_library`, with ``-x c++``,
the Eigen headers CasADi ships and the wheel's own headers, linked against its library) and loads
it with :mod:`ctypes`: a workspace (``EiquadprogFast`` and its Eigen matrices) and one solve call.

:class:`EiquadprogRunner` solves the bench's recorded problems with it the way TSID's
``SolverHQuadProgFast`` does: the matrices copied into the solver's Eigen matrices, then
``solve_quadprog`` from the unconstrained optimum (Goldfarb-Idnani's dual method has no warm
start). The copy is timed with the solve. :meth:`EiquadprogRunner.prepare` (untimed) writes each
problem in eiquadprog's form, ``CE x + ce0 = 0`` and ``CI x + ci0 >= 0``: the equalities and the
fixed variables (``lb == ub``) as equality rows, each finite side of a row or a bound as one
inequality row.

:func:`unusable` says why the solver cannot run here (the wheel not installed, no C++ compiler,
no Eigen headers), or ``None``.
"""

from __future__ import annotations

import ctypes
import functools
import os
from importlib import metadata, resources
from pathlib import Path

import numpy as np

from amlip_qp.exceptions import CodegenError
from amlip_qp.experiments.qp_runners import Runner
from amlip_qp.qp.problem import QPProblem

#: The shim's source (package data beside this module) and its names in the codegen cache.
SHIM_SOURCE = "eiquadprog_shim.cpp"
LIBRARY_FILE = "libamlip_eiquadprog.so"
#: eiquadprog-fast's status codes (``EiquadprogFast_status``). Its dual method finds an infeasible
#: problem's dual unbounded: such a problem returns 2, not 1.
STATUS = {
    0: "optimal",
    1: "infeasible",
    2: "dual unbounded (infeasible)",
    3: "iteration limit",
    4: "redundant equalities",
}


def _wheel_folders() -> tuple[Path, Path]:
    """``(include folder, library folder)`` of the installed ``eiquadprog`` wheel.

    Raises:
        metadata.PackageNotFoundError: the wheel is not installed.
        FileNotFoundError: it is, without its library or headers.
    """
    dist = metadata.distribution("eiquadprog")
    for entry in dist.files or ():
        if entry.name == "libeiquadprog.so":
            lib = Path(str(dist.locate_file(entry))).parent
            include = lib.parent / "include"
            if (include / "eiquadprog" / "eiquadprog-fast.hpp").is_file() and (lib / entry.name).is_file():
                return include, lib
    raise FileNotFoundError("the eiquadprog wheel has no libeiquadprog.so with its headers")


def _eigen_folder() -> Path:
    """The Eigen headers CasADi ships (``casadi/include/eigen3``).

    Raises:
        FileNotFoundError: CasADi has none.
    """
    import casadi

    folder = Path(casadi.__file__).parent / "include" / "eigen3"
    if not (folder / "Eigen" / "Dense").is_file():
        raise FileNotFoundError(f"no Eigen headers in {folder}")
    return folder


def _flags() -> tuple[list[str], list[str]]:
    """The shim's compile and link flags."""
    include, lib = _wheel_folders()
    compile_flags = ["-x", "c++", "-std=c++14", "-I", str(_eigen_folder()), "-I", str(include)]
    return compile_flags, ["-L", str(lib), "-leiquadprog", f"-Wl,-rpath,{lib}", "-lstdc++"]


def installed() -> bool:
    """Whether the ``eiquadprog`` wheel is installed with its library and headers."""
    try:
        _wheel_folders()
    except (metadata.PackageNotFoundError, FileNotFoundError):
        return False
    return True


def unusable() -> str | None:
    """Why the bench cannot run eiquadprog here (one phrase), or ``None`` when it can: the shim
    compiles (once, into the codegen cache) and loads."""
    try:
        load_shim()
    except (metadata.PackageNotFoundError, FileNotFoundError, OSError, CodegenError) as exc:
        return str(exc).splitlines()[0] or type(exc).__name__
    return None


@functools.cache
def load_shim(cache_dir: str | os.PathLike | None = None) -> ctypes.CDLL:
    """The compiled shim, loaded (once per process and cache folder).

    Raises:
        metadata.PackageNotFoundError: the ``eiquadprog`` wheel is not installed.
        FileNotFoundError: its library or headers, or CasADi's Eigen headers, are missing.
        CompilerUnavailableError: no C compiler (:mod:`amlip_qp.codegen.runtime`).
        CodegenError: the compiler rejected the shim.
        OSError: the library does not load.
    """
    from amlip_qp.codegen.runtime import compile_library

    compile_flags, link_flags = _flags()
    source = resources.files("amlip_qp.experiments").joinpath(SHIM_SOURCE).read_bytes()
    path = compile_library(
        source, SHIM_SOURCE, LIBRARY_FILE, cache_dir, compile_flags=compile_flags, link_flags=link_flags
    )
    lib = ctypes.CDLL(str(path))
    pointer, count = ctypes.c_void_p, ctypes.c_int
    lib.amlip_eiquadprog_new.restype = pointer
    lib.amlip_eiquadprog_new.argtypes = []
    lib.amlip_eiquadprog_free.restype = None
    lib.amlip_eiquadprog_free.argtypes = [pointer]
    lib.amlip_eiquadprog_solve.restype = count
    lib.amlip_eiquadprog_solve.argtypes = [pointer, count, count, count, *([pointer] * 7), ctypes.POINTER(count)]
    return lib


def eiquadprog_form(p: QPProblem) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``(H, g, CE, ce0, CI, ci0)`` of ``p`` in eiquadprog's form (module doc), each C-contiguous."""
    eye = np.eye(p.n)
    fixed = p.lb == p.ub
    fl, fu = np.isfinite(p.l), np.isfinite(p.u)
    bl, bu = np.isfinite(p.lb) & ~fixed, np.isfinite(p.ub) & ~fixed
    CE = np.vstack([p.A, eye[fixed]])
    ce0 = -np.concatenate([p.b, p.lb[fixed]])
    CI = np.vstack([p.C[fl], -p.C[fu], eye[bl], -eye[bu]])
    ci0 = np.concatenate([-p.l[fl], p.u[fu], -p.lb[bl], p.ub[bu]])
    c = np.ascontiguousarray
    return c(p.H, dtype=float), c(p.g, dtype=float), c(CE), c(ce0), c(CI), c(ci0)


class EiquadprogRunner(Runner):
    """eiquadprog-fast through the compiled shim (module doc): one workspace kept, each problem's
    matrices copied into it and solved from the unconstrained optimum."""

    name = "eiquadprog"
    start = "none: Goldfarb-Idnani starts from the unconstrained optimum (TSID's use)"
    timed = "the matrices copied into eiquadprog's Eigen workspace + EiquadprogFast::solve_quadprog"

    def __init__(self) -> None:
        super().__init__()
        self._lib = load_shim()
        workspace = self._lib.amlip_eiquadprog_new()
        if not workspace:
            raise MemoryError("eiquadprog: no memory for a workspace")
        self._workspace: ctypes.c_void_p | None = ctypes.c_void_p(workspace)
        self._iterations = ctypes.c_int(0)
        #: Statuses other than optimal, by name, counted over the solves.
        self.statuses: dict[str, int] = {}

    def __del__(self) -> None:
        workspace = getattr(self, "_workspace", None)
        self._workspace = None
        if workspace is not None and workspace.value:
            self._lib.amlip_eiquadprog_free(workspace)

    def prepare(self, p: QPProblem) -> tuple:
        H, g, CE, ce0, CI, ci0 = eiquadprog_form(p)
        return p.n, CE.shape[0], CI.shape[0], H, g, CE, ce0, CI, ci0

    def solve(self, data: tuple) -> np.ndarray | None:
        n, n_eq, n_in, H, g, CE, ce0, CI, ci0 = data
        x = np.empty(n)
        status = self._lib.amlip_eiquadprog_solve(
            self._workspace, n, n_eq, n_in, H.ctypes.data, g.ctypes.data, CE.ctypes.data, ce0.ctypes.data,
            CI.ctypes.data, ci0.ctypes.data, x.ctypes.data, ctypes.byref(self._iterations),
        )  # fmt: skip
        if status != 0:
            what = STATUS.get(status, f"status {status}")
            self.statuses[what] = self.statuses.get(what, 0) + 1
            self.failures += 1
            return None
        return x

    @property
    def iterations(self) -> int:
        """The active-set iterations of the last solve."""
        return int(self._iterations.value)
