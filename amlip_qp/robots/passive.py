"""Model-side passive forces and the joint-coupling constraints (pure numpy).

Both are derived from the MJCF's joint springs, dampers and fixed tendons as
read by the loader (:class:`~amlip_qp.robots.robot.Robot`), so they match
MuJoCo's ``qfrc_passive`` (converted to Pinocchio coordinates) for any model.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from amlip_qp.exceptions import InputError
from amlip_qp.robots.robot import Robot


def _checked(robot: Robot, q, v) -> tuple[np.ndarray, np.ndarray]:
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


def passive_forces(robot: Robot, q, v) -> np.ndarray:
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


def passive_forces_unchecked(robot: Robot, q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """:func:`passive_forces` without input validation, for callers that already checked ``(q, v)``.

    A caller that evaluates the forces every tick should keep a
    :class:`PassiveForces` instead (this builds one per call).
    """
    return PassiveForces(robot)(q, v)


def contiguous_index(idx: np.ndarray) -> slice | np.ndarray:
    """``idx`` as a slice when it is a contiguous increasing range (cheaper to index with), else unchanged."""
    if idx.size and np.array_equal(idx, np.arange(idx[0], idx[0] + idx.size)):
        return slice(int(idx[0]), int(idx[0]) + idx.size)
    return idx


class PassiveForces:
    """:func:`passive_forces` for one robot with its constants precomputed (the per-tick path).

    Call with a checked Pinocchio state ``(q, v)`` (shapes (nq,), (nv,)) to get
    the passive generalized forces (N m or N), shape (nv,): the arithmetic of
    :func:`passive_forces`, with the index gathers of the constant terms
    done once here.

    A tendon of two joints with coefficients +-1 (Cassie's achilles rods) gets
    its length and rate as Python floats, ``0.0 + k0 q0 + k1 q1``: the products
    are exact, so that is the rounding of the exact sum, bit for bit what the
    numpy dot of the general path gives, at a third of its cost.
    """

    def __init__(self, robot: Robot):
        smap = robot.state_map
        pv = smap.scalar_pin_v
        self._neg_damping = -robot.dof_damping
        self._pq, self._pv = contiguous_index(smap.scalar_pin_q), contiguous_index(pv)
        self._stiffness = robot.dof_stiffness[pv]
        self._springref = robot.dof_springref[pv]
        # Per tendon, in model order: the coupling, then for a +-1 pair ``(iq0, iq1, iv0, iv1, k0, k1)``
        # and ``None``; else ``None`` and its coefficients, q and v indices, and (index, coefficient) pairs.
        tendons: list[tuple] = []
        for c in robot.couplings:
            coef = [float(k) for k in c.coefficients]
            if len(coef) == 2 and all(abs(k) == 1.0 for k in coef):
                pair = (*(int(i) for i in c.pin_q_idx), *(int(i) for i in c.pin_v_idx), *coef)
                tendons.append((c, pair, None))
            else:
                general = (c.coefficients, c.pin_q_idx, c.pin_v_idx, tuple(zip(c.pin_v_idx.tolist(), coef)))
                tendons.append((c, None, general))
        self._tendons = tuple(tendons)
        self._lists = any(pair is not None for _, pair, _ in tendons)

    def __call__(self, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        f = self._neg_damping * v
        pv = self._pv
        f[pv] -= self._stiffness * (q[self._pq] - self._springref)
        if self._lists:
            ql, vl = q.tolist(), v.tolist()
        for c, pair, general in self._tendons:
            if pair is not None:
                iq0, iq1, iv0, iv1, k0, k1 = pair
                force = tendon_force(c, 0.0 + k0 * ql[iq0] + k1 * ql[iq1], 0.0 + k0 * vl[iv0] + k1 * vl[iv1])
                f[iv0] += k0 * force
                f[iv1] += k1 * force
                continue
            coef, iq, iv, pairs = general
            force = tendon_force(c, float(coef.dot(q[iq])), float(coef.dot(v[iv])))
            # A tendon couples distinct joints: one addition per joint.
            for i, k in pairs:
                f[i] += k * force
        return f


@dataclass(frozen=True)
class SpringRow:
    """One spring of the robot as a linear function of the joint coordinates.

    The deflection is ``g = sum_i coefficients[i] q[pin_q_idx[i]] - rest``
    (rad for hinge joints) and its rate ``sum_i coefficients[i]
    v[pin_v_idx[i]]``: for a passive joint with its own spring (``kind ==
    "joint"``) the joint angle minus its ``springref``; for a fixed tendon
    (``kind == "coupling"``, Cassie's achilles rod: knee + tarsus) its length
    minus :func:`coupling_target`.

    Attributes:
        name: The joint's or the tendon's name.
        kind: ``"joint"`` or ``"coupling"``.
        side: The leg (``"left"``/``"right"``) whose joints carry the spring,
            or ``None`` when its joints span both legs or neither.
        pin_q_idx: Pinocchio configuration indices of the joints.
        pin_v_idx: Pinocchio velocity indices of the joints.
        coefficients: The row's coefficients.
        rest: The rest value, rad.
        stiffness: The spring stiffness, N m/rad (0: a joint without a spring).
    """

    name: str
    kind: str
    side: str | None
    pin_q_idx: np.ndarray
    pin_v_idx: np.ndarray
    coefficients: np.ndarray
    rest: float
    stiffness: float

    def row_q(self, nq: int) -> np.ndarray:
        """The deflection's coefficients on the whole configuration, shape (nq,)."""
        row = np.zeros(nq)
        np.add.at(row, self.pin_q_idx, self.coefficients)
        return row

    def row_v(self, nv: int) -> np.ndarray:
        """The deflection rate's coefficients on the whole velocity (its Jacobian), shape (nv,)."""
        row = np.zeros(nv)
        np.add.at(row, self.pin_v_idx, self.coefficients)
        return row


def _side_of(robot: Robot, joint_names) -> str | None:
    sides = {s for s in robot.foot_sides for name in joint_names if name.startswith(s)}
    counted = all(any(name.startswith(s) for s in robot.foot_sides) for name in joint_names)
    return sides.pop() if len(sides) == 1 and counted else None


def spring_rows(robot: Robot) -> tuple[SpringRow, ...]:
    """The robot's springs, the one enumeration every tracker uses (read
    them from :attr:`Robot.springs <amlip_qp.robots.robot.Robot.springs>`,
    which the loader fills once).

    Order: the fixed tendons (couplings) in model order, then the passive
    joints outside every coupling in model order (Cassie: per leg the achilles
    rod, then the shin). Passive joints inside a coupling (Cassie's tarsus)
    are not springs of their own: the coupling row holds them. A passive joint
    outside the couplings is listed even without stiffness (``stiffness ==
    0``); callers choose whether such a free joint is held.
    """
    rows = []
    for c in robot.couplings:
        rows.append(SpringRow(
            name=c.name, kind="coupling", side=_side_of(robot, c.joint_names),
            pin_q_idx=np.asarray(c.pin_q_idx, dtype=int), pin_v_idx=np.asarray(c.pin_v_idx, dtype=int),
            coefficients=np.asarray(c.coefficients, dtype=float), rest=coupling_target(c),
            stiffness=float(c.stiffness),
        ))  # fmt: skip
    coupled = {int(i) for c in robot.couplings for i in c.pin_v_idx}
    for name, vi, qi in zip(robot.passive_joint_names, robot.passive_v_idx, robot.passive_q_idx):
        if int(vi) in coupled:
            continue
        rows.append(SpringRow(
            name=name, kind="joint", side=_side_of(robot, (name,)),
            pin_q_idx=np.array([int(qi)]), pin_v_idx=np.array([int(vi)]), coefficients=np.ones(1),
            rest=float(robot.dof_springref[vi]), stiffness=float(robot.dof_stiffness[vi]),
        ))  # fmt: skip
    return tuple(rows)


def coupling_target(coupling) -> float:
    """The length a coupling constraint holds: the spring length (mid-point of a dead band)."""
    low, high = coupling.springlength
    return 0.5 * (low + high)


def coupling_constraints(robot: Robot, q, v) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
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
