"""The output map ``h_0(q)`` of docs/ARCHITECTURE.md, with its Jacobian and drift.

Two layouts, chosen from the model:

- ``cassie`` (9 outputs; needs ``{side}-hip-yaw`` joints and toe/heel sites):
  ``torso_pitch, torso_roll, stance_hip_yaw, swing_hip_yaw,
  com_z_over_stance, com_x_over_swing, com_y_over_swing, com_z_over_swing,
  swing_toe_pitch``.
- ``planar`` (4 outputs; a planar root moving in the x-z plane, e.g. Rabbit):
  ``torso_pitch, com_z_over_stance, com_x_over_swing, com_z_over_swing``.

Angles in rad, distances in m. ``heading_rad`` is the step's heading ``D``;
``x_D = (cos D, sin D, 0)``, ``y_D = (-sin D, cos D, 0)``.

Each output is built from primitive quantities (rotation-matrix entries,
points, joint angles) whose value, Jacobian row and drift are known, and the
chain rule: ``J_y = grad f . J_x`` and
``Jdot_v_y = grad f . Jdot_v_x + xdot^T Hess f xdot``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from amlip_qp.exceptions import InputError, MJCFError

CASSIE_OUTPUTS: tuple[str, ...] = (
    "torso_pitch",
    "torso_roll",
    "stance_hip_yaw",
    "swing_hip_yaw",
    "com_z_over_stance",
    "com_x_over_swing",
    "com_y_over_swing",
    "com_z_over_swing",
    "swing_toe_pitch",
)
PLANAR_OUTPUTS: tuple[str, ...] = (
    "torso_pitch",
    "com_z_over_stance",
    "com_x_over_swing",
    "com_z_over_swing",
)


@dataclass(frozen=True)
class _Scalar:
    """A scalar function of the state: value, Jacobian row (nv,), drift ``Jdot v``."""

    val: float
    jac: np.ndarray
    jdv: float


def _combine(value: float, grad, hess, args, v) -> _Scalar:
    """Chain rule for ``f(args)`` with gradient ``grad`` and Hessian ``hess`` at ``args``."""
    jac = sum(g * a.jac for g, a in zip(grad, args))
    rates = np.array([a.jac @ v for a in args])
    jdv = float(sum(g * a.jdv for g, a in zip(grad, args)) + rates @ hess @ rates)
    return _Scalar(float(value), jac, jdv)


def _atan2(a: _Scalar, b: _Scalar, v) -> _Scalar:
    """``atan2(a, b)``."""
    r2 = a.val**2 + b.val**2
    grad = (b.val / r2, -a.val / r2)
    hab = (a.val**2 - b.val**2) / r2**2
    hess = np.array([[-2 * a.val * b.val / r2**2, hab], [hab, 2 * a.val * b.val / r2**2]])
    return _combine(np.arctan2(a.val, b.val), grad, hess, (a, b), v)


def _hypot(a: _Scalar, b: _Scalar, v) -> _Scalar:
    """``sqrt(a^2 + b^2)``."""
    rho = np.hypot(a.val, b.val)
    grad = (a.val / rho, b.val / rho)
    hess = np.array([[b.val**2, -a.val * b.val], [-a.val * b.val, a.val**2]]) / rho**3
    return _combine(rho, grad, hess, (a, b), v)


def _neg(a: _Scalar) -> _Scalar:
    return _Scalar(-a.val, -a.jac, -a.jdv)


class _Rotation:
    """Entries of a body's world rotation ``R`` as :class:`_Scalar` (``r_j`` = column j).

    ``d/dt R_ij = e_i . (w x r_j) = (r_j x e_i) . w`` and the drift of the
    second derivative is ``e_i . (alpha_d x r_j + w x (w x r_j))``.
    """

    def __init__(self, R, J_ang, alpha_drift, v):
        self.R, self.J, self.v = R, J_ang, v
        self.w = J_ang @ v
        self.alpha = alpha_drift

    def entry(self, i: int, j: int) -> _Scalar:
        r_j = self.R[:, j]
        e_i = np.eye(3)[i]
        jac = np.cross(r_j, e_i) @ self.J
        jdv = float(e_i @ (np.cross(self.alpha, r_j) + np.cross(self.w, np.cross(self.w, r_j))))
        return _Scalar(float(self.R[i, j]), jac, jdv)


def _component(pos, jac, jdv, axis: np.ndarray) -> _Scalar:
    return _Scalar(float(axis @ pos), axis @ jac, float(axis @ jdv))


class OutputMap:
    """``h_0(q)`` for one robot; evaluate on an updated :class:`RobotKinematics`.

    Attributes:
        layout: ``"cassie"`` or ``"planar"``.
        names: Output names, in order.
    """

    def __init__(self, robot):
        """Pick the layout from the model.

        Raises:
            MJCFError: The model fits neither layout.
        """
        self.robot = robot
        smap = robot.state_map
        has_yaw = all(f"{s}-hip-yaw" in smap.joint_pin_v for s in robot.foot_sides)
        has_blade = all(len(robot.force_sites[s]) == 2 for s in robot.foot_sides)
        if robot.is_floating and has_yaw and has_blade:
            self.layout, self.names = "cassie", CASSIE_OUTPUTS
            self._yaw_v = {s: smap.joint_pin_v[f"{s}-hip-yaw"] for s in robot.foot_sides}
            self._yaw_q = {s: smap.joint_pin_q[f"{s}-hip-yaw"] for s in robot.foot_sides}
        elif robot.is_planar:
            self.layout, self.names = "planar", PLANAR_OUTPUTS
        else:
            raise MJCFError(
                f"{robot.path}: no output map: need a free root with {{side}}-hip-yaw joints and "
                "toe/heel sites (Cassie layout), or a planar root (Rabbit layout)"
            )

    @property
    def size(self) -> int:
        """Number of outputs."""
        return len(self.names)

    def evaluate(self, kin, stance: str, heading_rad: float = 0.0):
        """Outputs, Jacobian and drift at the last ``kin.update``.

        Args:
            kin: An updated :class:`~amlip_qp.robots.kinematics.RobotKinematics`.
            stance: Stance side, ``"left"`` or ``"right"``.
            heading_rad: Step heading ``D`` (rad).

        Returns:
            ``(y, J, Jdot_v)`` with shapes (n,), (n, nv), (n,).

        Raises:
            InputError: Bad side or a non-finite heading.
        """
        if stance not in self.robot.foot_sides:
            raise InputError(f"stance must be 'left' or 'right', got {stance!r}")
        if not np.isfinite(heading_rad):
            raise InputError(f"heading_rad must be finite, got {heading_rad!r}")
        swing = self.robot.other_side(stance)
        v = kin.v
        rot = _Rotation(kin.base_rotation(), kin.base_angular_jacobian(), kin.base_angular_jdot_v(), v)
        c, Jc, dc = kin.com(), kin.com_jacobian(), kin.com_jdot_v()
        r_st = kin.contact_position(stance)
        p_st, J_st, d_st = c - r_st, Jc - kin.contact_jacobian(stance), dc - kin.contact_jdot_v(stance)
        p_sw = c - kin.contact_position(swing)
        J_sw = Jc - kin.contact_jacobian(swing)
        d_sw = dc - kin.contact_jdot_v(swing)
        ez = np.array([0.0, 0.0, 1.0])
        xD = np.array([np.cos(heading_rad), np.sin(heading_rad), 0.0])
        yD = np.array([-np.sin(heading_rad), np.cos(heading_rad), 0.0])

        if self.layout == "planar":
            outs = [
                _atan2(rot.entry(0, 2), rot.entry(2, 2), v),
                _component(p_st, J_st, d_st, ez),
                _component(p_sw, J_sw, d_sw, xD),
                _component(p_sw, J_sw, d_sw, ez),
            ]
        else:
            pitch = _atan2(_neg(rot.entry(2, 0)), _hypot(rot.entry(0, 0), rot.entry(1, 0), v), v)
            roll = _atan2(rot.entry(2, 1), rot.entry(2, 2), v)
            nv = kin.model.nv

            def joint(side: str) -> _Scalar:
                row = np.zeros(nv)
                row[self._yaw_v[side]] = 1.0
                return _Scalar(float(kin.q[self._yaw_q[side]]), row, 0.0)

            toe_id, heel_id = self.robot.force_frame_ids[swing]
            d = kin.frame_position(toe_id) - kin.frame_position(heel_id)
            Jd = kin.frame_jacobian(toe_id) - kin.frame_jacobian(heel_id)
            dd = kin.frame_jdot_v(toe_id) - kin.frame_jdot_v(heel_id)
            e = np.eye(3)
            dx, dy, dz = (_component(d, Jd, dd, e[k]) for k in range(3))
            toe_pitch = _atan2(_neg(dz), _hypot(dx, dy, v), v)
            outs = [
                pitch,
                roll,
                joint(stance),
                joint(swing),
                _component(p_st, J_st, d_st, ez),
                _component(p_sw, J_sw, d_sw, xD),
                _component(p_sw, J_sw, d_sw, yD),
                _component(p_sw, J_sw, d_sw, ez),
                toe_pitch,
            ]
        y = np.array([o.val for o in outs])
        J = np.vstack([o.jac for o in outs])
        jdv = np.array([o.jdv for o in outs])
        return y, J, jdv
