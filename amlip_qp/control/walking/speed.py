"""Integral action on the step-to-step speed error (beyond the paper).

The deadbeat foot placement reaches ``L_des`` exactly only on the LIP; the
unmodelled dynamics leave a steady speed bias, which
:class:`SpeedIntegrator` removes once per completed step (its effect is
measured in ``docs/TUNING.md``, "PBC tracker and walking loop").
:class:`SpeedCorrection` holds its gains and bounds; :class:`CorrectedCommand`
adds the correction to the command the planner sees;
``SpeedCorrection(enabled=False)`` gives the paper's controller unchanged.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from amlip_qp.exceptions import InputError

if TYPE_CHECKING:
    from amlip_qp.messages import Command


@dataclass(frozen=True)
class SpeedCorrection:
    """Integral action on the step-to-step velocity error.

    The deadbeat law reaches ``L_des`` exactly only on the LIP. On a real
    robot the unmodelled dynamics (the CoM bounce after impact, the swing
    leg's centroidal momentum, foot-placement error) leave a steady bias: a
    robot commanded at 1 m/s settles a few tenths slower, every step alike.
    This slow integral removes that bias. After every step the heading-frame
    mean CoM velocity over the step is compared with the command the planner
    aimed at for that step (the one in force a step earlier, so a speed ramp
    does not wind it up), and ``gain_per_step`` times the error is added to
    the correction given to the planner. Lateral errors use the mean over the
    last two steps (a stride), because the CoM sways from side to side.

    Attributes:
        enabled: Apply the correction.
        gain_per_step: Fraction of the error corrected per step (dimensionless).
        max_correction_mps: Bound on the correction, m/s.
        max_error_mps: Larger step errors are disturbances (a push), not bias:
            they are left to the foot placement and do not enter the integral, m/s.
        settle_steps: Steps ignored at the start of a run.
    """

    enabled: bool = True
    gain_per_step: float = 0.3
    max_correction_mps: float = 0.3
    max_error_mps: float = 0.5
    settle_steps: int = 2

    def __post_init__(self):
        vals = (self.gain_per_step, self.max_correction_mps, self.max_error_mps)
        if not all(math.isfinite(v) and v >= 0 for v in vals) or self.gain_per_step > 1 or self.settle_steps < 0:
            raise InputError(
                "SpeedCorrection needs 0 <= gain_per_step <= 1, finite non-negative bounds and settle_steps >= 0, "
                f"got {self!r}"
            )


class SpeedIntegrator:
    """The integral of :class:`SpeedCorrection`, updated once per completed step.

    Args:
        params: Gains and bounds.
        planar: Only the forward axis (planar robots).
    """

    def __init__(self, params: SpeedCorrection, planar: bool = False):
        self.params = params
        self.planar = bool(planar)
        self._correction = np.zeros(2)
        self._prev_vy = math.nan
        self._steps = 0

    @property
    def correction_mps(self) -> np.ndarray:
        """``(vx, vy)`` to add to the command, heading frame, m/s (copy)."""
        return self._correction.copy()

    def reset(self) -> None:
        """Back to zero correction (a new run)."""
        self._correction[:] = 0.0
        self._prev_vy = math.nan
        self._steps = 0

    def update(self, v_step_mps, v_aimed_mps) -> np.ndarray:
        """Account for one completed step; returns the new correction (m/s).

        Args:
            v_step_mps: The step's mean CoM velocity ``(vx, vy)``, heading frame, m/s.
            v_aimed_mps: The command the foot placement aimed at for that step, m/s.
        """
        p = self.params
        self._steps += 1
        vy_stride = 0.5 * (v_step_mps[1] + self._prev_vy)
        self._prev_vy = float(v_step_mps[1])
        if not p.enabled or self._steps <= p.settle_steps:
            return self.correction_mps
        for axis, v in ((0, float(v_step_mps[0])), (1, vy_stride)):
            if axis == 1 and self.planar or not math.isfinite(v):
                continue
            err = float(v_aimed_mps[axis]) - v
            if abs(err) <= p.max_error_mps:
                c = self._correction[axis] + p.gain_per_step * err
                self._correction[axis] = min(max(c, -p.max_correction_mps), p.max_correction_mps)
        return self.correction_mps


class CorrectedCommand:
    """The command the planner sees: the given one plus the integral speed correction.

    The corrected :class:`~amlip_qp.messages.Command` is made once per
    (command, correction) pair and reused while neither changes (the
    correction changes once per step).

    Attributes:
        correction_mps: The correction ``(v_x, v_y)`` added, heading frame, m/s;
            the walking controller sets it after every step.
    """

    def __init__(self) -> None:
        self.correction_mps = np.zeros(2)
        self._key: tuple | None = None
        self._corrected: Command | None = None

    def apply(self, command: Command) -> Command:
        """``command`` plus the correction (the same object if the correction is zero)."""
        cx, cy = self.correction_mps.tolist()
        if cx == 0.0 and cy == 0.0:
            return command
        key = (command, cx, cy)
        corrected = self._corrected
        if key != self._key or corrected is None:
            corrected = command.with_velocity(command.vx_mps + cx, command.vy_mps + cy)
            self._key, self._corrected = key, corrected
        return corrected
