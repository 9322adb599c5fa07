"""CasADi SX definitions of the two dense per-tick planner kernels.

The expressions are not written here: they come from calling
:func:`amlip_qp.alip.kernels.alip_plan_terms` and
:func:`amlip_qp.alip.kernels.swing_reference_terms` with SX symbols, so the
generated C and the numpy reference share one source of truth.

Each kernel is a ``casadi.Function`` with one dense input ``u`` (column
vector) and one dense output ``y``:

- ``alip_plan``: ``u[16] -> y[8]`` (layout: ``kernels.ALIP_PLAN_INPUTS`` /
  ``kernels.ALIP_PLAN_OUTPUTS``; SI units, see :mod:`amlip_qp.alip.kernels`).
- ``swing_reference``: ``u[15] -> y[30]`` (layout:
  ``kernels.SWING_REFERENCE_INPUTS``; ``h_d``, ``dh_d/dt``, ``d2h_d/dt2``).
- ``alip_mpc_qp``: ``u[62] -> y[568]``, the step-timing MPC's QP (layout:
  ``step_mpc.MPC_QP_INPUTS``, ``step_mpc.MPC_QP_BLOCKS``; :mod:`amlip_qp.alip.step_mpc`).

Physical parameters (mass, CoM height, step time, width, gravity, clearance)
are inputs, so the same functions serve Cassie and Rabbit. Every output entry
is structurally nonzero (``densify``), so callers always get ``n_out``
numbers in the documented order. Common subexpressions are merged
(``casadi.cse``) so the generated C computes each ``sqrt``/``cosh``/``sinh``
once.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from functools import cache

import casadi as ca

from amlip_qp.alip import kernels, step_mpc


@dataclass(frozen=True)
class KernelSpec:
    """Name, dense sizes and term builder of one kernel."""

    name: str
    n_in: int
    n_out: int
    terms: Callable[[Sequence], list]
    input_names: tuple[str, ...]


#: The kernels, in the order they appear in the generated library.
KERNEL_SPECS: tuple[KernelSpec, ...] = (
    KernelSpec("alip_plan", len(kernels.ALIP_PLAN_INPUTS), len(kernels.ALIP_PLAN_OUTPUTS),
               kernels.alip_plan_terms, kernels.ALIP_PLAN_INPUTS),
    KernelSpec("swing_reference", len(kernels.SWING_REFERENCE_INPUTS), kernels.SWING_REFERENCE_N_OUT,
               kernels.swing_reference_terms, kernels.SWING_REFERENCE_INPUTS),
    KernelSpec("alip_mpc_qp", len(step_mpc.MPC_QP_INPUTS), step_mpc.MPC_QP_N_OUT,
               step_mpc.mpc_qp_terms, step_mpc.MPC_QP_INPUTS),
)  # fmt: skip

#: Kernel names, in library order.
KERNEL_NAMES: tuple[str, ...] = tuple(spec.name for spec in KERNEL_SPECS)


def spec(name: str) -> KernelSpec:
    """Return the :class:`KernelSpec` called ``name`` (``KeyError`` if unknown)."""
    for s in KERNEL_SPECS:
        if s.name == name:
            return s
    raise KeyError(f"unknown kernel {name!r}; expected one of {KERNEL_NAMES}")


def build_function(kernel: KernelSpec) -> ca.Function:
    """Build the SX ``casadi.Function`` ``kernel.name: u[n_in] -> y[n_out]``."""
    u = ca.SX.sym("u", kernel.n_in)
    terms = kernel.terms([u[i] for i in range(kernel.n_in)])
    if len(terms) != kernel.n_out:
        raise AssertionError(f"{kernel.name}: {len(terms)} terms, expected {kernel.n_out}")
    y = ca.cse(ca.densify(ca.vertcat(*terms)))
    return ca.Function(kernel.name, [u], [y], ["u"], ["y"])


@cache
def function(name: str) -> ca.Function:
    """The (cached) SX Function of the kernel ``name`` (one of :data:`KERNEL_NAMES`)."""
    return build_function(spec(name))


def functions() -> dict[str, ca.Function]:
    """All kernels as ``{name: casadi.Function}``, in library order."""
    return {name: function(name) for name in KERNEL_NAMES}
