"""The wall time of the walking controller's stages, tick by tick, recorded when asked.

A :class:`StageTimer` given to :class:`~amlip_qp.control.walking.controller.WalkingController`
(``stage_timer=``) receives, for every tick that reaches the tracker, the wall time of the
kinematics update at the measured state and of the tracker's ``compute`` (for the QP tracker: the
problem's build and its solve). ``amlip-qp bench harness`` judges the tracker's own work (the two
together) against its speed goal (:mod:`amlip_qp.experiments.bench_goals`). Without a timer the
controller reads no clock (one ``is None`` test per stage).
"""

from __future__ import annotations


class StageTimer:
    """Per-tick stage times of one controller, µs (one entry per tick that ran the tracker)."""

    def __init__(self) -> None:
        #: The kinematics update at the tick's measured state, µs.
        self.kinematics_us: list[float] = []
        #: The tracker's ``compute``, µs.
        self.tracker_us: list[float] = []

    def record(self, kinematics_ns: int, tracker_ns: int) -> None:
        """Add one tick's times (the controller calls this), ns."""
        self.kinematics_us.append(kinematics_ns * 1e-3)
        self.tracker_us.append(tracker_ns * 1e-3)

    @property
    def tracker_work_us(self) -> list[float]:
        """The tracker's own work per tick: the kinematics update plus the tracker's ``compute``, µs."""
        return [k + t for k, t in zip(self.kinematics_us, self.tracker_us)]

    def clear(self) -> None:
        """Forget the recorded ticks."""
        self.kinematics_us.clear()
        self.tracker_us.clear()
