"""The output map ``h_0(q)`` with its Jacobian and drift as a CasADi function of Pinocchio's primitives.

The symbolic form shared by the generated output map
(:mod:`amlip_qp.control.walking.outputs_compiled`) and the QP tracker's
in-place assembly (:mod:`amlip_qp.control.wbc.compiled_in_place`), which
composes it with the frame terms it reads from Pinocchio's data. The readable reference is
:class:`~amlip_qp.robots.outputs.OutputMap`; the chain rule is described in
:mod:`amlip_qp.control.walking.outputs_compiled`.

Arguments of the function: ``JT`` (nv x n_jac): the transposed Jacobians of the
base's angular velocity, the CoM and the frames (stance contact, swing
contact, and for Cassie the swing toe and heel), world-aligned; ``packed``: the
base rotation (row-major), its angular drift, the CoM and its drift, each
frame's position and drift, the two hip-yaw angles (Cassie), the heading and
``v``. Outputs: ``y``, ``JyT`` (without the hip-yaw rows' ones, which the
callers set) and ``jdv``. SI units: m, rad, m/s^2, rad/s^2.
"""

from __future__ import annotations

import casadi as ca

from amlip_qp.alip.formulas import world_to_heading_xy

FUNCTION_NAME = "output_map"


def skew(r):
    """``[r]x`` (CasADi): ``skew(r) @ x == r x x``."""
    return ca.vertcat(
        ca.horzcat(0, -r[2], r[1]),
        ca.horzcat(r[2], 0, -r[0]),
        ca.horzcat(-r[1], r[0], 0),
    )


def output_map_function(layout: str, nv: int) -> tuple[ca.Function, int, int]:
    """The symbolic output map; returns ``(function, n_jacobian_rows, n_packed)``."""
    cassie = layout == "cassie"
    n_frames = 4 if cassie else 2  # stance contact, swing contact[, toe, heel]
    n_jac = 3 * (2 + n_frames)  # base angular, CoM, frames
    n_packed = 9 + 3 + 6 + 6 * n_frames + 3 + nv
    JT = ca.SX.sym("JT", nv, n_jac)
    p = ca.SX.sym("packed", n_packed)
    J = JT.T
    Rv, alpha = p[0:9], p[9:12]
    R = ca.reshape(Rv, 3, 3).T  # row-major
    at = 12
    com, com_drift = p[at : at + 3], p[at + 3 : at + 6]
    at += 6
    pos, drifts = [], []
    for _ in range(n_frames):
        pos.append(p[at : at + 3])
        drifts.append(p[at + 3 : at + 6])
        at += 6
    q_yaw_st, q_yaw_sw, heading = p[at], p[at + 1], p[at + 2]
    v = p[at + 3 : at + 3 + nv]
    Jw, Jc = J[0:3, :], J[3:6, :]
    Jf = [J[6 + 3 * i : 9 + 3 * i, :] for i in range(n_frames)]
    w = ca.mtimes(Jw, v)

    # Primitives x (values as fresh symbols for differentiation), their Jacobians and drifts.
    cols = [0, 2] if not cassie else [0, 1, 2]
    X_parts, Jx_parts, dx_parts, val_parts = [], [], [], []
    for j in cols:
        r = R[:, j]
        X_parts.append(ca.SX.sym(f"R{j}", 3))
        val_parts.append(r)
        Jx_parts.append(-ca.mtimes(skew(r), Jw))
        dx_parts.append(ca.cross(alpha, r) + ca.cross(w, ca.cross(w, r)))
    for value, jac, drift in [(com, Jc, com_drift)] + list(zip(pos, Jf, drifts)):
        X_parts.append(ca.SX.sym("p", 3))
        val_parts.append(value)
        Jx_parts.append(jac)
        dx_parts.append(drift)
    X = ca.vertcat(*X_parts)
    c, r_st, r_sw = X_parts[len(cols)], X_parts[len(cols) + 1], X_parts[len(cols) + 2]
    cD, sD = ca.cos(heading), ca.sin(heading)
    p_sw = c - r_sw
    p_sw_x, p_sw_y = world_to_heading_xy(p_sw[0], p_sw[1], cD, sD)
    if cassie:
        R0, R1, R2 = X_parts[0], X_parts[1], X_parts[2]  # columns 0, 1, 2
        pitch = ca.atan2(-R0[2], ca.hypot(R0[0], R0[1]))
        roll = ca.atan2(R1[2], R2[2])
        toe, heel = X_parts[len(cols) + 3], X_parts[len(cols) + 4]
        d = toe - heel
        toe_pitch = ca.atan2(-d[2], ca.hypot(d[0], d[1]))
        y = ca.vertcat(pitch, roll, 0, 0, c[2] - r_st[2], p_sw_x, p_sw_y, p_sw[2], toe_pitch)
    else:
        R0, R2 = X_parts[0], X_parts[1]  # columns 0 and 2
        pitch = ca.atan2(R2[0], R2[2])
        y = ca.vertcat(pitch, c[2] - r_st[2], p_sw_x, p_sw[2])
    grad = ca.jacobian(y, X)
    xdot_sym = ca.SX.sym("xdot", X.shape[0])
    curv = ca.vertcat(*[ca.mtimes([xdot_sym.T, ca.hessian(y[i], X)[0], xdot_sym]) for i in range(y.shape[0])])
    Jx, dx, xval = ca.vertcat(*Jx_parts), ca.vertcat(*dx_parts), ca.vertcat(*val_parts)
    xdot = ca.mtimes(Jx, v)
    Jy = ca.mtimes(grad, Jx)
    jdv = ca.mtimes(grad, dx) + curv
    subst = ca.substitute([y, Jy, jdv], [X, xdot_sym], [xval, xdot])
    y_out, Jy_out, jdv_out = subst
    if cassie:
        y_out[2], y_out[3] = q_yaw_st, q_yaw_sw
    fn = ca.Function(
        FUNCTION_NAME, [JT, p], [ca.densify(y_out), ca.densify(Jy_out.T), ca.densify(jdv_out)],
        ["JT", "packed"], ["y", "JyT", "jdv"],
    )  # fmt: skip
    return fn, n_jac, n_packed
