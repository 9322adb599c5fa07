"""The simplified spring model of the paper's section "Springs": static deflections of the stance leg.

On the stance leg the springs deflect under the robot's weight; the paper
offsets the stance knee reference by an amount computed from a simplified
model rather than from the spring encoders (which made the robot oscillate).
The PBC holds the springs at these deflections in its IK
(:attr:`~amlip_qp.control.pbc.gains.PBCGains.spring_model_offset`), which
gives the knee offset exactly.

Simplified model: quasi-static stance leg loaded by a force at the stance
contact point: by default the whole weight ``m g`` (vertical), or a given
contact force -- the PBC passes its own commanded ground reaction of the
previous tick (a model quantity, not the spring encoders). The spring torques
that balance it are ``tau_s = -(J_c^T f)`` restricted to each spring's
direction (the shin joint; the coupling length ``q_knee + q_tarsus``), so each
spring deflects by ``tau_s / k`` (N m over N m/rad = rad). Its accuracy
against MuJoCo is measured in ``docs/TUNING.md`` ("PBC tracker and walking loop").
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from amlip_qp.alip.formulas import GRAVITY_MPS2

if TYPE_CHECKING:  # pragma: no cover - typing only
    from amlip_qp.robots.kinematics import RobotKinematics
    from amlip_qp.robots.robot import Robot


def spring_deflections_rad(kin: RobotKinematics, stance: str, force_N=None) -> np.ndarray:
    """Static deflections (rad) of the stance leg's springs under a contact force.

    Measured against MuJoCo in ``docs/TUNING.md`` ("PBC tracker and walking loop").

    Order: the passive joints outside couplings (Cassie: shin), then the
    couplings of the stance leg (Cassie: achilles, ``q_knee + q_tarsus``
    stretch). Zero-length for robots without springs.

    Args:
        kin: Updated :class:`~amlip_qp.robots.kinematics.RobotKinematics`.
        stance: Stance side.
        force_N: Ground reaction on the stance contact point (world axes, N),
            default ``(0, 0, m g)``.
    """
    robot = kin.robot
    if force_N is None:
        f = np.array([0.0, 0.0, kin.mass_kg * GRAVITY_MPS2])
    else:
        f = np.asarray(force_N, dtype=float).reshape(3)
    tau_ext = kin.contact_jacobian(stance).T @ f  # generalized force of the ground reaction
    joints, couplings = _stance_springs(robot, stance)
    out = []
    for s in joints:
        # statics of the passive joint (link weights neglected): -k d + tau_ext = 0
        iv = int(s.pin_v_idx[0])
        out.append(tau_ext[iv] / s.stiffness if s.stiffness > 0 else 0.0)
    for s in couplings:
        # the knee motor holds the knee; the tarsus balances its load with the
        # coupling spring: -k_c (L - L0) + tau_ext,tarsus = 0
        tarsus = int(s.pin_v_idx[-1])
        out.append(tau_ext[tarsus] / (s.stiffness * float(s.coefficients[-1])))
    return np.array(out)


def _stance_springs(robot: Robot, stance: str):
    """The stance leg's springs: ``(passive joints outside couplings, couplings with a spring)``."""
    rows = [s for s in robot.springs if s.side == stance]
    return [s for s in rows if s.kind == "joint"], [s for s in rows if s.kind == "coupling" and s.stiffness > 0]
