"""Stance-knee offset compensating the leg springs (paper section "Springs").

On the stance leg the springs deflect under the robot's weight; the paper adds
an offset to the stance knee reference, computed from a simplified model
rather than from the spring encoders (which made the robot oscillate).

Simplified model used here: quasi-static stance leg loaded by a force at the
stance contact point: by default the whole weight ``m g`` (vertical), or a
given contact force -- the PBC passes its own commanded ground reaction of the
previous tick (a model quantity, not the spring encoders). The spring
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


def spring_deflections_rad(kin, stance: str, force_N=None) -> np.ndarray:
    """Static deflections (rad) of the stance leg's springs under a contact force.

    Checked against MuJoCo (Cassie at 1 m/s, 2.5-5.9 s, tests/test_control_pbc.py
    and the engineer's report): the achilles coupling dominates (heel spring,
    1250 N m/rad: about 0.08 rad at mid-stance); the shin (1500 N m/rad) deflects
    about 0.003 rad. With ``m g`` the model gives 0.068 rad at mid-stance and
    misses the load transfer at the start of the step (rms error 0.017 rad over
    the stance phases 0.1-1); with the PBC's commanded contact force the rms
    error is 0.007 rad (mid-stance 0.076-0.084 rad predicted, 0.074-0.088
    measured). The "about twice the double-support stretch" of the full weight is
    the load share: standing on two feet each leg carries half the weight
    (0.031 rad measured at the keyframe).

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


def _stance_springs(robot, stance: str):
    """The stance leg's springs: ``(passive joints outside couplings, couplings with a spring)``."""
    rows = [s for s in robot.springs if s.side == stance]
    return [s for s in rows if s.kind == "joint"], [s for s in rows if s.kind == "coupling" and s.stiffness > 0]


def stance_knee_offset_rad(kin, stance: str, force_N=None, deflections=None) -> float:
    """First-order offset (rad) on the stance knee reference compensating the spring deflection.

    Compared with the exact compensation (the IK solved with the springs held at
    the measured deflections minus the IK with the springs at rest, Cassie at
    1 m/s, mid-stance) this first-order formula over-predicts by about 15 %
    (0.078 vs 0.068 rad from the same measured deflections): the PBC therefore
    compensates through the IK (:attr:`~amlip_qp.control.pbc.PBCGains.spring_model_offset`)
    and this function stays as the simple estimate.

    Args:
        kin: Updated kinematics.
        stance: Stance side.
        force_N: Contact force for :func:`spring_deflections_rad`.
        deflections: The deflections to compensate instead (same order).

    Returns 0 for robots without springs or without a ``{stance}-knee`` joint.
    """
    robot = kin.robot
    smap = robot.state_map
    knee = f"{stance}-knee"
    if knee not in smap.joint_pin_v or not robot.springs:
        return 0.0
    defl = spring_deflections_rad(kin, stance, force_N) if deflections is None else np.asarray(deflections, float)
    if defl.size == 0:
        return 0.0
    # vertical distance hip -> contact and its sensitivity to the leg joints
    Jz = kin.contact_jacobian(stance)[2]
    joints, couplings = _stance_springs(robot, stance)
    cols = [int(s.pin_v_idx[0]) for s in joints]
    tarsi = [int(s.pin_v_idx[-1]) for s in couplings]
    dz = float(sum(Jz[i] * d for i, d in zip(cols + tarsi, defl)))
    iv_knee = smap.joint_pin_v[knee]
    dz_dknee = float(Jz[iv_knee] - sum(Jz[t] for t in tarsi))  # the tarsus follows the knee (rigid rod)
    if abs(dz_dknee) < 1e-6:
        return 0.0
    return -dz / dz_dknee
