"""The step-timing MPC planner wired to its runtime: the generated-C QP kernel and a hot-started DAQP.

:func:`make_mpc_planner` builds an :class:`~amlip_qp.alip.mpc_planner.MPCPlanner` (the pure
math, :mod:`amlip_qp.alip`) with the CasADi-generated ``alip_mpc_qp`` kernel
(:mod:`amlip_qp.codegen`) and a :class:`~amlip_qp.qp.small_qp.SmallQPSolver` whose leg-reach
rows are soft; :mod:`~amlip_qp.control.mpc.bench` times it (``amlip-qp bench mpc``).
"""

from amlip_qp.control.mpc.factory import make_mpc_planner

__all__ = ["make_mpc_planner"]
