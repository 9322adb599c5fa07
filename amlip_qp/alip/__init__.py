"""The pure ALIP planner math (numpy only, no robot model).

Modules, each with one job:

- :mod:`~amlip_qp.alip.formulas`: the formulas written once for numpy and CasADi (no validation);
- :mod:`~amlip_qp.alip.kernels`: the dense per-tick kernels ``ALIP_PLAN`` and ``SWING_REFERENCE``;
- :mod:`~amlip_qp.alip.lip`: validated flow, predictor, momentum transfer, foot placement;
- :mod:`~amlip_qp.alip.desired`: desired angular momentum at the end of the next step;
- :mod:`~amlip_qp.alip.heading`: heading frames and the hip-yaw split of a turn;
- :mod:`~amlip_qp.alip.kalman`: scalar Kalman filters on ``L``;
- :mod:`~amlip_qp.alip.phase`: the gait phase ``s``;
- :mod:`~amlip_qp.alip.clock`: :class:`StepClock`, the stance side, step start and phase of the current step;
- :mod:`~amlip_qp.alip.outputs`: the reference outputs ``h_d(s)`` and their names;
- :mod:`~amlip_qp.alip.planner`: the :class:`Planner` a controller calls every tick (what goes in
  and out of it: :mod:`amlip_qp.messages`; its inputs checked: :mod:`~amlip_qp.alip.planner_inputs`).
- :mod:`~amlip_qp.alip.footholds`: :class:`FootholdPlane`, the ground plane from the last footholds (blind mode).
- :mod:`~amlip_qp.alip.command_shaping`: the rate limit of the velocity command before the planner.
- :mod:`~amlip_qp.alip.step_mpc`: the step-timing MPC's quadratic program (footholds and the step's duration);
- :mod:`~amlip_qp.alip.mpc_planner`: :class:`MPCPlanner`, the planner that solves it every tick.
"""

from amlip_qp.alip.clock import StepClock
from amlip_qp.alip.desired import (
    Lx_from_lateral_speed,
    Lx_from_step_width,
    Ly_from_forward_speed,
    desired_L_heading,
    desired_L_world,
    end_of_step_velocity,
    mean_step_velocity,
    mean_to_end_factor,
    other_side,
    stance_sign,
)
from amlip_qp.alip.footholds import FootholdPlane, GroundPlane
from amlip_qp.alip.formulas import GRAVITY_MPS2
from amlip_qp.alip.heading import heading_to_world, hip_yaw_targets, rotation, world_to_heading, yaw_of
from amlip_qp.alip.kalman import AngularMomentumFilter, MomentumFilter1D
from amlip_qp.alip.kernels import alip_plan, swing_reference
from amlip_qp.alip.lip import (
    flow,
    foot_placement,
    foot_placement_vz,
    omega,
    predict_end_of_step,
    transfer,
    transfer_3d,
    vz_limit,
)
from amlip_qp.alip.outputs import REFERENCE_OUTPUTS, OutputSet, reference_outputs
from amlip_qp.alip.phase import step_phase, step_phase_clipped, time_remaining
from amlip_qp.alip.planner import Planner

__all__ = [
    "GRAVITY_MPS2",
    "REFERENCE_OUTPUTS",
    "AngularMomentumFilter",
    "FootholdPlane",
    "GroundPlane",
    "Lx_from_lateral_speed",
    "Lx_from_step_width",
    "Ly_from_forward_speed",
    "MomentumFilter1D",
    "OutputSet",
    "Planner",
    "StepClock",
    "alip_plan",
    "desired_L_heading",
    "desired_L_world",
    "end_of_step_velocity",
    "flow",
    "foot_placement",
    "foot_placement_vz",
    "heading_to_world",
    "hip_yaw_targets",
    "mean_step_velocity",
    "mean_to_end_factor",
    "omega",
    "other_side",
    "predict_end_of_step",
    "reference_outputs",
    "rotation",
    "stance_sign",
    "step_phase",
    "step_phase_clipped",
    "swing_reference",
    "time_remaining",
    "transfer",
    "transfer_3d",
    "vz_limit",
    "world_to_heading",
    "yaw_of",
]
