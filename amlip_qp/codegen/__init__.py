"""CasADi definitions of the planner kernels, their generated C, and a fast caller.

Modules (one job each):

- :mod:`~amlip_qp.codegen.symbolic`: the SX ``casadi.Function`` objects
  ``alip_plan`` and ``swing_reference`` built from :mod:`amlip_qp.alip.kernels`.
- :mod:`~amlip_qp.codegen.generate`: deterministic C generation into
  ``amlip_qp/codegen/generated/`` (package data) and the staleness check.
- :mod:`~amlip_qp.codegen.runtime`: compile-on-first-use into a per-user
  cache (:func:`compile_and_load`, for every generated library of amlip_qp).
- :mod:`~amlip_qp.codegen.kernels`: the planner kernels with microsecond
  calls (:func:`load_kernels`, :class:`Kernels`, :class:`FastFunction`).
- :mod:`~amlip_qp.codegen.output_map`, :mod:`~amlip_qp.codegen.frame_terms`: the output map
  ``h_0`` with its Jacobian and drift, and the frames' Jacobians and drifts, as CasADi
  expressions of Pinocchio's arrays (read in place by the generated code of the trackers and the
  walking loop).
- :mod:`~amlip_qp.codegen.bench`: timings of the fast path, the CasADi
  Function and the numpy reference.
- :mod:`~amlip_qp.codegen.cli`: the ``amlip-qp codegen`` / ``bench codegen`` handlers.

A controller gets the kernels with ``kernels = load_kernels()`` and calls
``kernels.alip_plan(u)`` and ``kernels.swing_reference(u)``.
"""

from amlip_qp.codegen.kernels import FastFunction, Kernels, load_kernels
from amlip_qp.codegen.runtime import CodegenFallbackWarning, CodegenStaleWarning, compile_and_load

__all__ = [
    "CodegenFallbackWarning",
    "CodegenStaleWarning",
    "FastFunction",
    "Kernels",
    "compile_and_load",
    "load_kernels",
]
