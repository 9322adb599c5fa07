"""The output map ``h_0(q)`` with its Jacobian and drift as a CasADi function of Pinocchio's primitives.

The symbolic form shared by the generated output map
(:mod:`amlip_qp.control.walking.outputs_compiled`) and the QP tracker's
in-place assembly (:mod:`amlip_qp.control.wbc.compiled_in_place`), which
composes it with the frame terms it reads from Pinocchio's data. The readable reference is
:class:`~amlip_qp.robots.outputs.OutputMap`; the chain rule is described in
:mod:`amlip_qp.control.walking.outputs_compiled`. Both are built from the
same declaration, the robot's outputs (:mod:`amlip_qp.profiles.outputs`) and
what they read (:class:`OutputInputs`).

Arguments of the function: ``JT`` (nv x n_jac): the transposed Jacobians,
world-aligned, of the base's angular velocity, the CoM, the points (the
stance contact, the swing contact, then the swing foot's first and last
force points if a ``swing_toe_pitch`` output reads them) and the angular
velocity of the rotating frames (the swing contact frame if a
``swing_foot_roll`` output reads it); ``packed``: the base rotation
(row-major) and its angular drift, the CoM and its drift, each point's
position and drift, each rotating frame's rotation (row-major) and angular
drift, the joint outputs' angles (in output order), the heading and ``v``.
Outputs: ``y``, ``JyT`` (without the joint outputs' ones, which the callers
set) and ``jdv``. SI units: m, rad, m/s^2, rad/s^2.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import casadi as ca

from amlip_qp.alip.formulas import world_to_heading_xy
from amlip_qp.profiles.outputs import OutputPrimitive

FUNCTION_NAME = "output_map"


@dataclass(frozen=True)
class OutputInputs:
    """What a list of outputs reads, in the function's argument order (module doc).

    Attributes:
        points: The points, each ``"stance_contact"``, ``"swing_contact"``, ``"swing_toe"``
            (the swing foot's first force point) or ``"swing_heel"`` (its last).
        rotations: The rotating frames besides the base: ``"swing_contact"`` or none.
        joints: Index of each joint output among the outputs, in order.
        base_columns: The base rotation's columns the base angles read.
    """

    points: tuple[str, ...]
    rotations: tuple[str, ...]
    joints: tuple[int, ...]
    base_columns: tuple[int, ...]

    @property
    def n_jacobian_rows(self) -> int:
        """Rows of ``JT``'s transpose: base angular, CoM, each point, each rotating frame's angular."""
        return 3 * (2 + len(self.points) + len(self.rotations))

    def n_packed(self, nv: int) -> int:
        """Size of ``packed`` for ``nv`` velocities."""
        return 9 + 3 + 6 + 6 * len(self.points) + 12 * len(self.rotations) + len(self.joints) + 1 + nv


def output_inputs(primitives: Sequence[OutputPrimitive], planar: bool) -> OutputInputs:
    """What ``primitives`` read (:class:`OutputInputs`); ``planar``: the root moves in the x-z plane."""
    points = ["stance_contact", "swing_contact"]
    if any(p.kind == "foot_angle" and p.axis == "pitch" for p in primitives):
        points += ["swing_toe", "swing_heel"]
    rotations = ("swing_contact",) if any(p.kind == "foot_angle" and p.axis == "roll" for p in primitives) else ()
    columns: set[int] = set()
    for p in primitives:
        if p.kind == "base_angle":
            # pitch: atan2(R_02, R_22) about a planar root's y axis, else z-y-x Euler (column 0);
            # roll: z-y-x Euler (columns 1 and 2). A planar root keeps column 0 beside (its x axis).
            columns |= {0, 2} if planar else ({0} if p.axis == "pitch" else {1, 2})
    joints = tuple(i for i, p in enumerate(primitives) if p.kind == "joint")
    return OutputInputs(tuple(points), rotations, joints, tuple(sorted(columns)))


def skew(r):
    """``[r]x`` (CasADi): ``skew(r) @ x == r x x``."""
    return ca.vertcat(
        ca.horzcat(0, -r[2], r[1]),
        ca.horzcat(r[2], 0, -r[0]),
        ca.horzcat(-r[1], r[0], 0),
    )


def _euler_pitch(R0):
    """Pitch of z-y-x Euler angles from a rotation's column 0."""
    return ca.atan2(-R0[2], ca.hypot(R0[0], R0[1]))


def _euler_roll(R1, R2):
    """Roll of z-y-x Euler angles from a rotation's columns 1 and 2."""
    return ca.atan2(R1[2], R2[2])


def output_map_function(
    primitives: Sequence[OutputPrimitive], planar: bool, nv: int
) -> tuple[ca.Function, OutputInputs]:
    """The symbolic output map of ``primitives``; returns ``(function, what it reads)``."""
    reads = output_inputs(primitives, planar)
    n_points, n_rot = len(reads.points), len(reads.rotations)
    JT = ca.SX.sym("JT", nv, reads.n_jacobian_rows)
    p = ca.SX.sym("packed", reads.n_packed(nv))
    J = JT.T
    Rv, alpha = p[0:9], p[9:12]
    R = ca.reshape(Rv, 3, 3).T  # row-major
    at = 12
    com, com_drift = p[at : at + 3], p[at + 3 : at + 6]
    at += 6
    pos, drifts = [], []
    for _ in range(n_points):
        pos.append(p[at : at + 3])
        drifts.append(p[at + 3 : at + 6])
        at += 6
    frame_R, frame_alpha = [], []
    for _ in range(n_rot):
        frame_R.append(ca.reshape(p[at : at + 9], 3, 3).T)
        frame_alpha.append(p[at + 9 : at + 12])
        at += 12
    joint_values = [p[at + k] for k in range(len(reads.joints))]
    at += len(reads.joints)
    heading = p[at]
    v = p[at + 1 : at + 1 + nv]
    Jw, Jc = J[0:3, :], J[3:6, :]
    Jf = [J[6 + 3 * i : 9 + 3 * i, :] for i in range(n_points)]
    Jrot = [J[6 + 3 * (n_points + i) : 9 + 3 * (n_points + i), :] for i in range(n_rot)]
    w = ca.mtimes(Jw, v)

    # Primitives x (values as fresh symbols for differentiation), their Jacobians and drifts.
    X_parts, Jx_parts, dx_parts, val_parts = [], [], [], []

    def rotation_column(Rm, j, Jang, w_ang, alpha_ang, label):
        r = Rm[:, j]
        X_parts.append(ca.SX.sym(f"{label}{j}", 3))
        val_parts.append(r)
        Jx_parts.append(-ca.mtimes(skew(r), Jang))
        dx_parts.append(ca.cross(alpha_ang, r) + ca.cross(w_ang, ca.cross(w_ang, r)))
        return X_parts[-1]

    base_cols = {j: rotation_column(R, j, Jw, w, alpha, "R") for j in reads.base_columns}
    point_sym = {}
    for name, value, jac, drift in [("com", com, Jc, com_drift)] + list(zip(reads.points, pos, Jf, drifts)):
        X_parts.append(ca.SX.sym("p", 3))
        val_parts.append(value)
        Jx_parts.append(jac)
        dx_parts.append(drift)
        point_sym[name] = X_parts[-1]
    frame_cols = {}
    for name, Rm, Jang, alpha_ang in zip(reads.rotations, frame_R, Jrot, frame_alpha):
        w_ang = ca.mtimes(Jang, v)
        frame_cols[name] = (rotation_column(Rm, 1, Jang, w_ang, alpha_ang, "F"),
                            rotation_column(Rm, 2, Jang, w_ang, alpha_ang, "F"))  # fmt: skip
    X = ca.vertcat(*X_parts)
    c = point_sym["com"]
    cD, sD = ca.cos(heading), ca.sin(heading)
    y_parts = []
    rel_to: dict[str, tuple] = {}  # contact -> (CoM minus it, its heading-frame x and y), built once
    for prim in primitives:
        if prim.kind == "base_angle" and prim.axis == "pitch":
            y_parts.append(ca.atan2(base_cols[2][0], base_cols[2][2]) if planar else _euler_pitch(base_cols[0]))
        elif prim.kind == "base_angle":
            y_parts.append(_euler_roll(base_cols[1], base_cols[2]))
        elif prim.kind == "joint":
            y_parts.append(0)  # the joint's angle, set below
        elif prim.kind == "com_over_contact":
            if prim.side not in rel_to:
                rel = c - point_sym[f"{prim.side}_contact"]
                rel_to[prim.side] = (rel, *world_to_heading_xy(rel[0], rel[1], cD, sD))
            rel, rel_x, rel_y = rel_to[prim.side]
            y_parts.append(rel[2] if prim.axis == "z" else rel_x if prim.axis == "x" else rel_y)
        elif prim.axis == "pitch":  # the swing foot's pitch, toe minus heel
            d = point_sym["swing_toe"] - point_sym["swing_heel"]
            y_parts.append(ca.atan2(-d[2], ca.hypot(d[0], d[1])))
        else:  # the swing foot's roll, its contact frame's columns 1 and 2
            y_parts.append(_euler_roll(*frame_cols["swing_contact"]))
    y = ca.vertcat(*y_parts)
    grad = ca.jacobian(y, X)
    xdot_sym = ca.SX.sym("xdot", X.shape[0])
    curv = ca.vertcat(*[ca.mtimes([xdot_sym.T, ca.hessian(y[i], X)[0], xdot_sym]) for i in range(y.shape[0])])
    Jx, dx, xval = ca.vertcat(*Jx_parts), ca.vertcat(*dx_parts), ca.vertcat(*val_parts)
    xdot = ca.mtimes(Jx, v)
    Jy = ca.mtimes(grad, Jx)
    jdv = ca.mtimes(grad, dx) + curv
    subst = ca.substitute([y, Jy, jdv], [X, xdot_sym], [xval, xdot])
    y_out, Jy_out, jdv_out = subst
    for i, value in zip(reads.joints, joint_values):
        y_out[i] = value
    fn = ca.Function(
        FUNCTION_NAME, [JT, p], [ca.densify(y_out), ca.densify(Jy_out.T), ca.densify(jdv_out)],
        ["JT", "packed"], ["y", "JyT", "jdv"],
    )  # fmt: skip
    return fn, reads


def output_map_on_terms(outputs, terms, stance: str, q, v, heading):
    """``h_0``'s ``(y, JyT, jdv)`` for ``stance`` as expressions of Pinocchio's terms read in place.

    Args:
        outputs: The robot's :class:`~amlip_qp.robots.outputs.OutputMap` (what it reads:
            ``points``, ``rotating_frames``, ``joint_indices``, ``joint_rows``, ``primitives``,
            ``planar``, ``robot``).
        terms: A :class:`~amlip_qp.codegen.frame_terms.FrameTerms` holding the base frame, the
            stance's points and rotating frames, with the base and the rotating frames' rotations.
        stance: The stance side.
        q, v: CasADi expressions of the configuration (nq,) and velocity (nv,).
        heading: The heading ``D`` (rad), a CasADi scalar.

    Returns:
        ``(y, JyT, jdv)`` (CasADi), the joint outputs' Jacobian entries included (structural
        ones in ``JyT``).
    """
    nv = outputs.robot.nv
    T = terms
    base = outputs.robot.base_frame_id
    frames, rotating = outputs.points(stance), outputs.rotating_frames(stance)
    JT = ca.horzcat(
        T.jacobian(base)[3:6, :].T, T.Jcom.T, *[T.jacobian(f)[0:3, :].T for f in frames],
        *[T.jacobian(f)[3:6, :].T for f in rotating],
    )  # fmt: skip
    q_idx, v_idx = outputs.joint_indices(stance)
    packed = ca.vertcat(
        ca.reshape(T.rotation(base).T, 9, 1), T.drift(base)[3:6], T.com, T.acom,
        *[ca.vertcat(T.position(f), T.drift(f)[0:3]) for f in frames],
        *[ca.vertcat(ca.reshape(T.rotation(f).T, 9, 1), T.drift(f)[3:6]) for f in rotating],
        *[q[i] for i in q_idx], heading, v,
    )  # fmt: skip
    y, JyT, jdv = output_map_function(outputs.primitives, outputs.planar, nv)[0](JT, packed)
    if q_idx:
        rows, cols = list(v_idx), list(outputs.joint_rows)
        n_out = len(outputs.primitives)
        JyT = JyT + ca.DM(ca.Sparsity.triplet(nv, n_out, rows, cols), 1.0)  # structural zeros there
    return y, JyT, jdv
