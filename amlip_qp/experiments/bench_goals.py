"""The controller's speed goals in ``amlip-qp bench harness``, in MuJoCo steps and real-time factors.

A shared machine's speed drifts (up to 1.6x within minutes on the 2-core
development machine, more with other jobs on it), so the tick goals are
ratios to MuJoCo's step measured in the same run: the plant's step in the
same tick of the walking loop (35-40 µs for Cassie on the development
machine), the median over the ticks of the per-tick ratios. A tick of ``x``
MuJoCo steps costs ``x`` times the plant's own step. ``amlip-qp bench
harness`` also gives the figures over the step alone
(:mod:`amlip_qp.experiments.mujoco_yardstick`, replayed after every walk).

- :data:`GOAL_CONTROLLER_STEPS`: the whole-body QP controller's whole tick
  (estimate, plan, track), median;
- :data:`GOAL_QP_TRACKER_STEPS`: the QP tracker's own work in a tick (the
  kinematics update, the problem's build, the solve, as the controller's
  :class:`~amlip_qp.control.walking.stage_timer.StageTimer` records them),
  median;
- :data:`GOAL_PBC_STEPS`: the PBC controller's whole tick, median;
- the real-time factor of each robot's nominal walk per tracker: its
  profile's ``[compare] realtime_goal`` (the median over the walks; it
  follows the machine's speed, so its verdict holds for the machine state of
  the run, which the report gives as the yardstick's step time).
"""

from __future__ import annotations

from amlip_qp.profiles import get_profile

#: The whole-body QP controller's tick, median, at most this many MuJoCo steps.
GOAL_CONTROLLER_STEPS = 3.0

#: The QP tracker's own work (kinematics update, build, solve), median, at most this many MuJoCo steps.
GOAL_QP_TRACKER_STEPS = 2.0

#: The PBC controller's tick, median, at most this many MuJoCo steps.
GOAL_PBC_STEPS = 6.0


def tracker_base(name: str, variants: dict[str, tuple[str, dict[str, object]]]) -> str:
    """The tracker a bench tracker name runs (``qp-daqp`` -> ``qp``)."""
    return variants[name][0] if name in variants else name


def realtime_goal(scenario_robot: str, scenario: str, tracker: str) -> float | None:
    """The real-time factor goal of ``tracker`` on ``scenario`` (a robot's nominal walk), or ``None``."""
    compare = get_profile(scenario_robot).compare
    if compare is None or compare.nominal_scenario != scenario:
        return None
    return compare.realtime_goal.get(tracker)


def tick_goals(tracker: str) -> dict[str, float]:
    """The tick goals (MuJoCo steps) that apply to ``tracker``: ``controller`` and, for the QP, ``tracker``."""
    if tracker == "qp":
        return {"controller": GOAL_CONTROLLER_STEPS, "tracker": GOAL_QP_TRACKER_STEPS}
    if tracker == "pbc":
        return {"controller": GOAL_PBC_STEPS}
    return {}
