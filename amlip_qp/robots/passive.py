"""Model-side passive forces and the joint-coupling constraints (pure numpy).

Both are derived from the MJCF's joint springs, dampers and fixed tendons as
read by the loader (:class:`~amlip_qp.robots.robot.Robot`), so they match
MuJoCo's ``qfrc_passive`` (converted to Pinocchio coordinates) for any model.
"""

from __future__ import annotations

import numpy as np

from amlip_qp.exceptions import InputError


def _checked(robot, q, v) -> tuple[np.ndarray, np.ndarray]:
    q = np.asarray(q, dtype=float)
    v = np.asarray(v, dtype=float)
    if q.shape != (robot.nq,) or v.shape != (robot.nv,):
        raise InputError(f"q, v must have shapes ({robot.nq},), ({robot.nv},); got {q.shape}, {v.shape}")
    if not (np.all(np.isfinite(q)) and np.all(np.isfinite(v))):
        raise InputError("q or v contains NaN or inf")
    return q, v


def tendon_force(coupling, length: float, rate: float) -> float:
    """MuJoCo's force along a fixed tendon (N m for hinge joints).

    Spring with a dead band: ``-k (L - clip(L, low, high))``; damping ``-b dL/dt``.

    Args:
        coupling: A :class:`~amlip_qp.robots.robot.Coupling`.
        length: Tendon length ``L`` (rad for hinge joints).
        rate: ``dL/dt``.
    """
    low, high = coupling.springlength
    stretch = length - min(max(length, low), high)
    return -coupling.stiffness * stretch - coupling.damping * rate


def passive_forces(robot, q, v) -> np.ndarray:
    """Passive generalized forces in Pinocchio coordinates, shape (nv,).

    Joint springs ``-k (q - springref)`` (hinge/slide joints), joint damping
    ``-b v`` (every dof) and fixed-tendon springs/dampers. This is MuJoCo's
    ``qfrc_passive`` mapped with ``f_pin = T^T f_mj`` (joint damping of a free
    joint is the same scalar on all six dofs, hence frame independent).

    Args:
        robot: The robot.
        q: Pinocchio configuration, shape (nq,).
        v: Pinocchio velocity, shape (nv,).
    """
    q, v = _checked(robot, q, v)
    return passive_forces_unchecked(robot, q, v)


def passive_forces_unchecked(robot, q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """:func:`passive_forces` without input validation, for callers that already checked ``(q, v)``."""
    smap = robot.state_map
    f = -robot.dof_damping * v
    pq, pv = smap.scalar_pin_q, smap.scalar_pin_v
    f[pv] -= robot.dof_stiffness[pv] * (q[pq] - robot.dof_springref[pv])
    for c in robot.couplings:
        length = float(c.coefficients @ q[c.pin_q_idx])
        rate = float(c.coefficients @ v[c.pin_v_idx])
        # A tendon couples distinct joints, so plain fancy-index addition is exact.
        f[c.pin_v_idx] += c.coefficients * tendon_force(c, length, rate)
    return f


def coupling_target(coupling) -> float:
    """The length a coupling constraint holds: the spring length (mid-point of a dead band)."""
    low, high = coupling.springlength
    return 0.5 * (low + high)


def coupling_constraints(robot, q, v) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Rigid versions of the fixed tendons: ``g(q) = sum_i c_i q_i - L0 = 0``.

    For Cassie this is ``q_tarsus + q_knee - 0.2269`` per side (the model's
    achilles tendons).

    Args:
        robot: The robot.
        q: Pinocchio configuration, shape (nq,).
        v: Pinocchio velocity, shape (nv,).

    Returns:
        ``(g, G, Gdot_v)``: residuals (n_c,), Jacobian (n_c, nv) and the
        drift ``Gdot v`` (n_c,), which is zero for these linear constraints.
    """
    q, v = _checked(robot, q, v)
    n = len(robot.couplings)
    g = np.zeros(n)
    G = np.zeros((n, robot.nv))
    for k, c in enumerate(robot.couplings):
        g[k] = float(c.coefficients @ q[c.pin_q_idx]) - coupling_target(c)
        np.add.at(G[k], c.pin_v_idx, c.coefficients)
    return g, G, np.zeros(n)
