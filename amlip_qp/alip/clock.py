"""The step clock: which leg is in stance, when the step started, how far it is.

The walking loop has one :class:`StepClock`, and it is the only record of the
stance side and the step start. The :class:`~amlip_qp.alip.planner.Planner`
holds it (the controller hands its clock to the planner) and starts a step on
it at every touchdown (:meth:`Planner.start_step
<amlip_qp.alip.planner.Planner.start_step>`); the planner reads the step start
from it to integrate the commanded turn rate. Every tick the controller reads
the time in the step (given to the planner) and the unclipped phase (given to
the touchdown test) from it.

A planner that plans the step's duration (the step-timing MPC,
:class:`~amlip_qp.alip.mpc_planner.MPCPlanner`) writes it on the clock
(:meth:`StepClock.plan_step_time`); :meth:`StepClock.step_time_s` then gives
it instead of the command's ``T``. Every :meth:`StepClock.start` forgets it.
"""

from __future__ import annotations

import math

from amlip_qp.alip.desired import other_side
from amlip_qp.exceptions import InputError


class StepClock:
    """Stance side, start time and phase of the current step.

    Before the first :meth:`start` there is no step: :attr:`stance` is
    ``None`` and the step start is 0 s.
    """

    def __init__(self) -> None:
        self._stance: str | None = None
        self._t_start_s = 0.0
        self._planned_T_s: float | None = None

    @property
    def stance(self) -> str | None:
        """Stance side of the current step (``None`` before the first step)."""
        return self._stance

    @property
    def swing(self) -> str | None:
        """Swing side of the current step (``None`` before the first step)."""
        return None if self._stance is None else other_side(self._stance)

    @property
    def t_start_s(self) -> float:
        """Time at which the current step started, s."""
        return self._t_start_s

    def start(self, stance: str, t_s: float) -> None:
        """Begin a step with ``stance`` in stance at time ``t_s`` (s): a touchdown.

        Raises:
            InputError: ``stance`` is not ``"left"`` or ``"right"``.
        """
        if stance not in ("left", "right"):
            raise InputError(f"stance must be 'left' or 'right', got {stance!r}")
        self._stance = stance
        self._t_start_s = float(t_s)
        self._planned_T_s = None

    def reset(self) -> None:
        """No step (a new run)."""
        self._stance = None
        self._t_start_s = 0.0
        self._planned_T_s = None

    @property
    def planned_step_time_s(self) -> float | None:
        """The current step's duration planned by the planner, s (``None``: not planned, the command's)."""
        return self._planned_T_s

    def plan_step_time(self, T_s: float) -> None:
        """Set the current step's planned duration ``T_s`` (s, > 0), until the next :meth:`start`.

        Raises:
            InputError: ``T_s`` is not a positive finite number.
        """
        if isinstance(T_s, bool) or not isinstance(T_s, (int, float)) or not 0.0 < T_s < math.inf:
            raise InputError(f"the planned step time must be a positive finite number of seconds, got {T_s!r}")
        self._planned_T_s = float(T_s)

    def step_time_s(self, command_T_s: float) -> float:
        """The current step's duration, s: the planned one, else ``command_T_s`` (the command's ``T``)."""
        return command_T_s if self._planned_T_s is None else self._planned_T_s

    def time_in_step(self, t_s: float) -> float:
        """Time since the step started, s, never negative."""
        return max(t_s - self._t_start_s, 0.0)

    def phase_unclipped(self, t_s: float, step_time_s: float) -> float:
        """``(t_s - t_start) / T`` (dimensionless): 1 at the nominal end of the step, above 1 when it is late."""
        return (t_s - self._t_start_s) / step_time_s
