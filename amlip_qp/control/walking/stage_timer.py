"""The wall time of the walking controller's stages, tick by tick, recorded when asked.

A :class:`StageTimer` given to :class:`~amlip_qp.control.walking.controller.WalkingController`
(``stage_timer=``) receives, for every tick that reaches the tracker, the wall time of the
kinematics update at the measured state, of the estimate (the state estimate, the step clock and
its touchdown test, the command's speed correction), of the planner's update and of the tracker's
``compute``, and the parts of that ``compute`` the tracker times itself (the QP tracker's
``info["build_us"]``, the problem's build, and ``info["solve_us"]``, the solver's call; the PBC's
``info["ik_us"]``, ``info["compensation_us"]`` and ``info["dynamics_us"]``: the IK, the swing
compensation, the constrained dynamics' assembly and solve).
``amlip-qp bench harness`` judges the tracker's own work (the kinematics update and ``compute``
together) against its speed goal (:mod:`amlip_qp.experiments.bench_goals`) and reports the parts of
the tick. Without a timer the controller reads no clock (one ``is None`` test per stage).
"""

from __future__ import annotations

import math
from collections.abc import Mapping


class StageTimer:
    """Per-tick stage times of one controller, µs (one entry per tick that ran the tracker)."""

    def __init__(self) -> None:
        #: The kinematics update at the tick's measured state, µs.
        self.kinematics_us: list[float] = []
        #: The tracker's ``compute``, µs.
        self.tracker_us: list[float] = []
        #: The estimate after the kinematics update: the state estimate, the step clock and its touchdown
        #: test, the command's speed correction and the planner's state, µs.
        self.estimate_us: list[float] = []
        #: The planner's update (:func:`~amlip_qp.control.walking.planners.plan_tick`), µs.
        self.plan_us: list[float] = []
        #: The problem's build within ``compute`` as the tracker timed it (``info["build_us"]``), µs;
        #: NaN in a tick whose tracker reports none (the PBC, a fallback before the build).
        self.build_us: list[float] = []
        #: The solver's call within ``compute`` as the tracker timed it (``info["solve_us"]``), µs; NaN
        #: in a tick whose tracker reports none.
        self.solve_us: list[float] = []
        #: The PBC's IK within ``compute`` (``info["ik_us"]``), µs; NaN in a tick whose tracker reports none.
        self.ik_us: list[float] = []
        #: The PBC's swing compensation (``info["compensation_us"]``), µs; NaN where it reports none.
        self.compensation_us: list[float] = []
        #: The PBC's constrained dynamics, assembly and solve (``info["dynamics_us"]``), µs; NaN where none.
        self.dynamics_us: list[float] = []

    def record(
        self,
        kinematics_ns: int,
        tracker_ns: int,
        info: Mapping[str, object] | None = None,
        estimate_ns: float = math.nan,
        plan_ns: float = math.nan,
    ) -> None:
        """Add one tick's times, ns, and the parts of ``compute`` in the tracker's ``info`` (µs; the
        controller calls this). A stage not timed is NaN."""
        self.kinematics_us.append(kinematics_ns * 1e-3)
        self.tracker_us.append(tracker_ns * 1e-3)
        self.estimate_us.append(estimate_ns * 1e-3)
        self.plan_us.append(plan_ns * 1e-3)
        parts = info or {}
        self.build_us.append(_part_us(parts, "build_us"))
        self.solve_us.append(_part_us(parts, "solve_us"))
        self.ik_us.append(_part_us(parts, "ik_us"))
        self.compensation_us.append(_part_us(parts, "compensation_us"))
        self.dynamics_us.append(_part_us(parts, "dynamics_us"))

    @property
    def tracker_work_us(self) -> list[float]:
        """The tracker's own work per tick: the kinematics update plus the tracker's ``compute``, µs."""
        return [k + t for k, t in zip(self.kinematics_us, self.tracker_us)]

    def clear(self) -> None:
        """Forget the recorded ticks."""
        self.kinematics_us.clear()
        self.tracker_us.clear()
        self.estimate_us.clear()
        self.plan_us.clear()
        self.build_us.clear()
        self.solve_us.clear()
        self.ik_us.clear()
        self.compensation_us.clear()
        self.dynamics_us.clear()


def _part_us(info: Mapping[str, object], key: str) -> float:
    """``info[key]`` as a float, µs; NaN when it is missing or not a finite number."""
    value = info.get(key)
    if isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value):
        return float(value)
    return math.nan
