"""The paper's tracker: iterative IK + a passivity-based controller (one job per module).

- :mod:`~amlip_qp.control.pbc.ik`: :class:`IterativeIK`, reference outputs ``h_d`` to joint references,
  with its equations (:mod:`~amlip_qp.control.pbc.ik_equations`), settings
  (:mod:`~amlip_qp.control.pbc.ik_settings`) and straight-knee handling
  (:mod:`~amlip_qp.control.pbc.knee_limits`);
- :mod:`~amlip_qp.control.pbc.gains`: :class:`PBCGains` and the gains of each bundled robot;
- :mod:`~amlip_qp.control.pbc.springs`: the simplified spring model (static deflections);
- :mod:`~amlip_qp.control.pbc.tracker`: :class:`PBCTracker`, the constrained dynamics solved per tick.

This package never imports the QP layer. Its ``__init__`` imports nothing, so
reading the gains (``amlip_qp.profiles``) does not load the tracker.
"""
