"""Compile generated C once into a per-user cache and load its functions.

The planner kernels are called through :mod:`amlip_qp.codegen.kernels`
(:func:`~amlip_qp.codegen.kernels.load_kernels`), which uses this module.

**Library.** The C source is ``generate.generate_files()``, i.e. the bytes of
the committed ``amlip_qp/codegen/generated/amlip_kernels.c`` (package data)
when that file is current (it is regenerated in memory, ~10 ms, and compared;
a stale committed file triggers a :class:`CodegenStaleWarning` and the fresh
source is used, a missing one is silently replaced by the fresh source).

**Compiling and binding.** :func:`compile_and_load` is the one way amlip_qp
turns generated C into callable functions (the planner kernels here, the
whole-body QP assembly and the output map in :mod:`amlip_qp.control`). It
compiles with the system C compiler (``-O2 -fPIC -shared
-ffp-contract=off``) into ``<cache>/<key>/<library>.so`` where ``<key>`` is
the SHA-256 of the source, the compiler command and the flags, and
``<cache>`` is ``$AMLIP_QP_CACHE_DIR``, else ``$XDG_CACHE_HOME/amlip_qp``,
else ``~/.cache/amlip_qp``, then loads the named functions with
``casadi.external``. The build writes a temporary file and renames it, so
parallel processes never load a half-written library. The first compilation
of a process into a cache folder says so in one line on stderr (a cold cache
costs seconds once; later runs reuse the libraries silently).

**Compiler.** ``$AMLIP_QP_CC`` (a command, e.g. ``"gcc"``; the value
``none`` means "no compiler"), else ``$CC``, else ``cc``, else ``gcc`` on the
``PATH``. Without one, :func:`compile_and_load` raises
:class:`~amlip_qp.exceptions.CompilerUnavailableError`; the callers fall back
to CasADi (the planner kernels: backend ``"casadi"``, same numbers, a few
times slower) and exactly one :class:`CodegenFallbackWarning` says so and why.
A compiler that rejects the source raises
:class:`~amlip_qp.exceptions.CodegenError` with its message.
"""

from __future__ import annotations

import hashlib
import os
import platform
import shlex
import shutil
import subprocess
import sys
import tempfile
import warnings
from collections.abc import Sequence
from pathlib import Path

import casadi as ca
import numpy as np

from amlip_qp.codegen import generate
from amlip_qp.exceptions import CodegenError, CompilerUnavailableError
from amlip_qp.paths import CACHE_ENV, CODEGEN_DIR, cache_root

#: Environment variable: cache folder for compiled libraries.
#: Environment variable: C compiler command; ``none`` disables compilation.
COMPILER_ENV = "AMLIP_QP_CC"
#: Compiler flags (``-ffp-contract=off`` keeps a*b+c unfused, as in numpy).
CFLAGS = ("-O2", "-fPIC", "-shared", "-ffp-contract=off")
#: File name of the compiled library inside its cache folder.
LIBRARY_FILE = f"lib{generate.LIBRARY_NAME}.so"
#: Seconds before a compilation is abandoned.
COMPILE_TIMEOUT_S = 300
#: Seconds a cold cache costs once, at most about: a walk compiles the
#: kernels, the output map and the QP assembly (measured with gcc 12 for a
#: Cassie QP walk: 0.2 + 1.0 + 12.9 s of CPU time; Rabbit's are smaller).
COLD_COMPILE_S = 15

# Cache folders whose first compilation this process has announced on stderr.
_announced_roots: set[Path] = set()


class CodegenFallbackWarning(RuntimeWarning):
    """The compiled C is unavailable; the kernels run on CasADi SX Functions."""


class CodegenStaleWarning(UserWarning):
    """The committed ``amlip_qp/codegen/generated/`` sources differ from the symbolic definitions."""


class _NoCompiler(Exception):
    """Internal: no usable C compiler (the message says why)."""


# --- locations ---------------------------------------------------------------


def find_compiler() -> list[str]:
    """Return the C compiler command as a list; raise ``_NoCompiler`` with the reason."""
    for env in (COMPILER_ENV, "CC"):
        value = os.environ.get(env, "").strip()
        if not value:
            continue
        if env == COMPILER_ENV and value.lower() == "none":
            raise _NoCompiler(f"{COMPILER_ENV}=none disables the C compiler")
        cmd = shlex.split(value)
        if shutil.which(cmd[0]) is None:
            raise _NoCompiler(f"the compiler {cmd[0]!r} named by ${env} is not on the PATH")
        return cmd
    for name in ("cc", "gcc"):
        path = shutil.which(name)
        if path is not None:
            return [name]
    raise _NoCompiler("neither 'cc' nor 'gcc' is on the PATH (set $AMLIP_QP_CC to a C compiler)")


def require_compiler() -> list[str]:
    """The C compiler command, as :func:`find_compiler` finds it.

    For callers that want to fail before spending seconds generating code.

    Raises:
        CompilerUnavailableError: No usable C compiler (the message says why).
    """
    try:
        return find_compiler()
    except _NoCompiler as exc:
        raise CompilerUnavailableError(str(exc)) from None


def library_source(committed_dir: Path = CODEGEN_DIR) -> bytes:
    """The C source to compile: the fresh generation, checked against ``committed_dir``.

    Warns :class:`CodegenStaleWarning` when the committed files exist but differ.
    """
    files = generate.generate_files()
    if (committed_dir / generate.SOURCE_FILE).is_file():
        stale = generate.stale_files(committed_dir, files)
        if stale:
            names = ", ".join(f"{name} ({state})" for name, state in stale)
            warnings.warn(
                f"{committed_dir} is stale: {names}; using freshly generated sources "
                "(run 'amlip-qp codegen' and commit the result)",
                CodegenStaleWarning,
                stacklevel=3,
            )
    return files[generate.SOURCE_FILE]


def cache_key(source: bytes, compiler: Sequence[str], flags: Sequence[str] = CFLAGS) -> str:
    """SHA-256 (hex) of the source, the compiler command, the flags and the
    platform (OS and CPU architecture: a cache folder may be shared between machines)."""
    h = hashlib.sha256()
    h.update(source)
    for part in (" ".join(compiler), " ".join(flags), f"{sys.platform}-{platform.machine()}"):
        h.update(b"\0" + part.encode("utf-8"))
    return h.hexdigest()


# --- compilation ---------------------------------------------------------------


def _key_flags(compile_flags: Sequence[str], link_flags: Sequence[str]) -> tuple[str, ...]:
    """The flags a cache key hashes: :data:`CFLAGS`, then any extra compile and link flags."""
    return (*CFLAGS, *compile_flags, "|", *link_flags) if compile_flags or link_flags else CFLAGS


def build_library(
    source: bytes,
    compiler: Sequence[str],
    cache_dir: Path | None = None,
    source_file: str = generate.SOURCE_FILE,
    library_file: str = LIBRARY_FILE,
    compile_flags: Sequence[str] = (),
    link_flags: Sequence[str] = (),
) -> Path:
    """Compile ``source`` into ``<cache>/<key>/<library_file>`` unless it is there.

    ``source_file`` and ``library_file`` name the files in the cache folder
    (default: the planner kernels'; other generated code, e.g. the whole-body
    QP assembly of :mod:`amlip_qp.control.wbc.compiled`, uses its own names).
    ``compile_flags`` go after :data:`CFLAGS`, before the source; ``link_flags`` after the
    source and ``-lm``. The key hashes them with the source, the compiler and :data:`CFLAGS`
    (with none, the key of the C sources without extra flags).
    Returns the library path. Raises :class:`CodegenError` (with the
    compiler's output) when compilation fails, ``_NoCompiler`` when the
    compiler cannot be executed.
    """
    flags = _key_flags(compile_flags, link_flags)
    folder = (cache_root() if cache_dir is None else Path(cache_dir)) / cache_key(source, compiler, flags)
    lib = folder / library_file
    if lib.is_file():
        return lib
    try:
        folder.mkdir(parents=True, exist_ok=True)
        src = folder / source_file
        if not (src.is_file() and src.read_bytes() == source):
            generate.atomic_write(src, source)
        fd, tmp = tempfile.mkstemp(prefix=f".{library_file}.", suffix=".tmp", dir=folder)
        os.close(fd)
    except OSError as exc:
        raise CodegenError(
            f"cannot write the kernel cache {folder}: {exc}; set ${CACHE_ENV} to a writable folder"
        ) from exc
    cmd = [*compiler, *CFLAGS, *compile_flags, "-o", tmp, str(src), "-lm", *link_flags]
    try:
        try:
            proc = subprocess.run(cmd, capture_output=True, text=True, timeout=COMPILE_TIMEOUT_S)
        except FileNotFoundError as exc:
            raise _NoCompiler(f"the compiler {compiler[0]!r} cannot be executed ({exc})") from exc
        except subprocess.TimeoutExpired as exc:
            raise CodegenError(f"compiling {src} took over {COMPILE_TIMEOUT_S} s: {shlex.join(cmd)}") from exc
        if proc.returncode != 0:
            message = (proc.stderr or proc.stdout).strip()
            raise CodegenError(f"compiling {src} failed (exit {proc.returncode}): {shlex.join(cmd)}\n{message}")
        os.replace(tmp, lib)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)
    return lib


def compile_library(
    source: bytes,
    source_file: str,
    library_file: str,
    cache_dir: str | os.PathLike | None = None,
    *,
    compile_flags: Sequence[str] = (),
    link_flags: Sequence[str] = (),
) -> Path:
    """Compile C ``source`` once into the cache (as :func:`compile_and_load`, announcing a cold
    cache on stderr) and return the library's path, for loading with :mod:`ctypes`.

    ``compile_flags`` go before the source (e.g. ``-x c++`` and include folders), ``link_flags``
    after it (e.g. a library to link); both are part of the cache key (:func:`build_library`).

    Raises:
        CompilerUnavailableError: No usable C compiler (the message says why).
        CodegenError: The compiler rejected the source.
    """
    root = cache_root() if cache_dir is None else Path(cache_dir)
    try:
        compiler = find_compiler()
        flags = _key_flags(compile_flags, link_flags)
        if not (root / cache_key(source, compiler, flags) / library_file).is_file():
            _announce_compilation(root)
        return build_library(source, compiler, root, source_file, library_file, compile_flags, link_flags)
    except _NoCompiler as exc:
        raise CompilerUnavailableError(str(exc)) from None


def compile_and_load(
    source: bytes,
    function_names: Sequence[str],
    source_file: str = generate.SOURCE_FILE,
    library_file: str = LIBRARY_FILE,
    cache_dir: str | os.PathLike | None = None,
) -> tuple[Path, dict[str, ca.Function]]:
    """Compile generated C once into the cache and load its functions.

    Args:
        source: The C source (its hash, with the compiler and flags, keys the cache folder).
        function_names: The functions to load from the library with ``casadi.external``.
        source_file, library_file: File names inside the cache folder (one pair
            per kind of generated code, see :func:`build_library`).
        cache_dir: Overrides :func:`cache_root`.

    Returns:
        ``(library path, {name: casadi.Function})``.

    On a cache miss, the first of this process for that cache folder, one line
    on stderr says that generated C is being compiled once, and where.

    Raises:
        CompilerUnavailableError: No usable C compiler (the message says why).
        CodegenError: The compiler rejected the source, or a function does not load.
    """
    lib = compile_library(source, source_file, library_file, cache_dir)
    functions = {}
    for name in function_names:
        try:
            functions[name] = ca.external(name, str(lib))
        except RuntimeError as exc:
            reason = "; ".join(line.strip() for line in str(exc).splitlines() if line.strip())
            raise CodegenError(f"cannot load {name} from {lib}: {reason}; delete {lib.parent} to rebuild") from exc
    return lib, functions


def _announce_compilation(root: Path) -> None:
    """One stderr line per process and cache folder: generated C is being compiled once."""
    if root in _announced_roots:
        return
    _announced_roots.add(root)
    shown, home = str(root), str(Path.home())
    if shown.startswith(home + os.sep):
        shown = "~" + shown[len(home) :]
    sys.stderr.write(
        f"amlip_qp: compiling generated C once into {shown} (up to about {COLD_COMPILE_S} s; later runs reuse it)\n"
    )
    sys.stderr.flush()


def bind_buffers(functions: dict[str, ca.Function], inputs: list, outputs: list) -> dict[str, tuple]:
    """Bind each function's inputs and outputs to the arrays (contiguous; a
    C-order (a, b) array is the column-major (b, a) matrix).

    Returns:
        Per name, its ``(buffer, evaluate)`` pair.

    Raises:
        CodegenError: A size differs or an array is not contiguous.
    """
    bound = {}
    # Stub limit: casadi's FunctionBuffer.set_arg/set_res stubs demand a size (the binding takes it from the buffer).
    for name, fn in functions.items():
        buf, ev = fn.buffer()
        for kind, arrays, nnz, setter in (
            ("input", inputs, fn.nnz_in, buf.set_arg), ("output", outputs, fn.nnz_out, buf.set_res)
        ):  # fmt: skip
            for i, arr in enumerate(arrays):
                if nnz(i) != arr.size or arr.dtype != np.float64:
                    raise CodegenError(f"{name} {kind} {i} has the wrong size or type")
                if not (arr.flags.c_contiguous or arr.flags.f_contiguous):
                    raise CodegenError(f"{name} {kind} {i} is not contiguous")
                setter(i, memoryview(arr.reshape(-1, order="A")))  # type: ignore[call-arg]
        bound[name] = (buf, ev)
    return bound


class PerDataBindings:
    """Generated functions bound in place to the arrays of each Pinocchio data they read.

    ``bind(data)`` binds them (:func:`bind_buffers` on the data's arrays) and returns ``(keep,
    evaluators)``: what must stay alive while the evaluators run (the views, the buffers) and the
    evaluators. :meth:`evaluators` binds a data on its first use and keeps the bindings of the last
    ``max_entries`` data objects (e.g. a controller's kinematics and its IK's); each entry holds its
    data, so an entry's key (the data's ``id``) is never reused while the entry lives.
    """

    def __init__(self, bind, max_entries: int):
        self._bind = bind
        self._max = max_entries
        self._entries: dict[int, tuple] = {}

    def evaluators(self, data):
        """The evaluators bound to ``data`` (binding it first if needed)."""
        entry = self._entries.get(id(data))
        if entry is not None and entry[0] is data:
            return entry[2]
        if len(self._entries) >= self._max:
            del self._entries[next(iter(self._entries))]  # the oldest
        keep, evaluators = self._bind(data)
        self._entries[id(data)] = (data, keep, evaluators)
        return evaluators
