"""What the walking controller reports: one :class:`StepRecord` per completed step, one :class:`TickInfo` per tick.

:class:`~amlip_qp.control.walking.controller.WalkingController` appends a
:class:`StepRecord` to its ``steps`` at every touchdown and returns a
:class:`TickInfo` from every ``step``; a tick in the damped safe mode logs
the NaN estimate, plan and outputs of :func:`nan_tick_signals`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from amlip_qp.control.walking.estimator import Estimate
from amlip_qp.messages import PlannerOutput


@dataclass
class StepRecord:
    """What happened in one completed step (recorded at its touchdown).

    Attributes:
        t_start_s: When the step began, s.
        t_end_s: Touchdown time ending it, s.
        stance: Its stance side.
        swing_target_m: The planner's last swing-contact target (world), m.
        swing_actual_m: Where the swing contact was at touchdown (world), m.
        L_end_Nms: ``(L_x, L_y)`` about the stance contact at the end of the step (measured), kg m^2/s.
        L_target_Nms: The ``L_des`` the planner aimed at for the end of this
            step (chosen during the previous step), or NaN for the first step.
        com_vel_end_mps: CoM velocity at the end of the step, m/s.
        heading_rad: The step's heading ``D_k``, rad.
        mean_velocity_heading_mps: Mean CoM velocity over the step (CoM
            displacement / duration) in the step's heading frame, m/s.
        speed_correction_mps: The integral speed correction in force during the step, m/s.
    """

    t_start_s: float
    t_end_s: float
    stance: str
    swing_target_m: np.ndarray
    swing_actual_m: np.ndarray
    L_end_Nms: np.ndarray
    L_target_Nms: np.ndarray
    com_vel_end_mps: np.ndarray
    heading_rad: float
    mean_velocity_heading_mps: np.ndarray = field(default_factory=lambda: np.zeros(2))
    speed_correction_mps: np.ndarray = field(default_factory=lambda: np.zeros(2))


@dataclass
class TickInfo:
    """This tick's signals, for logging (all references, not copies: copy to keep)."""

    t_s: float
    stance: str
    phase: float
    estimate: Estimate
    plan: PlannerOutput
    h: np.ndarray
    tau_Nm: np.ndarray
    tracker_ok: bool
    touchdown: bool
    info: dict = field(default_factory=dict)


def nan_tick_signals(n_outputs: int) -> tuple[Estimate, PlannerOutput, np.ndarray]:
    """NaN estimate, plan and outputs (``n_outputs`` of them) for the logs of a safe-mode tick."""
    n = n_outputs
    nan = math.nan

    def vec(k: int) -> np.ndarray:
        return np.full(k, nan)

    est = Estimate(vec(3), vec(3), vec(3), vec(3), vec(3), vec(3), vec(3))
    plan = PlannerOutput(
        s=nan, t_remaining_s=nan, L_hat_Nms=vec(2), p_hat_m=vec(2), L_des_Nms=vec(2),
        p_sw_des_world_m=vec(2), p_sw_des_heading_m=vec(2), swing_target_world_m=vec(3),
        h_d=vec(n), dh_d=vec(n), ddh_d=vec(n), heading_rad=nan, heading_next_rad=nan, turn_rad=nan,
        v_z_used_mps=nan,
    )  # fmt: skip
    return est, plan, vec(n)
