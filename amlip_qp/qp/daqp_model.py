"""One DAQP workspace, set up once and hot-started, driven through DAQP's C API.

DAQP's Python package exposes a workspace as ``daqp.Model`` (``setup``, ``update``,
``solve``); each call builds Python objects around a few microseconds of solver work
(``update`` copies nothing but checks its arguments, ``solve`` returns fresh copies of
``x`` and of the multipliers in a dict). The library inside that package also exports
DAQP's C functions. :func:`make_model` returns a :class:`CModel` that calls them through
:mod:`ctypes` on arrays the caller owns: ``setup_daqp``, then ``daqp_update_ldp`` with
the mask ``daqp.Model.update`` uses for ``H, f, A, bupper, blower``, then ``daqp_solve``.
It is the same sequence of C calls as ``daqp.Model``'s on the same arrays, so the
solutions are the same bits (``tests/test_qp_daqp_model.py`` checks this on random
problem sequences with soft rows and equalities).

The C structures' layouts are those of the daqp release listed in
:data:`VERIFIED_VERSIONS`; with any other installed version, or when the layout
checks at load fail, :func:`make_model` returns a :class:`PyModel` (``daqp.Model``
behind the same three methods: the same solutions, slower) and one
:class:`DAQPModelFallbackWarning` per process says why.

Both models hold pointers to the arrays handed to :meth:`~CModel.setup` and
:meth:`~CModel.update` (C-contiguous float64, ``sense`` int32): the caller keeps those
arrays alive and unmoved, and writes new data into them before each ``update``.
"""

from __future__ import annotations

import ctypes
import importlib.metadata
import struct
import warnings
from dataclasses import dataclass
from typing import Any

import numpy as np

#: daqp releases whose C structures this module's layout matches (checked at load too).
VERIFIED_VERSIONS = ("0.11.0",)
#: ``daqp_update_ldp``'s mask for new ``H`` (1), ``A`` (2), ``f`` (4) and bounds (8): ``daqp.Model.update``'s.
UPDATE_ALL = 1 | 2 | 4 | 8
# Bytes reserved for DAQP's workspace and result structures (larger than either: DAQP writes only its own fields).
_WORK_BYTES = 4096
_RESULT_BYTES = 256
# DAQPSettings: 5 doubles (primal_tol first), cycle_tol and iter_limit (ints), then doubles.
_SETTINGS_CHECK_BYTES = 136
_OFFSET_PRIMAL_TOL, _OFFSET_ITER_LIMIT = 0, 44
# DAQPResult: x, lam (pointers), fval, soft_slack (doubles), exitflag, iter (ints).
_OFFSET_EXITFLAG, _OFFSET_ITERATIONS = 32, 36


@dataclass(frozen=True)
class CHandles:
    """What compiled code needs to drive a :class:`CModel`'s workspace itself (addresses as ints):
    DAQP's ``daqp_update_ldp`` and ``daqp_solve``, the workspace, problem and result structures,
    the mask :meth:`CModel.update` passes, and the exit flag's byte offset in the result."""

    update_fn: int
    solve_fn: int
    work: int
    problem: int
    result: int
    update_mask: int
    exitflag_offset: int
    #: The model these addresses belong to: whoever keeps the addresses keeps it alive.
    owner: Any = None


class DAQPModelFallbackWarning(RuntimeWarning):
    """DAQP's C API is not used (module doc): the solves go through ``daqp.Model``, same solutions, slower."""


class _Problem(ctypes.Structure):
    """DAQP's ``DAQPProblem``: dense row-major ``H`` and ``A``; the bounds of ``x`` first in ``bupper``, ``blower``."""

    _fields_ = [
        ("n", ctypes.c_int),
        ("m", ctypes.c_int),
        ("ms", ctypes.c_int),
        ("H", ctypes.c_void_p),
        ("f", ctypes.c_void_p),
        ("A", ctypes.c_void_p),
        ("bupper", ctypes.c_void_p),
        ("blower", ctypes.c_void_p),
        ("sense", ctypes.c_void_p),
        ("break_points", ctypes.c_void_p),
        ("nh", ctypes.c_int),
        ("problem_type", ctypes.c_int),
        ("_reserved", ctypes.c_char * 64),
    ]


def _address(a: np.ndarray) -> int:
    return a.__array_interface__["data"][0]


class _Library:
    """The C functions and the settings pointer's offset in a workspace, found and checked once."""

    def __init__(self, daqp_module: Any):
        lib = ctypes.CDLL(daqp_module.__file__)
        vp = ctypes.c_void_p
        self.setup = lib.setup_daqp
        self.setup.argtypes, self.setup.restype = [vp, vp, vp], ctypes.c_int
        self.update = lib.daqp_update_ldp
        self.update.argtypes, self.update.restype = [ctypes.c_int, vp, vp], ctypes.c_int
        self.solve = lib.daqp_solve
        self.solve.argtypes, self.solve.restype = [vp, vp], None
        self.free_workspace = lib.free_daqp_workspace
        self.free_workspace.argtypes, self.free_workspace.restype = [vp], None
        self.free_ldp = lib.free_daqp_ldp
        self.free_ldp.argtypes, self.free_ldp.restype = [vp], None
        # the settings pointer: the one word allocate_daqp_settings writes in a zeroed workspace,
        # pointing at daqp_default_settings' values
        allocate, defaults = lib.allocate_daqp_settings, lib.daqp_default_settings
        allocate.argtypes, defaults.argtypes = [vp], [vp]
        work = ctypes.create_string_buffer(_WORK_BYTES)
        allocate(work)
        words = np.frombuffer(work.raw, dtype=np.uint64)
        set_words = np.flatnonzero(words)
        expected = ctypes.create_string_buffer(_SETTINGS_CHECK_BYTES + 64)
        defaults(expected)
        if len(set_words) != 1:
            raise RuntimeError(f"allocate_daqp_settings wrote {len(set_words)} words of a workspace, expected 1")
        address = int(words[set_words[0]])
        if ctypes.string_at(address, _SETTINGS_CHECK_BYTES) != expected.raw[:_SETTINGS_CHECK_BYTES]:
            raise RuntimeError("the workspace's settings differ from daqp_default_settings'")
        (primal_tol,) = struct.unpack_from("d", expected, _OFFSET_PRIMAL_TOL)
        if primal_tol != 1e-6:
            raise RuntimeError(f"DAQPSettings.primal_tol reads {primal_tol!r}, expected DAQP's default 1e-6")
        self.settings_offset = int(set_words[0]) * 8
        ctypes.memset(work, 0, _WORK_BYTES)  # the settings struct leaks once per process (a few hundred bytes)


class CModel:
    """A DAQP workspace through the C API (module doc): :meth:`setup`, then :meth:`update` and
    :meth:`solve` per problem. ``n`` variables, ``m`` bounds and rows in all, the first ``ms``
    the bounds of ``x``; :attr:`x` holds the last solution (overwritten by the next solve),
    :attr:`iterations` its count of working-set changes."""

    def __init__(self, library: _Library, n: int, m: int, ms: int):
        self._lib = library
        self._problem = _Problem(n=n, m=m, ms=ms)
        self._work = ctypes.create_string_buffer(_WORK_BYTES)
        self._result = ctypes.create_string_buffer(_RESULT_BYTES)
        self.x = np.zeros(n)
        self._lam = np.zeros(m + n + 2)
        struct.pack_into("PP", self._result, 0, _address(self.x), _address(self._lam))
        self._arrays: tuple = ()
        self._sense: np.ndarray | None = None
        self._set_up = False
        self._pw = ctypes.addressof(self._work)
        self._pp = ctypes.addressof(self._problem)
        self._pr = ctypes.addressof(self._result)

    def _point(self, arrays: tuple) -> None:
        """Point the problem at ``(H, f, A, bupper, blower)`` (a no-op for the arrays of last time)."""
        last = self._arrays
        if len(last) == 5 and all(a is b for a, b in zip(arrays, last, strict=True)):
            return
        for a in arrays:
            if a.dtype != np.float64 or not a.flags.c_contiguous:
                raise ValueError(f"DAQP's arrays must be C-contiguous float64, got {a.dtype} {a.shape}")
        H, f, A, bupper, blower = arrays
        p = self._problem
        p.H, p.f, p.A = _address(H), _address(f), _address(A) if A.size else None
        p.bupper, p.blower = _address(bupper), _address(blower)
        self._arrays = arrays

    def setup(self, H, f, A, bupper, blower, sense) -> int:
        """Set the workspace up (once); returns DAQP's set-up code (< 0: failed)."""
        if self._set_up:
            raise RuntimeError("CModel.setup called twice: make a new model")
        if sense.dtype != np.intc or not sense.flags.c_contiguous:
            raise ValueError(f"DAQP's sense must be a C-contiguous int32 array, got {sense.dtype}")
        self._point((H, f, A, bupper, blower))
        self._sense = sense
        self._problem.sense = _address(sense)
        setup_time = ctypes.c_double(0.0)
        code = int(self._lib.setup(self._pp, self._pw, ctypes.addressof(setup_time)))
        self._set_up = code >= 0
        return code

    def set_settings(self, iter_limit: int, primal_tol: float) -> None:
        """DAQP's ``iter_limit`` and ``primal_tol`` settings (the others stay DAQP's defaults); a no-op
        before a successful :meth:`setup` (a failed one leaves no settings), as ``daqp.Model``'s."""
        if not self._set_up:
            return
        (address,) = struct.unpack_from("P", self._work, self._lib.settings_offset)
        if not address:
            return
        settings = (ctypes.c_char * _SETTINGS_CHECK_BYTES).from_address(address)
        struct.pack_into("i", settings, _OFFSET_ITER_LIMIT, int(iter_limit))
        struct.pack_into("d", settings, _OFFSET_PRIMAL_TOL, float(primal_tol))

    def update(self, H, f, A, bupper, blower) -> int:
        """New data (in the arrays last given, or in new ones of the same shapes); returns DAQP's code."""
        if not self._set_up:
            raise RuntimeError("CModel.update before a successful setup")
        self._point((H, f, A, bupper, blower))
        return int(self._lib.update(UPDATE_ALL, self._pw, self._pp))

    def solve(self) -> int:
        """Solve from the last working set; returns DAQP's exit flag (1, 2: solved). Solution in :attr:`x`."""
        if not self._set_up:
            raise RuntimeError("CModel.solve before a successful setup")
        self._lib.solve(self._pr, self._pw)
        return struct.unpack_from("i", self._result, _OFFSET_EXITFLAG)[0]

    def c_handles(self) -> CHandles:
        """The addresses compiled code needs to update and solve this workspace (:class:`CHandles`);
        valid while this model lives, once :meth:`setup` succeeded."""
        if not self._set_up:
            raise RuntimeError("CModel.c_handles before a successful setup")
        lib = self._lib
        address = ctypes.cast(lib.update, ctypes.c_void_p).value, ctypes.cast(lib.solve, ctypes.c_void_p).value
        return CHandles(
            int(address[0] or 0), int(address[1] or 0), self._pw, self._pp, self._pr, UPDATE_ALL, _OFFSET_EXITFLAG, self
        )

    @property
    def iterations(self) -> int:
        """The last solve's iterations (DAQP's count)."""
        return struct.unpack_from("i", self._result, _OFFSET_ITERATIONS)[0]

    def __reduce__(self):
        raise TypeError("a CModel holds pointers into this process's memory and cannot be pickled; make a new one")

    def __del__(self):
        if getattr(self, "_set_up", False):
            self._set_up = False
            self._lib.free_workspace(self._pw)
            self._lib.free_ldp(self._pw)


class PyModel:
    """``daqp.Model`` behind :class:`CModel`'s methods (the fallback of :func:`make_model`)."""

    def __init__(self, daqp_module: Any, n: int, m: int, ms: int):
        self._model = daqp_module.Model()
        self.x = np.zeros(n)
        self.iterations = 0

    def setup(self, H, f, A, bupper, blower, sense) -> int:
        return int(self._model.setup(H, f, A, bupper, blower, sense)[0])

    def set_settings(self, iter_limit: int, primal_tol: float) -> None:
        self._model.settings = {"iter_limit": int(iter_limit), "primal_tol": float(primal_tol)}

    def update(self, H, f, A, bupper, blower) -> int:
        return int(self._model.update(H=H, f=f, A=A, bupper=bupper, blower=blower))

    def solve(self) -> int:
        x, _, flag, info = self._model.solve()
        self.x, self.iterations = x, int(info.get("iterations", 0))
        return int(flag)


_library: _Library | None = None
_fallback_reason: str | None = None


def c_api_status(refresh: bool = False) -> str | None:
    """``None`` when :func:`make_model` uses DAQP's C API, else why not (loaded on the first call;
    ``refresh``: forget that and load again, warning again if it falls back)."""
    global _library, _fallback_reason
    if refresh:
        _library = _fallback_reason = None
    _load()
    return _fallback_reason


def _load() -> _Library | None:
    global _library, _fallback_reason
    if _library is not None or _fallback_reason is not None:
        return _library
    import daqp

    version = importlib.metadata.version("daqp")
    if version not in VERIFIED_VERSIONS:
        verified = ", ".join(VERIFIED_VERSIONS)
        _fallback_reason = f"daqp {version} is not a release whose C layout was verified ({verified})"
    else:
        try:
            _library = _Library(daqp)
        except (OSError, AttributeError, RuntimeError) as exc:
            _fallback_reason = f"daqp's C API did not load ({exc})"
    if _fallback_reason is not None:
        warnings.warn(
            f"{_fallback_reason}: DAQP solves go through daqp.Model (the same solutions, a few µs slower each)",
            DAQPModelFallbackWarning,
            stacklevel=3,
        )
    return _library


def make_model(n: int, m: int, ms: int, use_c_api: bool = True) -> CModel | PyModel:
    """A DAQP model for ``n`` variables and ``m`` constraints, the first ``ms`` the bounds of ``x``:
    a :class:`CModel` when DAQP's C API loads (module doc), else (or with ``use_c_api=False``) a
    :class:`PyModel`."""
    library = _load() if use_c_api else None
    if library is not None:
        return CModel(library, n, m, ms)
    import daqp

    return PyModel(daqp, n, m, ms)
