"""Robot models: MJCF loading into MuJoCo and Pinocchio, state conversion, kinematics.

- :func:`load_robot` / :class:`Robot` (:mod:`.loader`, :mod:`.robot`): one
  MJCF file compiled by both libraries, described from the models.
- :mod:`.state`: MuJoCo ``(qpos, qvel)`` <-> Pinocchio ``(q, v)``.
- :class:`RobotKinematics` (:mod:`.kinematics`): CoM, centroidal momentum,
  ``L`` about a contact, contact Jacobians, ``M``, ``h``, passive forces,
  coupling constraints and the output map ``h_0`` (:mod:`.outputs`); the
  model's part (Pinocchio's passes, frames, CoM, momentum, ``M``, ``h``) is
  :class:`~amlip_qp.robots.model_kinematics.ModelKinematics` (:mod:`.model_kinematics`).
"""

from amlip_qp.robots.kinematics import RobotKinematics
from amlip_qp.robots.loader import load_robot
from amlip_qp.robots.outputs import OutputMap, output_names
from amlip_qp.robots.passive import coupling_constraints, passive_forces
from amlip_qp.robots.robot import FOOT_SIDES, ActuatorSet, Coupling, Robot
from amlip_qp.robots.state import (
    StateMap,
    bias_mj_to_pin,
    force_mj_to_pin,
    force_pin_to_mj,
    mass_matrix_mj_to_pin,
    mj_to_pin,
    pin_to_mj,
    q_to_qpos,
    qpos_to_q,
    qvel_to_v,
    v_to_qvel,
    velocity_map,
    velocity_map_dot_v,
)

__all__ = [
    "FOOT_SIDES",
    "ActuatorSet",
    "Coupling",
    "OutputMap",
    "Robot",
    "RobotKinematics",
    "StateMap",
    "bias_mj_to_pin",
    "coupling_constraints",
    "force_mj_to_pin",
    "force_pin_to_mj",
    "load_robot",
    "mass_matrix_mj_to_pin",
    "mj_to_pin",
    "output_names",
    "passive_forces",
    "pin_to_mj",
    "q_to_qpos",
    "qpos_to_q",
    "qvel_to_v",
    "v_to_qvel",
    "velocity_map",
    "velocity_map_dot_v",
]
