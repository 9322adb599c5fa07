"""When each push of a run acts: from its time, or from a phase of the step after its time.

:class:`PushSchedule` is the harness's push logic: the world force on the
base at each control tick. A :class:`~amlip_qp.sim.loop.run_types.Push` without a
``phase`` acts on ``[t_s, t_s + duration_s)``; one with a ``phase`` starts at
the first tick at or after ``t_s`` where the controller's step phase reaches
it (crosses it from below, or a new step begins at or past it; the first
tick with a phase, at a run's start or after the controller's safe mode, counts
as reaching it when at or past it) and then acts for ``duration_s``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from amlip_qp.sim.loop.run_types import Push

#: Tolerance of the push-window time comparisons, s.
TIME_TOL_S = 1e-9


class PushSchedule:
    """The pushes of one run; call :meth:`force` once per tick, in order, and :meth:`reset` before a run."""

    def __init__(self, pushes: Sequence[Push]):
        self.pushes = tuple(pushes)
        self._forces = tuple(np.asarray(p.force_N, dtype=float) for p in self.pushes)  # N, world
        self.reset()

    def reset(self) -> None:
        """Forget the phase pushes' start times and the last phase (a new run)."""
        self.starts: dict[int, float] = {}  # phase push index -> its start time, s
        self.last_phase = math.nan  # the step phase of the previous call

    def force(self, t_s: float, phase: float = math.nan) -> np.ndarray:
        """World force on the base at time ``t_s`` (N), the sum of the active pushes.

        ``phase``: this tick's step phase (NaN, e.g. in the controller's safe
        mode, starts no phase push). Times are compared with a 1 ns tolerance so
        that MuJoCo's accumulated ``data.time`` does not shift a push by a tick.
        """
        f = np.zeros(3)
        for i, p in enumerate(self.pushes):
            start = p.t_s if p.phase is None else self._phase_start(i, p.t_s, p.phase, t_s, phase)
            if start - TIME_TOL_S <= t_s < start + p.duration_s - TIME_TOL_S:
                f += self._forces[i]
        self.last_phase = phase
        return f

    def _phase_start(self, index: int, after_s: float, target: float, t_s: float, phase: float) -> float:
        """Start time (s) of phase push ``index``, or ``inf`` while it waits for its phase."""
        start = self.starts.get(index)
        if start is None:
            prev = self.last_phase
            # reached: the phase crossed the target from below, or a new step began at or past it
            if t_s >= after_s - TIME_TOL_S and phase >= target and not (prev >= target and phase >= prev):
                self.starts[index] = start = t_s
        return math.inf if start is None else start
