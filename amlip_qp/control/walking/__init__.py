"""The walking loop around a tracker (one job per module).

- :mod:`~amlip_qp.control.walking.controller`: :class:`WalkingController`, one call per control tick
  (its step clock is :class:`amlip_qp.alip.clock.StepClock`, shared with the planner);
- :mod:`~amlip_qp.control.walking.records`: what it reports, per step and per tick;
- :mod:`~amlip_qp.control.walking.estimator`: the state estimate (``p_st``, filtered ``L``, ``v_z``);
- :mod:`~amlip_qp.control.walking.gait`: touchdown detection and the swing foot's contact weight;
- :mod:`~amlip_qp.control.walking.stage_timer`: the per-tick wall time of the kinematics update and
  the tracker, recorded when the controller is given a :class:`~amlip_qp.control.walking.stage_timer.StageTimer`;
- :mod:`~amlip_qp.control.walking.speed`: the per-step integral on the speed error;
- :mod:`~amlip_qp.control.walking.outputs_compiled`: the output map ``h_0(q)`` as generated C, and
  :func:`~amlip_qp.control.walking.outputs_compiled.make_kinematics`, the kinematics made with it
  (the controller's default);
- :mod:`~amlip_qp.control.walking.planners`: the foot-placement planner by name, and its update of
  each tick (:func:`~amlip_qp.control.walking.planners.plan_tick`).

The walking loop runs any :class:`~amlip_qp.control.tracker.Tracker` and
imports no specific one. This package's ``__init__`` imports nothing, so
importing one module does not load the others.
"""
