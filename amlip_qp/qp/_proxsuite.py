"""Import ProxSuite's portable build, so that ProxQP solves are bit-reproducible.

ProxSuite's wheels ship three builds of the same solver (AVX-512, AVX2 and a
portable SSE2 one) and ``import proxsuite`` loads the widest the CPU supports.
The vectorised builds are not reproducible: their Eigen kernels round
differently with the address of the solver's internal buffers, so the same
problem sequence solved twice gave solutions differing by up to 3e-6, and a
walking simulation that amplifies such bits ended differently from run to run
(measured on 1200 recorded Cassie QPs, 5 fresh solvers each: the AVX-512 and
AVX2 builds never matched themselves, the portable build always did, at about
1.3x the AVX2 solve time).

So amlip_qp loads the portable build by default (the project's standard: the
same seed and arguments give the same result). Set the environment variable
``AMLIP_QP_PROXSUITE_SIMD=1`` before importing amlip_qp to get ProxSuite's
default choice (faster, not reproducible). This only works if amlip_qp
imports ProxSuite first; :data:`PROXSUITE_BUILD` says which build is loaded.
"""

from __future__ import annotations

import importlib
import os
import sys
import types
import warnings

#: Environment variable that lets ProxSuite pick its vectorised build.
SIMD_ENV = "AMLIP_QP_PROXSUITE_SIMD"
#: ProxSuite's portable (reproducible) build.
PORTABLE_BUILD = "proxsuite_pywrap"


def _wants_simd() -> bool:
    return os.environ.get(SIMD_ENV, "").strip().lower() in ("1", "true", "yes", "on")


class _NoVectorBuilds(types.ModuleType):
    """Stand-in for ``proxsuite.instructionset`` that reports no AVX-512 or AVX2 support."""

    @staticmethod
    def has_AVX512F() -> bool:
        return False

    @staticmethod
    def has_AVX2() -> bool:
        return False


def _import_proxsuite():
    if "proxsuite" not in sys.modules and not _wants_simd():
        # proxsuite/__init__.py asks proxsuite.instructionset which builds the
        # CPU supports; answer "none" for the duration of the import.
        sys.modules["proxsuite.instructionset"] = _NoVectorBuilds("proxsuite.instructionset")
        try:
            return importlib.import_module("proxsuite")
        finally:
            sys.modules.pop("proxsuite.instructionset", None)
    return importlib.import_module("proxsuite")


proxsuite = _import_proxsuite()
#: Name of the loaded ProxSuite build (``"proxsuite_pywrap"``: portable).
PROXSUITE_BUILD: str = getattr(getattr(proxsuite, "_submodule", None), "__name__", "unknown").rsplit(".", 1)[-1]
#: Whether ProxQP solves are bit-reproducible in this process.
REPRODUCIBLE: bool = PROXSUITE_BUILD == PORTABLE_BUILD
proxqp = proxsuite.proxqp

if not REPRODUCIBLE and not _wants_simd():
    warnings.warn(
        f"ProxSuite was imported before amlip_qp and loaded its {PROXSUITE_BUILD!r} build: ProxQP "
        "solves (and QP-tracker walks) are not bit-reproducible; import amlip_qp first",
        RuntimeWarning,
        stacklevel=2,
    )
