"""The output map ``h_0(q)`` with its Jacobian and drift, as generated C.

:class:`~amlip_qp.robots.outputs.OutputMap` is the readable reference (a
scalar chain rule in Python). :class:`CompiledOutputMap` evaluates the same
outputs with C code that CasADi generates from the same definitions, and has
the same ``evaluate(kin, stance, heading_rad)`` interface, so it plugs into
:attr:`RobotKinematics.output_map <amlip_qp.robots.kinematics.RobotKinematics.output_map>`.

Python gathers the primitive quantities from Pinocchio (base rotation,
angular Jacobian and drift, the CoM, the contact points and, for Cassie, the
swing foot's toe and heel: positions, Jacobians, drifts). The generated code
applies the chain rule symbolically: with ``x`` the primitives (the base
rotation's entries, the points), ``y = f(x)``, ``J_y = df/dx J_x`` and
``Jdot_v_y = df/dx Jdot_v_x + xdot^T (d2f/dx2) xdot``, where a rotation
column ``r_j`` has ``J = -[r_j]x J_w`` and drift ``alpha x r_j + w x (w x r_j)``.
The hip-yaw outputs are joint coordinates and stay in Python.

The source depends only on the robot's layout and ``nv``: it is compiled
once into the codegen cache (see :mod:`amlip_qp.codegen.runtime`).

It lives in the walking loop: it needs CasADi and the codegen runtime, which
``robots`` may not import, and the walking controller is what installs it
(``WalkingController(output_backend="c")``); every tracker then reads it
through ``kin.outputs``.
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path
from typing import TYPE_CHECKING

import casadi as ca
import numpy as np

from amlip_qp.alip.formulas import world_to_heading_xy
from amlip_qp.codegen import generate, runtime
from amlip_qp.exceptions import CodegenError
from amlip_qp.robots.outputs import OutputMap

if TYPE_CHECKING:  # pragma: no cover - typing only
    from amlip_qp.robots.kinematics import RobotKinematics
    from amlip_qp.robots.robot import Robot

FUNCTION_NAME = "output_map"
SOURCE_FILE = "amlip_outputs.c"
LIBRARY_FILE = "libamlip_outputs.so"


def _skew(r):
    return ca.vertcat(
        ca.horzcat(0, -r[2], r[1]),
        ca.horzcat(r[2], 0, -r[0]),
        ca.horzcat(-r[1], r[0], 0),
    )


def _function(layout: str, nv: int) -> tuple[ca.Function, int, int]:
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
        Jx_parts.append(-ca.mtimes(_skew(r), Jw))
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


def generate_source(layout: str, nv: int) -> bytes:
    """The C source of the output map for a layout (``"cassie"`` or ``"rabbit"``) and ``nv``."""
    fn, _, _ = _function(layout, nv)
    cg = ca.CodeGenerator(SOURCE_FILE, dict(generate.CODEGEN_OPTIONS, with_header=False))
    cg.add(fn)
    with tempfile.TemporaryDirectory(prefix="amlip_qp_outputs_") as tmp:
        cg.generate(tmp + os.sep)
        source = (Path(tmp) / SOURCE_FILE).read_bytes()
    return generate.banner().encode("ascii") + source


class CompiledOutputMap:
    """Drop-in compiled :class:`~amlip_qp.robots.outputs.OutputMap` (see the module doc).

    Raises:
        CompilerUnavailableError: No C compiler.
        CodegenError: The compiler rejected the source or the library does not load.
    """

    def __init__(self, robot: Robot, cache_dir: str | os.PathLike | None = None):
        ref = OutputMap(robot)
        self.robot = robot
        self.layout, self.names = ref.layout, ref.names
        self._ref = ref
        self._yaw_q, self._yaw_v = ref.yaw_q_idx, ref.yaw_v_idx
        nv = robot.nv
        source = generate_source(self.layout, nv)
        self.library_path, functions = runtime.compile_and_load(
            source, [FUNCTION_NAME], SOURCE_FILE, LIBRARY_FILE, cache_dir
        )
        fn = functions[FUNCTION_NAME]
        n = len(self.names)
        self._JT = np.zeros((fn.nnz_in(0) // nv, nv))
        self._p = np.zeros(fn.nnz_in(1))
        self._y, self._J, self._jdv = np.zeros(n), np.zeros((n, nv)), np.zeros(n)
        self._buffer, self._eval = fn.buffer()
        # Stub limits: casadi's FunctionBuffer.set_arg/set_res stubs demand a size (the binding takes
        # it from the buffer); numpy's stubs declare ndarray a Buffer only for Python >= 3.12.
        for i, arr in enumerate((self._JT, self._p)):
            self._buffer.set_arg(i, memoryview(arr.reshape(-1)))  # type: ignore[call-arg, arg-type]
        for i, arr in enumerate((self._y, self._J, self._jdv)):
            if fn.nnz_out(i) != arr.size:
                raise CodegenError(f"{self.library_path}: {FUNCTION_NAME} output {i} has the wrong size")
            self._buffer.set_res(i, memoryview(arr.reshape(-1)))  # type: ignore[call-arg, arg-type]
        self._cassie = self.layout == "cassie"
        self._base = robot.base_frame_id
        # Per stance side: the frames of the packed input (stance contact, swing contact[, swing toe, heel]).
        self._frames = {
            stance: (robot.contact_frame_ids[stance], robot.contact_frame_ids[swing])
            + (tuple(robot.force_frame_ids[swing]) if self._cassie else ())
            for stance, swing in zip(robot.foot_sides, robot.foot_sides[::-1])
        }
        # Views of the inputs each primitive is copied into (``view[...] = x`` is the cheapest copy).
        JT, p = self._JT, self._p
        self._in_base = (JT[0:3], JT[3:6], p[0:9].reshape(3, 3), p[9:12], p[12:15], p[15:18])
        n_frames = len(self._frames[robot.foot_sides[0]])
        self._in_frames = tuple((JT[6 + 3 * i : 9 + 3 * i], p[18 + 6 * i : 21 + 6 * i], p[21 + 6 * i : 24 + 6 * i])
                                for i in range(n_frames))  # fmt: skip
        self._at = 18 + 6 * n_frames
        self._in_v = p[p.size - nv :]

    @property
    def size(self) -> int:
        """Number of outputs."""
        return len(self.names)

    def evaluate(self, kin: RobotKinematics, stance: str, heading_rad: float = 0.0):
        """Same contract as :meth:`OutputMap.evaluate <amlip_qp.robots.outputs.OutputMap.evaluate>`."""
        swing = self._ref.checked_swing(stance, heading_rad)
        q, v = kin.state()
        jac, acc = kin.frame_jacobian6, kin.frame_jdot_v6
        base = self._base
        Jw, Jc, R, alpha, com, com_drift = self._in_base
        Jw[...] = jac(base)[3:]
        Jc[...] = kin.com_jacobian()
        R[...] = kin.frame_rotation_view(base)  # row-major into the packed input
        alpha[...] = acc(base)[3:]
        com[...] = kin.com_view
        com_drift[...] = kin.com_jdot_v()
        for fid, (J_in, pos_in, drift_in) in zip(self._frames[stance], self._in_frames):
            J_in[...] = jac(fid)[:3]
            pos_in[...] = kin.frame_translation_view(fid)
            drift_in[...] = acc(fid)[:3]
        p, at = self._p, self._at
        if self._cassie:
            p[at] = q[self._yaw_q[stance]]
            p[at + 1] = q[self._yaw_q[swing]]
        p[at + 2] = heading_rad
        self._in_v[...] = v
        self._eval()
        J = self._J.copy()
        if self._cassie:
            J[2, self._yaw_v[stance]] = 1.0
            J[3, self._yaw_v[swing]] = 1.0
        return self._y.copy(), J, self._jdv.copy()
