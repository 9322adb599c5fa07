"""Quadratic programs for whole-body tracking: an inspectable problem object
(:class:`QPProblem`), two persistent solvers with one interface (the
warm-started ProxQP, :class:`ProxQPSolver`, and the hot-started dual
active-set DAQP, :class:`DAQPSolver`), and a cross-check through any
``qpsolvers`` backend (:meth:`QPProblem.solve_with`).

Building a problem is separate from solving it, so a user can inspect,
record, or re-solve any tick's problem.
"""

from amlip_qp.qp.daqp_solver import DAQPSolver
from amlip_qp.qp.problem import QPProblem
from amlip_qp.qp.solver import ProxQPSolver, QPSolution

__all__ = ["DAQPSolver", "ProxQPSolver", "QPProblem", "QPSolution"]
