"""Build the step-timing MPC planner on its fast path (package doc)."""

from __future__ import annotations

from collections.abc import Sequence

from amlip_qp.alip import step_mpc
from amlip_qp.alip.mpc_planner import MPCPlanner, MPCSettings
from amlip_qp.exceptions import InputError
from amlip_qp.qp.small_qp import SmallQPSolver


def make_mpc_planner(
    outputs: Sequence[str],
    mass_kg: float,
    *,
    backend: str = "c",
    settings: MPCSettings | None = None,
    **planner_kwargs,
) -> MPCPlanner:
    """An :class:`~amlip_qp.alip.mpc_planner.MPCPlanner` with a hot-started DAQP (soft reach rows);
    with the ``"c"`` backend its solves run as one compiled call each
    (:mod:`amlip_qp.codegen.daqp_step`; the same solutions as the Python path).

    Args:
        outputs: the robot's output names (as :class:`~amlip_qp.alip.planner.Planner`).
        mass_kg: total mass, kg.
        backend: ``"c"``: the generated-C kernels (``alip_plan``, ``swing_reference``,
            ``alip_mpc_qp``; CasADi with a warning without a compiler); ``"numpy"``: the references.
        settings: :class:`~amlip_qp.alip.mpc_planner.MPCSettings` (default limits and weights).
        **planner_kwargs: the :class:`~amlip_qp.alip.planner.Planner`'s keyword arguments
            (``clock``, ``late_descent``, ...).

    Raises:
        InputError: an unknown backend, or a bad argument of the planner.
    """
    if backend not in ("c", "numpy"):
        raise InputError(f"backend must be 'c' or 'numpy', got {backend!r}")
    kw = dict(planner_kwargs)
    fast: dict = {}
    if backend == "c":
        from amlip_qp.codegen import load_kernels
        from amlip_qp.codegen.daqp_step import load_daqp_step

        kernels = load_kernels()
        kw.update(plan_fn=kernels.alip_plan, reference_fn=kernels.swing_reference, mpc_fn=kernels.alip_mpc_qp)
        fast = {
            "fast_step": load_daqp_step(),
            "producer": kernels.alip_mpc_qp,
            "producer_c": kernels.c_kernel("alip_mpc_qp"),
        }
    solver = SmallQPSolver(step_mpc.N_VAR, step_mpc.N_ROWS, step_mpc.SOFT_ROWS, **fast)
    return MPCPlanner(outputs, mass_kg, solver, settings=settings, **kw)
