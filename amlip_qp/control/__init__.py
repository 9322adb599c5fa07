"""The controller side of the closed loop, one job per subpackage.

- :mod:`~amlip_qp.control.tracker`: the one interface every tracker
  implements (:class:`~amlip_qp.control.tracker.Tracker`,
  :class:`~amlip_qp.control.tracker.TrackingTarget`,
  :class:`~amlip_qp.messages.TrackerResult`);
- :mod:`~amlip_qp.control.walking`: the walking loop (estimator, step clock,
  touchdown detection, speed integral, the ALIP planner call, the compiled
  output map) around any tracker;
- :mod:`~amlip_qp.control.pbc`: the paper's tracker, iterative IK plus a
  passivity-based controller, with the spring model;
- :mod:`~amlip_qp.control.wbc`: the whole-body QP tracker (tasks,
  constraints and costs, builder, compiled build, tracker).

Nothing here imports MuJoCo: the controller sees a state estimate only
(``docs/ARCHITECTURE.md``).
"""
