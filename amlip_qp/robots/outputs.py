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

import math

import numpy as np

from amlip_qp.alip import outputs as _alip_outputs
from amlip_qp.exceptions import InputError, MJCFError

# One definition of the output names, shared with the planner's references.
#: Cassie's nine outputs, in order.
CASSIE_OUTPUTS: tuple[str, ...] = _alip_outputs.CASSIE_OUTPUTS
#: The planar (Rabbit) layout's four outputs, in order.
PLANAR_OUTPUTS: tuple[str, ...] = _alip_outputs.RABBIT_OUTPUTS


class _Scalar:
    """A scalar function of the state, for the chain rule on plain floats.

    ``val`` is its value, ``rate`` its time derivative ``J v``, ``jdv`` its drift
    ``Jdot v``, and ``coef`` its Jacobian as three coefficients on the rows of a
    3 x nv basis Jacobian chosen by the caller (the base's angular Jacobian for
    rotation entries, the toe-minus-heel point Jacobian for the foot pitch).
    """

    __slots__ = ("val", "rate", "coef", "jdv")

    def __init__(self, val: float, rate: float, coef: tuple, jdv: float):
        self.val, self.rate, self.coef, self.jdv = val, rate, coef, jdv


def _lin(ka: float, a: tuple, kb: float, b: tuple) -> tuple:
    return (ka * a[0] + kb * b[0], ka * a[1] + kb * b[1], ka * a[2] + kb * b[2])


def _atan2(a: _Scalar, b: _Scalar) -> _Scalar:
    """``atan2(a, b)`` with the chain rule.

    ``y' = (b a' - a b') / r^2`` and
    ``y'' = (b a'' - a b'') / r^2 - 2 (b a' - a b') (a a' + b b') / r^4``.
    """
    r2 = a.val * a.val + b.val * b.val
    num = b.val * a.rate - a.val * b.rate
    coef = _lin(b.val / r2, a.coef, -a.val / r2, b.coef)
    jdv = (b.val * a.jdv - a.val * b.jdv) / r2 - 2.0 * num * (a.val * a.rate + b.val * b.rate) / (r2 * r2)
    return _Scalar(math.atan2(a.val, b.val), num / r2, coef, jdv)


def _hypot(a: _Scalar, b: _Scalar) -> _Scalar:
    """``sqrt(a^2 + b^2)`` with the chain rule.

    ``rho' = (a a' + b b') / rho`` and
    ``rho'' = (a a'' + b b'' + a'^2 + b'^2) / rho - (a a' + b b')^2 / rho^3``.
    """
    rho = math.hypot(a.val, b.val)
    dot = a.val * a.rate + b.val * b.rate
    coef = _lin(a.val / rho, a.coef, b.val / rho, b.coef)
    jdv = (a.val * a.jdv + b.val * b.jdv + a.rate * a.rate + b.rate * b.rate) / rho - dot * dot / rho**3
    return _Scalar(rho, dot / rho, coef, jdv)


def _neg(a: _Scalar) -> _Scalar:
    return _Scalar(-a.val, -a.rate, (-a.coef[0], -a.coef[1], -a.coef[2]), -a.jdv)


def _cross(a, b) -> tuple[float, float, float]:
    """``a x b`` for 3-vectors, on floats (numpy's cross costs ~20 µs on 3-vectors)."""
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


class _Rotation:
    """Entries of a body's world rotation ``R`` as :class:`_Scalar` (``r_j`` = column j).

    With ``w`` the world angular velocity, ``d/dt r_j = w x r_j``, so
    ``d/dt R_ij = (w x r_j)_i = (r_j x e_i) . w`` (coefficients on the rows of
    the angular Jacobian) and the drift of the second derivative is
    ``(alpha_d x r_j + w x (w x r_j))_i``.
    """

    def __init__(self, R, w, alpha_drift):
        self.R = R
        self.w = tuple(float(x) for x in w)
        self.alpha = tuple(float(x) for x in alpha_drift)
        self._cols: dict[int, tuple] = {}

    def _column(self, j: int) -> tuple:
        col = self._cols.get(j)
        if col is None:
            r = (float(self.R[0, j]), float(self.R[1, j]), float(self.R[2, j]))
            dr = _cross(self.w, r)
            ddr = _cross(self.alpha, r)
            wdr = _cross(self.w, dr)
            col = self._cols[j] = (r, dr, (ddr[0] + wdr[0], ddr[1] + wdr[1], ddr[2] + wdr[2]))
        return col

    def entry(self, i: int, j: int) -> _Scalar:
        r, dr, drift = self._column(j)
        if i == 0:
            coef = (0.0, r[2], -r[1])
        elif i == 1:
            coef = (-r[2], 0.0, r[0])
        else:
            coef = (r[1], -r[0], 0.0)
        return _Scalar(r[i], dr[i], coef, drift[i])


def _point(d, rate, drift, k: int) -> _Scalar:
    """Component ``k`` of a point offset whose Jacobian is the basis itself."""
    coef = (1.0 if k == 0 else 0.0, 1.0 if k == 1 else 0.0, 1.0 if k == 2 else 0.0)
    return _Scalar(float(d[k]), float(rate[k]), coef, float(drift[k]))


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
        n = len(self.names)
        y = np.empty(n)
        J = np.zeros((n, kin.model.nv))
        jdv = np.empty(n)
        Jw = kin.base_angular_jacobian()
        rot = _Rotation(kin.base_rotation(), Jw @ v, kin.base_angular_jdot_v())
        c, Jc, dc = kin.com(), kin.com_jacobian(), kin.com_jdot_v()
        p_st = c - kin.contact_position(stance)
        J_st = Jc - kin.contact_jacobian(stance)
        d_st = dc - kin.contact_jdot_v(stance)
        p_sw = c - kin.contact_position(swing)
        J_sw = Jc - kin.contact_jacobian(swing)
        d_sw = dc - kin.contact_jdot_v(swing)
        cD, sD = math.cos(heading_rad), math.sin(heading_rad)

        def angle(row: int, a: _Scalar, basis: np.ndarray) -> None:
            y[row] = a.val
            np.dot(a.coef, basis, out=J[row])
            jdv[row] = a.jdv

        def positions(rows: tuple[int, ...]) -> None:
            # com_z_over_stance, com_x_over_swing, (com_y_over_swing), com_z_over_swing
            r_z, r_x, r_y, r_zs = rows
            y[r_z], J[r_z], jdv[r_z] = p_st[2], J_st[2], d_st[2]
            y[r_x] = cD * p_sw[0] + sD * p_sw[1]
            J[r_x] = cD * J_sw[0] + sD * J_sw[1]
            jdv[r_x] = cD * d_sw[0] + sD * d_sw[1]
            if r_y is not None:
                y[r_y] = -sD * p_sw[0] + cD * p_sw[1]
                J[r_y] = -sD * J_sw[0] + cD * J_sw[1]
                jdv[r_y] = -sD * d_sw[0] + cD * d_sw[1]
            y[r_zs], J[r_zs], jdv[r_zs] = p_sw[2], J_sw[2], d_sw[2]

        if self.layout == "planar":
            angle(0, _atan2(rot.entry(0, 2), rot.entry(2, 2)), Jw)
            positions((1, 2, None, 3))
            return y, J, jdv

        angle(0, _atan2(_neg(rot.entry(2, 0)), _hypot(rot.entry(0, 0), rot.entry(1, 0))), Jw)
        angle(1, _atan2(rot.entry(2, 1), rot.entry(2, 2)), Jw)
        for row, side in ((2, stance), (3, swing)):
            y[row] = kin.q[self._yaw_q[side]]
            J[row, self._yaw_v[side]] = 1.0
            jdv[row] = 0.0
        positions((4, 5, 6, 7))
        toe_id, heel_id = self.robot.force_frame_ids[swing]
        d = kin.frame_position(toe_id) - kin.frame_position(heel_id)
        Jd = kin.frame_jacobian(toe_id) - kin.frame_jacobian(heel_id)
        dd = kin.frame_jdot_v(toe_id) - kin.frame_jdot_v(heel_id)
        rd = Jd @ v
        dx, dy, dz = (_point(d, rd, dd, k) for k in range(3))
        angle(8, _atan2(_neg(dz), _hypot(dx, dy)), Jd)
        return y, J, jdv
