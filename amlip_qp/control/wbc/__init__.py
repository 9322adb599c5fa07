"""Whole-body control: the task-space QP tracker (TSID vocabulary).

Accelerations and contact forces are the decision variables; tasks,
contacts and limits become the costs and constraints of one dense QP per
control tick, solved by one persistent solver: the hot-started DAQP the
bundled robots' profiles name, or the warm-started ProxQP (``QPConfig.qp_solver``).

- :mod:`~amlip_qp.control.wbc.config`: weights, gains, limits; the tuned configurations;
- :mod:`~amlip_qp.control.wbc.layout`: the decision variables;
- :mod:`~amlip_qp.control.wbc.tasks`: the tasks (error, Jacobian, drift);
- :mod:`~amlip_qp.control.wbc.spring_elimination`: rigid springs' forces eliminated, the torque map;
- :mod:`~amlip_qp.control.wbc.inputs`: the per-tick inputs, gathered once;
- :mod:`~amlip_qp.control.wbc.constraints`, :mod:`~amlip_qp.control.wbc.costs`: objects of one shape
  (the constraints' shape: :mod:`~amlip_qp.control.wbc.constraint_base`);
- :mod:`~amlip_qp.control.wbc.builder`: :class:`WholeBodyQP`, the problem from those lists;
- :mod:`~amlip_qp.control.wbc.compiled`: the same build as generated C;
- :mod:`~amlip_qp.control.wbc.compiled_in_place`: the same as generated C reading Pinocchio's arrays in place
  (the tracker's default);
- :mod:`~amlip_qp.control.wbc.tracker`: :class:`QPTracker`, build, solve, fall back.
"""
