"""Shared planner inputs of the alip tests: a Command and a StateEstimate with overridable fields (SI units)."""

from amlip_qp.messages import Command, StateEstimate

#: CoM height (m) and step time (s) of the cases.
H, T = 0.9, 0.3


def cmd(**kw) -> Command:
    base = dict(step_time_s=T, com_height_m=H, clearance_m=0.1, vx_mps=0.5, vy_mps=0.1, step_width_m=0.2)
    base.update(kw)
    return Command(**base)


def est(**kw) -> StateEstimate:
    base = dict(stance="left", p_st_m=[0.03, -0.1, H], L_Nms=[1.5, 12.0, 0.2], v_z_mps=0.05, t_in_step_s=0.1,
                com_m=[1.0, 0.5, H])  # fmt: skip
    base.update(kw)
    return StateEstimate(**base)


#: A 3-D robot's outputs (hip yaws and a toe) and a planar robot's, in their order.
OUT3 = (
    "torso_pitch", "torso_roll", "stance_hip_yaw", "swing_hip_yaw", "com_z_over_stance",
    "com_x_over_swing", "com_y_over_swing", "com_z_over_swing", "swing_toe_pitch",
)  # fmt: skip
OUT2 = ("torso_pitch", "com_z_over_stance", "com_x_over_swing", "com_z_over_swing")
