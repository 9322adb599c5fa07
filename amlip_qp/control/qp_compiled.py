"""The whole-body QP's per-tick assembly as generated, compiled C.

:meth:`WholeBodyQP.build <amlip_qp.control.qp_formulation.WholeBodyQP.build>`
is the readable reference: about 75 numpy calls per tick, each cheap, whose
Python overhead made the assembly the largest part of the controller tick
(more than the solve). :class:`CompiledBuild` writes the same problem with
one call of C code that CasADi generates from the same formulas:

- Python still evaluates what needs Pinocchio or the references: the
  dynamics terms ``h - taup``, the force-point Jacobians, the output task's
  ``(J, r)`` with the pelvis-yaw feedback, the swing force ramp ``w``;
- the generated function (one per stance side, the stance's constants
  baked in) forms everything else straight into the problem's arrays: the
  row map ``R [M | -Jf^T]`` (dynamics equalities, torque map, rigid-spring
  forces), the contact and rigid-spring rows, torque limits (with
  ``stance_foot_torque_max_Nm``), the swing pyramid lifting, the joint-limit
  and force boxes, and the cost ``H0 + E^T E``, ``g`` (with the stance yaw
  moment penalty).

The C source depends on the robot and the :class:`QPConfig` (its constants
are baked in). It is compiled once into the codegen cache (see
:mod:`amlip_qp.codegen.runtime`: the same compiler, flags and cache folder,
keyed by the source's hash) and called through ``Function.buffer()`` with
inputs and outputs bound once to preallocated arrays, so a call costs about
a microsecond plus the arithmetic. The results equal the Python build to
rounding (tested to 1e-12 relative on random states, both robots, both
stances, three phases, the default configs and variants without rigid
springs, with the pre-touchdown force blend and without the yaw penalty).

Measured in isolation on Cassie (same states, same machine): 22 µs against
62 µs for the Python build with its two add-ons; in the closed loop the
tracker's build went from 185 to 116 µs median.
"""

from __future__ import annotations

import math
import os
import tempfile
from pathlib import Path

import casadi as ca
import numpy as np

from amlip_qp.codegen import generate, runtime
from amlip_qp.exceptions import CodegenError, InputError

#: Name stem of the generated functions (``<stem>_left``, ``<stem>_right``).
FUNCTION_STEM = "wbqp_build"
#: File names inside the cache folder.
SOURCE_FILE = "amlip_wbqp.c"
LIBRARY_FILE = "libamlip_wbqp.so"


def _dm(a) -> ca.DM:
    return ca.DM(np.asarray(a, dtype=float))


def small_layout(builder) -> dict:
    """Slices of the packed small input ``u``: ``q``, ``v``, ``contact`` (Cassie:
    stance toe and heel positions, m, and drifts, m/s^2; planar: the point's
    drift), ``r`` (output task residual), ``w`` (swing force ramp); and its ``size``."""
    nq, nv = builder.robot.nq, builder._layout.nv
    n_con = 12 if builder._layout.n_points == 2 else len(builder._axes)
    sizes = {"q": nq, "v": nv, "contact": n_con, "r": builder.output_task.size, "w": 1}
    out, at = {}, 0
    for name, size in sizes.items():
        out[name] = slice(at, at + size)
        at += size
    out["size"] = at
    return out


class _Symbolic:
    """The per-stance CasADi function of the assembly (see the module doc)."""

    def __init__(self, builder, stance: str):
        B, robot = builder, builder.robot
        L, cfg = B._layout, B.config
        nv, nq, n = L.nv, robot.nq, L.n
        d, k = len(B._axes), L.n_points
        nf = d * k
        P = B.problem
        n_eq, n_in = P.n_eq, P.n_in
        nu = B._act_v.size
        n_out = B.output_task.size
        rs = B._stance_rows(stance)
        swing = robot.other_side(stance)
        nd = B._sl_dyn.stop
        small = small_layout(builder)

        Mu = ca.MX.sym("M_upper", nv, nv)
        hp = ca.MX.sym("hp", nv)
        JfT = ca.MX.sym("JfT", nv, 2 * nf)
        JoT = ca.MX.sym("JoT", nv, n_out)
        u = ca.MX.sym("u", small["size"])
        q, v = u[small["q"]], u[small["v"]]
        con, r, w = u[small["contact"]], u[small["r"]], u[small["w"]]

        M = ca.triu(Mu) + ca.triu(Mu, False).T
        D = ca.horzcat(M, -JfT)
        RD = ca.mtimes(_dm(rs.R), D)
        Rhp = ca.mtimes(_dm(rs.R), hp)
        T, tau0 = RD[nd : nd + nu, :], Rhp[nd : nd + nu]
        Lam, lam0 = RD[nd + nu :, :], Rhp[nd + nu :]

        # Equalities: dynamics, contact, rigid springs.
        Jf = JfT.T
        if k == 2:
            p0, p1, jdv0, jdv1 = con[0:3], con[3:6], con[6:9], con[9:12]
            ax = p0 - p1
            ax = ax / ca.norm_2(ax)
            n1 = ca.vertcat(-ax[2] * ax[0], -ax[2] * ax[1], 1.0 - ax[2] * ax[2])
            n1 = n1 / ca.norm_2(n1)
            N = ca.horzcat(n1, ca.cross(ax, n1)).T
            Ac = ca.vertcat(Jf[0:3, :], ca.mtimes(N, Jf[3:6, :]))
            drift = ca.vertcat(jdv0, ca.mtimes(N, jdv1))
        else:
            Ac, drift = Jf[0:d, :], con
        bc = -cfg.contact_kd * ca.mtimes(Ac, v) - drift
        A = ca.vertcat(RD[:nd, :], ca.horzcat(Ac, ca.MX(Ac.shape[0], n - nv)))
        b = ca.vertcat(-Rhp[:nd], bc)
        if L.n_lambda:
            A = ca.vertcat(A, ca.horzcat(_dm(rs.G), ca.MX(L.n_lambda, n - nv)))
            b = ca.vertcat(b, _dm(rs.kp_offs) - ca.mtimes(_dm(rs.kpGq), q) - ca.mtimes(_dm(rs.kdG), v))
        assert A.shape == (n_eq, n)

        # Torque limits (the stance foot motor bounded as limit_stance_foot_torque does).
        lo, hi = B._tau_lo.copy(), B._tau_hi.copy()
        i_foot = B._stance_foot_index(stance)
        lim = cfg.stance_foot_torque_max_Nm
        if i_foot is not None and math.isfinite(lim):
            lo[i_foot] = max(lo[i_foot], -lim)
            hi[i_foot] = min(hi[i_foot], lim)
        l_tau = _dm(lo) - tau0
        n_fric = n_in - nu
        lifted = ca.if_else(w == 0.0, math.inf, 0.0)
        u_all = ca.vertcat(_dm(hi) - tau0, ca.DM.zeros(n_fric // 2), ca.repmat(lifted, n_fric // 2, 1))

        # Box: joint limits of the swing leg's actuated joints, force boxes.
        vi, qi, c_lo, c_hi, other = B._limits_by_swing[swing]
        hz, rec = cfg.joint_limit_horizon_s, cfg.joint_limit_max_recovery
        Sv = np.zeros((vi.size, nv))
        Sv[np.arange(vi.size), vi] = 1.0
        Sq = np.zeros((qi.size, nq))
        Sq[np.arange(qi.size), qi] = 1.0
        t = (ca.mtimes(_dm(Sq), q) + ca.mtimes(_dm(Sv), v) * hz) * (2.0 / (hz * hz))
        ub_v = ca.fmax(_dm(c_hi) - t, -rec)
        lb_v = ca.fmin(_dm(c_lo) - t, rec)
        place = np.zeros((n, vi.size))
        place[vi, np.arange(vi.size)] = 1.0
        lb0, ub0 = P.lb.copy(), P.ub.copy()
        lb0[L.sl_vdot], ub0[L.sl_vdot] = -np.inf, np.inf
        lb0[vi], ub0[vi] = 0.0, 0.0
        lb0[L.sl_f_sw], ub0[L.sl_f_sw] = 0.0, 0.0
        unit_lb, unit_ub = np.zeros(n), np.zeros(n)
        unit_lb[L.sl_f_sw], unit_ub[L.sl_f_sw] = B._sw_lb_unit, B._sw_ub_unit
        lb = _dm(lb0) + ca.mtimes(ca.DM(ca.sparsify(_dm(place))), lb_v) + w * ca.sparsify(_dm(unit_lb))
        ub = _dm(ub0) + ca.mtimes(ca.DM(ca.sparsify(_dm(place))), ub_v) + w * ca.sparsify(_dm(unit_ub))

        # Cost: H0 + E^T E, g = Kq q + Kv v + k0 + E^T e.
        sw = B._sqrt_w[0]
        E_rows = [ca.horzcat(ca.mtimes(ca.diag(_dm(sw)), JoT.T), ca.MX(n_out, n - nv))]
        e_rows = [_dm(sw) * r]
        if B._reg_tau_rows:
            E_rows.append(B._sqrt_reg_torque * T)
            e_rows.append(B._sqrt_reg_torque * tau0)
        if B._reg_lam_rows:
            E_rows.append(B._sqrt_reg_coupling * Lam)
            e_rows.append(B._sqrt_reg_coupling * lam0)
        wy = cfg.stance_yaw_moment_weight
        if wy > 0 and B._yaw_idx is not None:
            # w M_z^2 with M_z = a . f[yaw_idx], a = (-dy, dx, dy, -dx), (dx, dy) = (p_toe - p_heel) / 2.
            dxy = 0.5 * (con[0:2] - con[3:5])
            a = ca.vertcat(-dxy[1], dxy[0], dxy[1], -dxy[0])
            place_yaw = np.zeros((n, 4))
            place_yaw[B._yaw_idx, np.arange(4)] = 1.0
            E_rows.append(math.sqrt(wy) * ca.mtimes(ca.DM(ca.sparsify(_dm(place_yaw))), a).T)
            e_rows.append(ca.MX(1, 1))
        E, e = ca.vertcat(*E_rows), ca.vertcat(*e_rows)
        g_tasks = ca.mtimes(_dm(B._Kq), q) + ca.mtimes(_dm(B._Kv), v) + _dm(B._k0)
        g = ca.vertcat(g_tasks, ca.MX(n - nv, 1)) + ca.mtimes(E.T, e)
        self.n_cost_rows = E.shape[0]

        outputs = {
            "ET": E.T, "g": g, "AT": A.T, "b": b, "TT": T.T, "l_tau": l_tau, "u_in": u_all,
            "lb": lb, "ub": ub, "RDT": RD.T, "Rhp": Rhp,
        }  # fmt: skip
        self.output_names = tuple(outputs)
        self.function = ca.Function(
            f"{FUNCTION_STEM}_{stance}",
            [Mu, hp, JfT, JoT, u],
            [ca.densify(x) for x in outputs.values()],
            ["M_upper", "hp", "JfT", "JoT", "packed"],
            list(outputs),
        )


def generate_source(builder) -> tuple[bytes, dict[str, ca.Function]]:
    """The C source of both stances' assembly functions for ``builder``, and the functions."""
    # Expanded to scalar (SX) code: sparsity and constants folded, ~5000
    # operations per stance. The Hessian product E^T E stays with numpy
    # (one BLAS call): unrolled, it was 41000 operations and 7 s of gcc.
    functions = {side: _Symbolic(builder, side).function.expand() for side in builder.robot.foot_sides}
    options = dict(generate.CODEGEN_OPTIONS, with_header=False)
    cg = ca.CodeGenerator(SOURCE_FILE, options)
    for fn in functions.values():
        cg.add(fn)
    with tempfile.TemporaryDirectory(prefix="amlip_qp_wbqp_") as tmp:
        cg.generate(tmp + os.sep)
        source = (Path(tmp) / SOURCE_FILE).read_bytes()
    return generate.banner().encode("ascii") + source, functions


class CompiledBuild:
    """The compiled assembly of one :class:`WholeBodyQP` (see the module doc).

    Args:
        builder: The :class:`~amlip_qp.control.qp_formulation.WholeBodyQP`
            whose problem arrays it fills.
        cache_dir: Overrides the codegen cache folder.

    Raises:
        CompilerUnavailableError: No C compiler.
        CodegenError: The compiler rejected the source or the library does not load.
        InputError: A builder this assembly does not cover (other varying tasks).
    """

    def __init__(self, builder, cache_dir: str | os.PathLike | None = None):
        if list(builder._varying_tasks) != [builder.output_task]:
            raise InputError("the compiled QP assembly covers one varying task, the output task")
        self.builder = builder
        source, _ = generate_source(builder)
        names = [f"{FUNCTION_STEM}_{side}" for side in builder.robot.foot_sides]
        self.library_path, functions = runtime.compile_and_load(source, names, SOURCE_FILE, LIBRARY_FILE, cache_dir)
        B, L = builder, builder._layout
        robot = B.robot
        nv = L.nv
        nf = len(B._axes) * L.n_points
        small = small_layout(builder)
        self._small_sl = small
        # Inputs, bound once (column-major views: a C-order (a, b) array is the (b, a) matrix).
        self._Mu = np.zeros((nv, nv), order="F")
        self._hp = np.zeros(nv)
        self._JoT = np.zeros((B.output_task.size, nv))
        self._u = np.zeros(small["size"])
        n_cost_rows = sum(t.size for t in B._varying_tasks) + B._reg_tau_rows + B._reg_lam_rows
        if B.config.stance_yaw_moment_weight > 0 and B._yaw_idx is not None:
            n_cost_rows += 1
        self._E = np.zeros((n_cost_rows, L.n))
        P = B.problem
        outputs = {
            "ET": self._E, "g": P.g, "AT": P.A, "b": P.b, "TT": P.C[: B._sl_tau.stop], "l_tau": P.l[: B._sl_tau.stop],
            "u_in": P.u, "lb": P.lb, "ub": P.ub, "RDT": B._RD, "Rhp": B._Rhp,
        }  # fmt: skip
        for name, arr in outputs.items():
            if not (arr.flags.c_contiguous or arr.flags.f_contiguous):
                raise InputError(f"compiled QP assembly: output {name} is not contiguous")
        self._outputs = outputs  # keeps the bound arrays alive
        self._eval = {}
        self._buffers = {}
        for side in robot.foot_sides:
            name = f"{FUNCTION_STEM}_{side}"
            fn = functions[name]
            buf, ev = fn.buffer()
            for i, arr in enumerate((self._Mu, self._hp, B._Jf, self._JoT, self._u)):
                if fn.nnz_in(i) != arr.size:
                    raise CodegenError(f"{self.library_path}: {name} input {i} has the wrong size")
                buf.set_arg(i, memoryview(arr.reshape(-1, order="A")))
            for i, arr in enumerate(outputs.values()):
                if fn.nnz_out(i) != arr.size:
                    raise CodegenError(f"{self.library_path}: {name} output {i} has the wrong size")
                buf.set_res(i, memoryview(arr.reshape(-1, order="A")))
            self._buffers[side], self._eval[side] = buf, ev
        self._nf = nf
        self._k = L.n_points

    def build(self, kin, target):
        """Fill the builder's problem for ``kin`` and ``target`` (the
        stance-foot torque bound and the stance yaw-moment cost included);
        return it. Same contract as :meth:`WholeBodyQP.build`."""
        B = self.builder
        stance = target.stance
        swing = "right" if stance == "left" else "left"
        ev = self._eval[stance]
        nf = self._nf
        kin.require_dynamics()
        np.subtract(kin.nonlinear_effects(), kin.passive_forces(), out=self._hp)
        B._force_jacobians(kin, stance, slice(0, nf))
        B._force_jacobians(kin, swing, slice(nf, 2 * nf))
        np.copyto(self._Mu, kin.data.M)
        u, sl = self._u, self._small_sl
        u[sl["q"]] = kin.q
        u[sl["v"]] = kin.v
        fids = B.robot.force_frame_ids[stance]
        c = sl["contact"].start
        if self._k == 2:
            u[c : c + 3] = kin.frame_translation_view(fids[0])
            u[c + 3 : c + 6] = kin.frame_translation_view(fids[1])
            u[c + 6 : c + 9] = kin.frame_jdot_v(fids[0])
            u[c + 9 : c + 12] = kin.frame_jdot_v(fids[1])
        else:
            u[sl["contact"]] = kin.frame_jdot_v(fids[0])[B._axes_index]
        task = B.output_task
        J, r = task.least_squares(kin, target)
        np.copyto(self._JoT, J)
        rr = u[sl["r"]]
        rr[:] = r
        if B._hip_yaw is not None:
            dh, ddh = B._hip_yaw_correction(kin, target)
            i = B._hip_yaw[1]
            rr[i] -= task.gains.kd[i] * ddh + task.gains.kp[i] * dh
        w = B.swing_force_weight(target)
        u[sl["w"]] = w
        ev()
        E = self._E
        np.add(B._H0, np.matmul(E.T, E, out=B._EtE), out=B.problem.H)
        B._last_force_weight = w
        B._G = B._stance_rows(stance).G
        return B.problem
