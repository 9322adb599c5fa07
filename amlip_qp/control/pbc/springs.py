"""The simplified spring model of the paper's section "Springs": static deflections of the stance leg.

On the stance leg the springs deflect under the robot's weight; the paper
offsets the stance knee reference by an amount computed from a simplified
model rather than from the spring encoders (which made the robot oscillate).
The PBC holds the springs at these deflections in its IK
(:attr:`~amlip_qp.control.pbc.gains.PBCGains.spring_model_offset`), which
gives the knee offset exactly.

Simplified model: quasi-static stance leg loaded by a force at the stance
contact point: by default the whole weight ``m g`` (vertical), or a given
contact force. The spring torques that balance it follow from the
generalized force of the load, ``tau = J_c^T f``, on each spring's
coordinate (the shin joint; the coupling length ``q_knee + q_tarsus``), so
each spring deflects by torque over stiffness (N m over N m/rad = rad).

The achilles linkage (:class:`~amlip_qp.control.pbc.gains.AchillesLinkage`). The controller's model
(``cassie.xml``) closes Cassie's leg loop with a tendon spring of 1250 N m/rad
on ``q_knee + q_tarsus`` and nothing on the shin. On the robot (and on the
closed-chain plant ``cassie-closed-chain.xml``, the parameter sheet's full
tree) the achilles rod runs from the hip-pitch body to a heel-spring lever on
the tarsus, so

- the rod also has a moment arm about the shin (knee-spring) joint, 1.36 times
  its arm about the tarsus joint: the rod's tension loads the knee spring;
- the heel spring (1250 N m/rad) sits behind a lever: its arm is 0.81 times
  the tarsus arm, so a rotation of the tarsus turns the heel spring 1.24
  times as far.

With the rod's length fixed (``a_s dq_shin + a_t dq_tarsus + a_h dq_heel = 0``
with the knee held, ``a_*`` the rod's moment arms), the statics of the
tarsus, shin and heel spring give, with ``r_s = a_s / a_t`` and
``r_h = a_h / a_t``::

    T = -tau_t / a_t                                   (rod tension)
    q_shin = (tau_s - r_s tau_t) / k_shin
    stretch = q_knee + q_tarsus - L0 = -r_s q_shin + r_h^2 tau_t / k_heel

The tendon of ``cassie.xml`` is the special case ``r_s = 0``, ``r_h = 1``,
``k_heel = 1250``. Measured numbers and the reasons are in ``docs/TUNING.md``
("Spring model").
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from amlip_qp.alip.formulas import GRAVITY_MPS2
from amlip_qp.exceptions import InputError

if TYPE_CHECKING:  # pragma: no cover - typing only
    from amlip_qp.control.pbc.gains import AchillesLinkage
    from amlip_qp.robots.kinematics import RobotKinematics
    from amlip_qp.robots.robot import Robot


def spring_deflections_rad(
    kin: RobotKinematics, stance: str, force_N=None, linkage: AchillesLinkage | None = None
) -> np.ndarray:
    """Static deflections (rad) of the stance leg's springs under a contact force.

    Order: the passive joints outside couplings (Cassie: shin), then the
    couplings of the stance leg (Cassie: achilles, ``q_knee + q_tarsus``
    stretch). Zero-length for robots without springs.

    Args:
        kin: Updated :class:`~amlip_qp.robots.kinematics.RobotKinematics`.
        stance: Stance side.
        force_N: Ground reaction on the stance contact point (world axes, N),
            default ``(0, 0, m g)``.
        linkage: The leg's achilles linkage (module doc), or ``None`` for the
            controller model's own springs (each spring balances its own
            coordinate's load: the tendon of ``cassie.xml``). A linkage needs
            exactly one passive joint and one coupling on the stance leg.

    Raises:
        InputError: A linkage on a leg that is not one shin plus one coupling.
    """
    robot = kin.robot
    if force_N is None:
        f = np.array([0.0, 0.0, kin.mass_kg * GRAVITY_MPS2])
    else:
        f = np.asarray(force_N, dtype=float).reshape(3)
    tau_ext = np.dot(kin.contact_jacobian(stance).T, f)  # generalized force of the ground reaction
    joints, couplings = _stance_springs(robot, stance)
    if linkage is not None:
        if len(joints) != 1 or len(couplings) != 1:
            raise InputError(
                f"{robot.name}: an achilles linkage needs one passive joint and one coupling on the "
                f"{stance} leg, found {len(joints)} and {len(couplings)}"
            )
        return _linkage_deflections(linkage, joints[0], couplings[0], tau_ext)
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


def _linkage_deflections(linkage: AchillesLinkage, shin, coupling, tau_ext: np.ndarray) -> np.ndarray:
    """``[q_shin, stretch]`` (rad) of one leg through its achilles linkage (module doc)."""
    tau_s = float(tau_ext[int(shin.pin_v_idx[0])])
    tau_t = float(tau_ext[int(coupling.pin_v_idx[-1])]) / float(coupling.coefficients[-1])
    r_s, r_h = linkage.shin_ratio, linkage.heel_ratio
    q_shin = (tau_s - r_s * tau_t) / shin.stiffness
    stretch = -r_s * q_shin + r_h * r_h * tau_t / linkage.heel_stiffness_Nmprad
    return np.array([q_shin, stretch])


def _stance_springs(robot: Robot, stance: str):
    """The stance leg's springs: ``(passive joints outside couplings, couplings with a spring)``."""
    rows = [s for s in robot.springs if s.side == stance]
    return [s for s in rows if s.kind == "joint"], [s for s in rows if s.kind == "coupling" and s.stiffness > 0]
