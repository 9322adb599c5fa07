"""The output map ``h_0(q)`` of docs/ARCHITECTURE.md, with its Jacobian and drift.

Two layouts (:func:`output_layout`: a bundled robot's profile names it, any
other model gets the one it fits), named like the planner's references
(:data:`amlip_qp.alip.outputs.ROBOT_OUTPUTS`):

- ``cassie`` (9 outputs; needs a free root, ``{side}-hip-yaw`` joints and
  toe/heel sites): ``torso_pitch, torso_roll, stance_hip_yaw, swing_hip_yaw,
  com_z_over_stance, com_x_over_swing, com_y_over_swing, com_z_over_swing,
  swing_toe_pitch``.
- ``rabbit`` (4 outputs; a planar root moving in the x-z plane):
  ``torso_pitch, com_z_over_stance, com_x_over_swing, com_z_over_swing``.

Angles in rad, distances in m. ``heading_rad`` is the step's heading ``D``;
``x_D = (cos D, sin D, 0)``, ``y_D = (-sin D, cos D, 0)``.

Each output is built from primitive quantities (rotation-matrix entries,
points, joint angles) whose value, Jacobian row and drift are known, and the
chain rule: ``J_y = grad f . J_x`` and
``Jdot_v_y = grad f . Jdot_v_x + xdot^T Hess f xdot``.

This runs every control tick, so the scalar chain rule works on plain Python
floats packed in tuples (a "chain scalar", below) and each Jacobian row is
written with one or two numpy calls into preallocated scratch space; no
per-scalar objects are created. The floating-point operations are those of
the plain per-row formulas (no reordering, no fused BLAS products), so the
results are the same to the last bit.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from amlip_qp.alip import other_side
from amlip_qp.alip import outputs as _alip_outputs
from amlip_qp.alip.formulas import world_to_heading_xy
from amlip_qp.exceptions import InputError, MJCFError

if TYPE_CHECKING:  # pragma: no cover - typing only
    from amlip_qp.robots.kinematics import RobotKinematics
    from amlip_qp.robots.robot import Robot

# One definition of the output names, shared with the planner's references.
#: Cassie's nine outputs, in order.
CASSIE_OUTPUTS: tuple[str, ...] = _alip_outputs.CASSIE_OUTPUTS
#: The planar (Rabbit) layout's four outputs, in order.
PLANAR_OUTPUTS: tuple[str, ...] = _alip_outputs.RABBIT_OUTPUTS


# A "chain scalar" is a tuple ``(val, rate, c0, c1, c2, jdv)``: a scalar
# function of the state with its value, its time derivative ``J v``, its
# Jacobian as three coefficients ``(c0, c1, c2)`` on the rows of a 3 x nv basis
# Jacobian chosen by the caller (the base's angular Jacobian for rotation
# entries, the toe-minus-heel point Jacobian for the foot pitch) and its drift
# ``Jdot v``. Units follow the quantity (rad or m; per s; per s^2).


def _atan2(a: tuple, b: tuple) -> tuple:
    """``atan2(a, b)`` of two chain scalars, with the chain rule.

    ``y' = (b a' - a b') / r^2`` and
    ``y'' = (b a'' - a b'') / r^2 - 2 (b a' - a b') (a a' + b b') / r^4``.
    """
    av, ar, a0, a1, a2, aj = a
    bv, br, b0, b1, b2, bj = b
    r2 = av * av + bv * bv
    num = bv * ar - av * br
    ka, kb = bv / r2, -av / r2
    jdv = (bv * aj - av * bj) / r2 - 2.0 * num * (av * ar + bv * br) / (r2 * r2)
    return (math.atan2(av, bv), num / r2, ka * a0 + kb * b0, ka * a1 + kb * b1, ka * a2 + kb * b2, jdv)


def _hypot(a: tuple, b: tuple) -> tuple:
    """``sqrt(a^2 + b^2)`` of two chain scalars, with the chain rule.

    ``rho' = (a a' + b b') / rho`` and
    ``rho'' = (a a'' + b b'' + a'^2 + b'^2) / rho - (a a' + b b')^2 / rho^3``.
    """
    av, ar, a0, a1, a2, aj = a
    bv, br, b0, b1, b2, bj = b
    rho = math.hypot(av, bv)
    dot = av * ar + bv * br
    ka, kb = av / rho, bv / rho
    jdv = (av * aj + bv * bj + ar * ar + br * br) / rho - dot * dot / rho**3
    return (rho, dot / rho, ka * a0 + kb * b0, ka * a1 + kb * b1, ka * a2 + kb * b2, jdv)


def _neg(a: tuple) -> tuple:
    """``-a`` of a chain scalar."""
    return (-a[0], -a[1], -a[2], -a[3], -a[4], -a[5])


def _rotation_column(R: list, j: int, w: tuple, alpha: tuple) -> tuple:
    """Entries ``(R_0j, R_1j, R_2j)`` of a body's world rotation ``R`` (nested lists) as chain scalars.

    The basis is the body's angular Jacobian. With ``w`` the world angular
    velocity (rad/s) and ``alpha`` the angular acceleration drift (rad/s^2),
    the column ``r = r_j`` moves as ``dr = w x r``, its second-derivative drift
    is ``alpha x r + w x dr``, and ``d/dt R_ij = (r x e_i) . w`` gives the
    coefficients ``r x e_i``.
    """
    w0, w1, w2 = w
    a0, a1, a2 = alpha
    r0, r1, r2 = R[0][j], R[1][j], R[2][j]
    dr0, dr1, dr2 = w1 * r2 - w2 * r1, w2 * r0 - w0 * r2, w0 * r1 - w1 * r0
    return (
        (r0, dr0, 0.0, r2, -r1, (a1 * r2 - a2 * r1) + (w1 * dr2 - w2 * dr1)),
        (r1, dr1, -r2, 0.0, r0, (a2 * r0 - a0 * r2) + (w2 * dr0 - w0 * dr2)),
        (r2, dr2, r1, -r0, 0.0, (a0 * r1 - a1 * r0) + (w0 * dr1 - w1 * dr0)),
    )


def _rotation_entry_z(R: list, j: int, w: tuple, alpha: tuple) -> tuple:
    """The entry ``R_2j`` alone of :func:`_rotation_column` (the same arithmetic, fewer terms)."""
    w0, w1, w2 = w
    a0, a1, _ = alpha
    r0, r1, r2 = R[0][j], R[1][j], R[2][j]
    dr0, dr1 = w1 * r2 - w2 * r1, w2 * r0 - w0 * r2
    return (r2, w0 * r1 - w1 * r0, r1, -r0, 0.0, (a0 * r1 - a1 * r0) + (w0 * dr1 - w1 * dr0))


def _fitting_layout(robot: Robot) -> str | None:
    """The layout the model fits (``"cassie"``, ``"rabbit"``), or ``None``."""
    has_yaw = all(robot.role_joint("hip_yaw", s) is not None for s in robot.foot_sides)
    has_blade = all(len(robot.force_sites[s]) == 2 for s in robot.foot_sides)
    if robot.is_floating and has_yaw and has_blade:
        return "cassie"
    if robot.is_planar:
        return "rabbit"
    return None


def output_layout(robot: Robot) -> str:
    """The output layout of ``robot``, ``"cassie"`` or ``"rabbit"`` (also the planner's robot name).

    A bundled robot's comes from its profile (:mod:`amlip_qp.profiles`) and
    must fit its model; any other model gets the layout it fits (module doc).

    Raises:
        MJCFError: The model fits no layout, or not its profile's.
    """
    fits = _fitting_layout(robot)
    profile = robot.profile
    if profile is not None and profile.output_layout != fits:
        raise MJCFError(
            f"{robot.path}: the {profile.name!r} profile names the output layout {profile.output_layout!r}, "
            f"which this model does not fit (it fits {fits!r})"
        )
    if fits is None:
        raise MJCFError(
            f"{robot.path}: no output map: need a free root with {{side}}-hip-yaw joints and "
            "toe/heel sites (Cassie layout), or a planar root (Rabbit layout)"
        )
    return fits


def computes_standard_outputs(output_map) -> bool:
    """Whether ``output_map`` evaluates the robot's standard ``h_0``: its own class (not a base
    class) sets ``standard_outputs = True``, so a subclass that changes ``evaluate`` is not taken
    for the standard map unless it says so."""
    return vars(type(output_map)).get("standard_outputs") is True


class OutputMap:
    """``h_0(q)`` for one robot; evaluate on an updated :class:`RobotKinematics`.

    One instance keeps scratch buffers for :meth:`evaluate`: do not share it
    between threads.

    Attributes:
        layout: ``"cassie"`` or ``"rabbit"`` (:func:`output_layout`).
        names: Output names, in order.
        yaw_q_idx: Side -> Pinocchio ``q`` index of its hip-yaw joint (``cassie`` layout; empty otherwise).
        yaw_v_idx: Side -> Pinocchio ``v`` index of its hip-yaw joint (``cassie`` layout; empty otherwise).
    """

    #: This map evaluates the robot's standard ``h_0`` (docs/ARCHITECTURE.md), which generated code
    #: may then compute in its place (the QP tracker's in-place assembly). Read with
    #: :func:`computes_standard_outputs`: a subclass counts only if it sets the flag itself.
    standard_outputs = True

    def __init__(self, robot: Robot):
        """Pick the layout (:func:`output_layout`).

        Raises:
            MJCFError: The model fits no layout, or not its profile's.
        """
        self.robot = robot
        smap = robot.state_map
        self.layout = output_layout(robot)
        self.names = _alip_outputs.ROBOT_OUTPUTS[self.layout]
        self.yaw_q_idx: dict[str, int] = {}
        self.yaw_v_idx: dict[str, int] = {}
        if self.layout == "cassie":
            yaw = {s: robot.role_joint("hip_yaw", s) for s in robot.foot_sides}
            self.yaw_v_idx = {s: smap.joint_pin_v[yaw[s]] for s in robot.foot_sides}  # type: ignore[index]
            self.yaw_q_idx = {s: smap.joint_pin_q[yaw[s]] for s in robot.foot_sides}  # type: ignore[index]
        self._swing_of = {s: other_side(s) for s in robot.foot_sides}
        nv = robot.nv
        # Scratch (overwritten by every evaluate): J_c - J_sw, J_toe - J_heel (3 x nv each),
        # the heading rotation [[cD, sD], [-sD, cD]] and its products with the first two rows of J_c - J_sw.
        self._J_csw = np.empty((3, nv))
        self._J_blade = np.empty((3, nv))
        self._rot = np.empty((2, 2, 1))
        self._rot_products = np.empty((2, 2, nv))

    @property
    def size(self) -> int:
        """Number of outputs."""
        return len(self.names)

    def checked_swing(self, stance: str, heading_rad: float) -> str:
        """The swing side of ``stance``; :class:`InputError` for a bad side or a non-finite heading."""
        swing = self._swing_of.get(stance) if isinstance(stance, str) else None
        if swing is None:
            raise InputError(f"stance must be 'left' or 'right', got {stance!r}")
        if not math.isfinite(heading_rad):
            raise InputError(f"heading_rad must be finite, got {heading_rad!r}")
        return swing

    def evaluate(self, kin: RobotKinematics, stance: str, heading_rad: float = 0.0):
        """Outputs, Jacobian and drift at the last ``kin.update``.

        Args:
            kin: An updated :class:`~amlip_qp.robots.kinematics.RobotKinematics`.
            stance: Stance side, ``"left"`` or ``"right"``.
            heading_rad: Step heading ``D`` (rad).

        Returns:
            ``(y, J, Jdot_v)`` with shapes (n,), (n, nv), (n,): outputs (rad or
            m), their Jacobian on Pinocchio's ``v`` and their drift ``Jdot v``
            (rad/s^2 or m/s^2). New arrays on every call.

        Raises:
            InputError: Bad side or a non-finite heading.
        """
        swing = self.checked_swing(stance, heading_rad)
        robot = self.robot
        q, v = kin.state()
        jac = kin.frame_jacobian6  # world-aligned (linear rows, angular rows), cached per update
        J = np.zeros((len(self.names), v.shape[0]))

        # Base orientation: R, world angular velocity w = Jw v (rad/s), drift alpha (rad/s^2).
        base = robot.base_frame_id
        Jw = jac(base)[3:]
        w = tuple((Jw @ v).tolist())
        alpha = tuple(kin.frame_jdot_v6(base)[3:].tolist())
        R = kin.frame_rotation_view(base).tolist()

        # CoM relative to the two contact points (m) and the drifts (m/s^2).
        fid_st, fid_sw = robot.contact_frame_ids[stance], robot.contact_frame_ids[swing]
        c0, c1, c2 = kin.com_view.tolist()
        dc0, dc1, dc2 = kin.com_jdot_v().tolist()
        r0, r1, r2 = kin.frame_translation_view(fid_st).tolist()
        p_st_z = c2 - r2
        d_st_z = dc2 - kin.frame_jdot_v6(fid_st).tolist()[2]
        r0, r1, r2 = kin.frame_translation_view(fid_sw).tolist()
        p_sw = (c0 - r0, c1 - r1, c2 - r2)
        a_sw = kin.frame_jdot_v6(fid_sw).tolist()
        d_sw = (dc0 - a_sw[0], dc1 - a_sw[1], dc2 - a_sw[2])
        cD, sD = math.cos(heading_rad), math.sin(heading_rad)
        p_sw_x, p_sw_y = world_to_heading_xy(p_sw[0], p_sw[1], cD, sD)
        d_sw_x, d_sw_y = world_to_heading_xy(d_sw[0], d_sw[1], cD, sD)
        ys = [p_st_z, p_sw_x]
        ds = [d_st_z, d_sw_x]

        # Their Jacobian rows: c_z - r_st,z; (c - r_sw) . x_D; [(c - r_sw) . y_D]; c_z - r_sw,z.
        cassie = self.layout == "cassie"
        r_z, r_x, r_zs = (4, 5, 7) if cassie else (1, 2, 3)
        Jc = np.ascontiguousarray(kin.com_jacobian())  # Pinocchio's is column-major; rows are used here
        np.subtract(Jc[2], jac(fid_st)[2], out=J[r_z])
        J_csw = np.subtract(Jc, jac(fid_sw)[:3], out=self._J_csw)
        J[r_zs] = J_csw[2]
        rot, prod = self._rot, self._rot_products
        rot[0, 0, 0], rot[0, 1, 0], rot[1, 0, 0], rot[1, 1, 0] = cD, sD, -sD, cD
        np.multiply(rot, J_csw[:2], out=prod)  # prod[i, j] = rot[i, j] * J_csw[j]
        if cassie:
            np.add(prod[:, 0], prod[:, 1], out=J[r_x : r_x + 2])  # x_D and y_D rows
            ys.append(p_sw_y)
            ds.append(d_sw_y)
        else:
            np.add(prod[0, 0], prod[0, 1], out=J[r_x])
        ys.append(p_sw[2])
        ds.append(d_sw[2])

        if not cassie:
            R02, _, R22 = _rotation_column(R, 2, w, alpha)
            pitch = _atan2(R02, R22)
            np.dot(pitch[2:5], Jw, out=J[0])
            return np.array([pitch[0], *ys]), J, np.array([pitch[5], *ds])

        # Torso pitch and roll (intrinsic z-y-x Euler angles of the base).
        R00, R10, R20 = _rotation_column(R, 0, w, alpha)
        pitch = _atan2(_neg(R20), _hypot(R00, R10))
        roll = _atan2(_rotation_entry_z(R, 1, w, alpha), _rotation_entry_z(R, 2, w, alpha))
        np.dot(pitch[2:5], Jw, out=J[0])
        np.dot(roll[2:5], Jw, out=J[1])
        # Hip yaws: joint coordinates.
        yaw_q, yaw_v = self.yaw_q_idx, self.yaw_v_idx
        J[2, yaw_v[stance]] = 1.0
        J[3, yaw_v[swing]] = 1.0
        # Swing toe pitch from the blade vector d = toe - heel (m).
        toe_id, heel_id = robot.force_frame_ids[swing]
        t0, t1, t2 = kin.frame_translation_view(toe_id).tolist()
        h0, h1, h2 = kin.frame_translation_view(heel_id).tolist()
        d = (t0 - h0, t1 - h1, t2 - h2)
        Jd = np.subtract(jac(toe_id)[:3], jac(heel_id)[:3], out=self._J_blade)
        at, ah = kin.frame_jdot_v6(toe_id).tolist(), kin.frame_jdot_v6(heel_id).tolist()
        dd = (at[0] - ah[0], at[1] - ah[1], at[2] - ah[2])
        rd = (Jd @ v).tolist()
        # The components of d as chain scalars on the blade Jacobian (coefficients: unit vectors).
        dx = (d[0], rd[0], 1.0, 0.0, 0.0, dd[0])
        dy = (d[1], rd[1], 0.0, 1.0, 0.0, dd[1])
        dz = (d[2], rd[2], 0.0, 0.0, 1.0, dd[2])
        toe = _atan2(_neg(dz), _hypot(dx, dy))
        np.dot(toe[2:5], Jd, out=J[8])
        y = np.array([pitch[0], roll[0], q[yaw_q[stance]], q[yaw_q[swing]], *ys, toe[0]])
        jdv = np.array([pitch[5], roll[5], 0.0, 0.0, *ds, toe[5]])
        return y, J, jdv


def check_output_map(robot: Robot, output_map) -> None:
    """Check that ``output_map`` can stand in for ``OutputMap(robot)`` (as
    :attr:`RobotKinematics.output_map <amlip_qp.robots.kinematics.RobotKinematics.output_map>`):
    the same ``names``, a callable ``evaluate(kin, stance, heading_rad)`` and,
    if it has a ``robot``, the same ``nv``.

    Raises:
        InputError: It does not, naming the outputs it must evaluate.
    """
    names = OutputMap(robot).names
    other = getattr(output_map, "robot", robot)
    if (
        tuple(getattr(output_map, "names", ())) != tuple(names)
        or not callable(getattr(output_map, "evaluate", None))
        or other.nv != robot.nv
    ):
        raise InputError(f"output_map must evaluate the outputs {names} of {robot.name} (nv = {robot.nv})")
