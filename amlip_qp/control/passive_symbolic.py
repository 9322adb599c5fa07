"""The robot's passive forces as a CasADi expression of ``(q, v)``, for generated code.

The same forces as :class:`~amlip_qp.robots.passive.PassiveForces` (MuJoCo's
``qfrc_passive`` in Pinocchio coordinates, N m or N): joint springs
``-k (q - springref)`` on the hinge and slide joints, joint damping ``-b v``
on every dof, and per fixed tendon of length ``L = sum_i c_i q_i`` the force
``-k_t (L - clip(L, low, high)) - b_t dL/dt`` applied as ``c_i`` times it to
each of its joints. Tested equal to :class:`PassiveForces` to rounding.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import casadi as ca
import numpy as np

if TYPE_CHECKING:
    from amlip_qp.robots.robot import Robot


def passive_forces_expression(robot: Robot, q, v) -> ca.MX:
    """``taup(q, v)`` (nv,) for the robot's springs, dampers and tendons; ``q`` (nq,), ``v`` (nv,) CasADi vectors."""
    smap = robot.state_map
    nv = robot.nv
    pq, pv = [int(i) for i in smap.scalar_pin_q], [int(i) for i in smap.scalar_pin_v]
    parts = [-float(robot.dof_damping[i]) * v[i] for i in range(nv)]
    stiffness, springref = robot.dof_stiffness, robot.dof_springref
    for iq, iv in zip(pq, pv):
        if stiffness[iv] != 0.0:
            parts[iv] = parts[iv] - float(stiffness[iv]) * (q[iq] - float(springref[iv]))
    for c in robot.couplings:
        coef = [float(k) for k in np.asarray(c.coefficients)]
        length = sum(k * q[int(i)] for k, i in zip(coef, c.pin_q_idx))
        rate = sum(k * v[int(i)] for k, i in zip(coef, c.pin_v_idx))
        low, high = (float(x) for x in c.springlength)
        stretch = length - ca.fmin(ca.fmax(length, low), high)
        force = -float(c.stiffness) * stretch - float(c.damping) * rate
        for k, i in zip(coef, c.pin_v_idx):
            parts[int(i)] = parts[int(i)] + k * force
    return ca.vertcat(*parts)
