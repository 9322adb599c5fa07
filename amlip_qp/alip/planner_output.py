"""The planner's answer of one tick, made cheaply: :func:`planner_output`.

:class:`~amlip_qp.messages.PlannerOutput` is a frozen dataclass with slots; its constructor
sets each of its 15 fields through ``object.__setattr__`` after handling the keywords, a few
microseconds of the 2 kHz planner tick. :func:`planner_output` makes the same object with the
fields' own slot setters.
"""

from __future__ import annotations

from dataclasses import fields

import numpy as np

from amlip_qp.messages import PlannerOutput

#: The slot setters of :class:`~amlip_qp.messages.PlannerOutput`'s fields, in field order.
_SETTERS = tuple(getattr(PlannerOutput, f.name).__set__ for f in fields(PlannerOutput))


def planner_output(
    s: float,
    t_remaining_s: float,
    L_hat_Nms: np.ndarray,
    p_hat_m: np.ndarray,
    L_des_Nms: np.ndarray,
    p_sw_des_world_m: np.ndarray,
    p_sw_des_heading_m: np.ndarray,
    swing_target_world_m: np.ndarray,
    h_d: np.ndarray,
    dh_d: np.ndarray,
    ddh_d: np.ndarray,
    heading_rad: float,
    heading_next_rad: float,
    turn_rad: float,
    v_z_used_mps: float,
) -> PlannerOutput:
    """``PlannerOutput(s=s, ...)`` with the fields in their order, positional: the same object (tested),
    without the frozen constructor's keyword handling and ``object.__setattr__`` calls (the units and
    meanings: :class:`~amlip_qp.messages.PlannerOutput`)."""
    new = object.__new__(PlannerOutput)
    put = _SETTERS
    put[0](new, s)
    put[1](new, t_remaining_s)
    put[2](new, L_hat_Nms)
    put[3](new, p_hat_m)
    put[4](new, L_des_Nms)
    put[5](new, p_sw_des_world_m)
    put[6](new, p_sw_des_heading_m)
    put[7](new, swing_target_world_m)
    put[8](new, h_d)
    put[9](new, dh_d)
    put[10](new, ddh_d)
    put[11](new, heading_rad)
    put[12](new, heading_next_rad)
    put[13](new, turn_rad)
    put[14](new, v_z_used_mps)
    return new
