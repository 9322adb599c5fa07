"""Stance-knee offset compensating the leg springs (paper section "Springs").

On the stance leg the springs deflect under the robot's weight; the paper adds
an offset to the stance knee reference, computed from a simplified model
rather than from the spring encoders (which made the robot oscillate).

Simplified model used here: quasi-static single support with the whole weight
``m g`` carried as a vertical force at the stance contact point. The spring
torques that balance it are ``tau_s = -(J_c^T f)`` restricted to each spring's
direction (the shin joint; the coupling length ``q_knee + q_tarsus``), so each
spring deflects by ``tau_s / k`` (N m over N m/rad = rad). The knee offset is
the knee change that gives the same contact-to-hip vertical distance as these
deflections would take away, to first order:
``dq_knee = -(dz/dq_spring . defl) / (dz/dq_knee)``, where the knee column moves
the tarsus with it (rigid coupling) and ``z`` is the hip height over the
contact.
"""

from __future__ import annotations

import numpy as np

from amlip_qp.alip.formulas import GRAVITY_MPS2


def spring_deflections_rad(kin, stance: str) -> np.ndarray:
    """Static deflections (rad) of the stance leg's springs under the full weight.

    Order: the passive joints outside couplings (Cassie: shin), then the
    couplings of the stance leg (Cassie: achilles, ``q_knee + q_tarsus``
    stretch). Zero-length for robots without springs.

    Args:
        kin: Updated :class:`~amlip_qp.robots.kinematics.RobotKinematics`.
        stance: Stance side.
    """
    robot = kin.robot
    f = np.array([0.0, 0.0, kin.mass_kg * GRAVITY_MPS2])
    tau_ext = kin.contact_jacobian(stance).T @ f  # generalized force of the ground reaction
    out = []
    coupled = {int(i) for c in robot.couplings for i in c.pin_v_idx}
    for name, iv in zip(robot.passive_joint_names, robot.passive_v_idx):
        if int(iv) in coupled or not name.startswith(stance):
            continue
        k = float(robot.dof_stiffness[iv])
        # statics of the passive joint (link weights neglected): -k d + tau_ext = 0
        out.append(tau_ext[iv] / k if k > 0 else 0.0)
    for c in robot.couplings:
        if not c.name.startswith(stance) or c.stiffness <= 0:
            continue
        # the knee motor holds the knee; the tarsus balances its load with the
        # coupling spring: -k_c (L - L0) + tau_ext,tarsus = 0
        tarsus = int(c.pin_v_idx[-1])
        out.append(tau_ext[tarsus] / (c.stiffness * float(c.coefficients[-1])))
    return np.array(out)


def stance_knee_offset_rad(kin, stance: str) -> float:
    """Offset (rad) on the stance knee reference compensating the static spring deflection.

    Returns 0 for robots without springs or without a ``{stance}-knee`` joint.
    """
    robot = kin.robot
    smap = robot.state_map
    knee = f"{stance}-knee"
    if knee not in smap.joint_pin_v or not robot.couplings and len(robot.passive_v_idx) == 0:
        return 0.0
    defl = spring_deflections_rad(kin, stance)
    if defl.size == 0:
        return 0.0
    # vertical distance hip -> contact and its sensitivity to the leg joints
    Jz = kin.contact_jacobian(stance)[2]
    coupled = {int(i) for c in robot.couplings for i in c.pin_v_idx}
    cols = [int(iv) for name, iv in zip(robot.passive_joint_names, robot.passive_v_idx)
            if int(iv) not in coupled and name.startswith(stance)]
    tarsi = [int(c.pin_v_idx[-1]) for c in robot.couplings if c.name.startswith(stance) and c.stiffness > 0]
    dz = float(sum(Jz[i] * d for i, d in zip(cols + tarsi, defl)))
    iv_knee = smap.joint_pin_v[knee]
    dz_dknee = float(Jz[iv_knee] - sum(Jz[t] for t in tarsi))  # the tarsus follows the knee (rigid rod)
    if abs(dz_dknee) < 1e-6:
        return 0.0
    return -dz / dz_dknee
