"""The paper's baseline tracker: iterative IK + a passivity-based controller (PBC).

Model (paper section "Passivity-based Controller", after Sadeghian et al. 2017,
moved to the floating base; Coriolis terms kept since Pinocchio gives them for
free in ``h``):

    M(q) vdot + h(q, v) - tau_pas(q, v) = B tau + J_c(q)^T lambda      (1)
    J_c(q) vdot + Jdot_c v = 0                                            (2)

- ``M`` the joint-space inertia (armature included), ``h = C v + g``,
  ``tau_pas`` the joint/tendon springs and dampers (MuJoCo's ``qfrc_passive``);
- ``B`` selects the actuated coordinates (joint-side torques ``tau``, N m);
- the constraints ``J_c`` are the stance contact -- Cassie's blade foot: the
  foot frame's translation (3 rows) and its rotation about the two axes
  normal to the blade (2 rows; the roll about the blade is free; a four-point
  sole is held by the same rows on its sole line, toe-pair midpoint to
  heel-pair midpoint, ``Robot.sole_line_frame_ids``); Rabbit's
  point foot: its in-plane translation (2 rows) -- and the springs treated as
  rigid, as the paper does: each coupling (Cassie's ``q_knee + q_tarsus``) and
  each passive joint outside a coupling (Cassie's shin). The spring forces lie
  in the span of these rows' ``J_c^T`` and are absorbed by their ``lambda``.
  The swing leg is in the same single-support model (it has no contact).

Control: the actuated coordinates other than the stance ankle (Cassie's stance
toe is passive, zero torque, as in the paper) follow

    vdot_a = qdd_r + K_d (qd_r - qd) + K_p (q_r - q)                      (3)

with ``(q_r, qd_r, qdd_r)`` from :class:`~amlip_qp.control.pbc.ik.IterativeIK`.
(1)-(3) are linear in ``x = (vdot, tau_ctrl, lambda)``; with ``n_c``
constraint rows and ``n_a`` controlled joints this is a square system of
``nv + n_c + n_a`` equations, solved each tick (assembled by generated C reading
Pinocchio's arrays in place, :mod:`~amlip_qp.control.pbc.dynamics_compiled`, or by
:meth:`PBCTracker.assemble_dynamics` without a compiler; the same system to rounding). Written as torques, (3) gives
``tau = Bbar^-1 (Mbar qdd_r + Cbar + Gbar) + Mbar-weighted PD``: the
feed-forward from the references plus PD on the errors of the paper's PBC.

Springs: by default the IK holds the springs at their estimates (encoders),
so the references already account for the deflection. With
:attr:`PBCGains.spring_model_offset` (the paper's "Springs") the IK holds them
at the simplified model's deflections instead (stance leg under the commanded
contact force, swing leg rigid), which offsets the stance knee reference.

Swing torso compensation (:attr:`PBCGains.swing_torso_compensation`, on for
Cassie): the swing joints' references are moved to the IK solution for the
measured torso orientation, so a torso error (a push) does not carry the swing
foot off its CoM-relative reference.

Fallback: a failed or non-finite solve gives ``TrackerResult(ok=False,
fallback=reason)`` with a joint PD towards the IK reference (or pure damping
if the IK failed too); never NaN.
"""

from __future__ import annotations

import math
import time
import warnings
from typing import TYPE_CHECKING

import numpy as np
from scipy.linalg.lapack import dgesv as _dgesv

from amlip_qp.alip import other_side
from amlip_qp.codegen.runtime import CodegenFallbackWarning
from amlip_qp.control.pbc.contact_release import solve_released
from amlip_qp.control.pbc.contact_rows import contact_rows
from amlip_qp.control.pbc.dynamics_compiled import CompiledDynamics
from amlip_qp.control.pbc.gains import PBCGains, default_gains
from amlip_qp.control.pbc.ik import IterativeIK
from amlip_qp.control.pbc.ik_newton import all_finite
from amlip_qp.control.pbc.ik_settings import IKSettings
from amlip_qp.control.pbc.springs import spring_deflections_rad
from amlip_qp.control.pbc.stance_layout import StanceLayout
from amlip_qp.control.pelvis_yaw import PelvisYawFeedback
from amlip_qp.control.tracker import Tracker, TrackingTarget
from amlip_qp.exceptions import CompilerUnavailableError, InputError
from amlip_qp.messages import TrackerResult
from amlip_qp.robots.outputs import OutputMap
from amlip_qp.robots.passive import contiguous_index

if TYPE_CHECKING:  # pragma: no cover - typing only
    from amlip_qp.robots.kinematics import RobotKinematics
    from amlip_qp.robots.robot import Robot


class PBCTracker(Tracker):
    """Iterative IK + passivity-based controller on the constrained floating-base model.

    Args:
        robot: The :class:`~amlip_qp.robots.robot.Robot`.
        gains: Controller gains (default: :func:`default_gains`).
        ik_settings: IK iteration settings.
        compiled_dynamics: Assemble the system (1)-(3) with the generated C of
            :mod:`~amlip_qp.control.pbc.dynamics_compiled` (the same system to rounding, read
            in place from Pinocchio's arrays): ``None`` (default) when a C compiler is found,
            else the Python assembly with a
            :class:`~amlip_qp.codegen.runtime.CodegenFallbackWarning`; ``True`` requires it
            (:class:`~amlip_qp.exceptions.CompilerUnavailableError` without a compiler);
            ``False``: the Python assembly (:meth:`assemble_dynamics`).
        compiled_ik: The IK's evaluation in generated C, the same choice
            (:class:`~amlip_qp.control.pbc.ik.IterativeIK`'s ``compiled``).
    """

    name = "pbc"

    def __init__(
        self,
        robot: Robot,
        gains: PBCGains | None = None,
        ik_settings: IKSettings | None = None,
        compiled_dynamics: bool | None = None,
        compiled_ik: bool | None = None,
    ):
        for name, value in (("compiled_dynamics", compiled_dynamics), ("compiled_ik", compiled_ik)):
            if not any(value is allowed for allowed in (None, True, False)):  # not 0, 1 or 'yes'
                raise InputError(f"{name} must be None, True or False, got {value!r}")
        self.robot = robot
        if robot.profile is not None:
            robot.profile.check_supported("pbc")  # the profile's reason, before the IK's own check
        self.gains = gains or default_gains(robot)
        self.shortest_step_s = self.gains.shortest_step_s
        self.ik = IterativeIK(robot, ik_settings, compiled_ik)
        nv = robot.nv
        act = robot.actuated
        self._nu = len(act)
        # Rigid springs (couplings, then the passive joints outside them).
        rows = [spring.row_v(nv) for spring in robot.springs]
        self._J_springs = np.array(rows).reshape(len(rows), nv)
        self._layout: dict[str, StanceLayout] = {}
        g = self.gains
        for side in robot.foot_sides:
            ctrl = self.ik.equations.controlled_actuated(side)
            swing_side = other_side(side)
            swing_leg = set(robot.leg_joint_names[swing_side])
            swing_mask = np.array([act.joint_names[k] in swing_leg for k in ctrl], dtype=bool)
            kp = np.where(swing_mask, g.kp_swing_ps2, g.kp_stance_ps2)
            kd = np.where(swing_mask, g.kd_swing_ps, g.kd_stance_ps)
            if g.swing_ankle_gain_scale != 1.0:
                ankle = np.isin(act.pin_v_idx[ctrl], self.ik.equations.held_v[swing_side])
                kp[ankle] *= g.swing_ankle_gain_scale
                kd[ankle] *= math.sqrt(g.swing_ankle_gain_scale)
            self._layout[side] = StanceLayout(
                ctrl=ctrl,
                ctrl_v=act.pin_v_idx[ctrl],
                ctrl_q=act.pin_q_idx[ctrl],
                kp=kp,
                kd=kd,
                swing_mask=swing_mask,
                swing_pos=np.flatnonzero(swing_mask),
                swing_v=act.pin_v_idx[ctrl][swing_mask],
            )
        # A two- or four-point foot: the rows of its sole line (a four-point sole is held as its line).
        self._blade = {s: len(robot.sole_line_frame_ids.get(s, ())) == 2 for s in robot.foot_sides}
        self._planar = robot.is_planar
        # preallocated KKT system per stance (unknowns: vdot, tau_ctrl, lambda)
        ns = len(self._J_springs)
        for side, lay in self._layout.items():
            ncf = 2 if self._planar else (5 if self._blade[side] else 3)
            na = len(lay.ctrl_v)
            nc = ncf + ns
            K = np.zeros((nv + nc + na, nv + na + nc))
            K[lay.ctrl_v, nv + np.arange(na)] = -1.0
            K[nv + nc + np.arange(na), lay.ctrl_v] = 1.0
            if ns:
                K[nv + ncf : nv + nc, :nv] = self._J_springs
                K[:nv, nv + na + ncf :] = -self._J_springs.T
            lay.K, lay.rhs, lay.n_contact = K, np.zeros(nv + nc + na), ncf
        #: Who assembles the system: ``"c-in-place"`` (:mod:`~amlip_qp.control.pbc.dynamics_compiled`)
        #: or ``"python"`` (:meth:`assemble_dynamics`).
        self.dynamics_backend = "python"
        self._compiled: CompiledDynamics | None = None
        if compiled_dynamics is None or compiled_dynamics:
            try:
                self._compiled = CompiledDynamics(robot, self._layout, self._blade, self._J_springs)
                self.dynamics_backend = "c-in-place"
            except CompilerUnavailableError as exc:
                if compiled_dynamics:
                    raise
                warnings.warn(
                    f"PBCTracker: no compiled dynamics ({exc}); using the Python assembly (same system, slower)",
                    CodegenFallbackWarning,
                    stacklevel=2,
                )
        self._nv = nv
        names = OutputMap(robot).names
        self._yaw_feedback = PelvisYawFeedback.for_outputs(names, self.gains.hip_yaw_feedback)
        torso = np.array([i for i, nm in enumerate(names) if nm in ("torso_pitch", "torso_roll")], dtype=int)
        self._has_torso_rows = len(torso) > 0
        self._torso_rows = contiguous_index(torso)  # a slice when they are adjacent (views, not copies)
        self._rhs_comp = np.zeros(nv)
        # spring model (see PBCGains.spring_model_offset): rest values and the stance leg's entries
        self._spring_rest = self.ik.equations.spring_rest_values()
        # Per stance: the held springs whose deflection the model gives, in the order of
        # spring_deflections_rad (that leg's joints, then its couplings with a spring).
        self._spring_idx = {
            side: np.array(
                [
                    k
                    for k, s in enumerate(self.ik.equations.held_springs)
                    if s.side == side and (s.kind == "joint" or s.stiffness > 0)
                ],
                dtype=int,
            )  # fmt: skip
            for side in robot.foot_sides
        }
        self._last_force: dict[str, np.ndarray | None] = dict.fromkeys(robot.foot_sides)
        self._fz_row = 1 if self._planar else 2  # the contact force's normal component in lambda
        #: Ticks solved without the stance contact (``PBCGains.release_pulling_contact``).
        self.contact_releases = 0

    def layout(self, stance: str) -> StanceLayout:
        """The controlled joints, gains and KKT buffers for ``stance`` (read-only)."""
        return self._layout[stance]

    def last_contact_force_N(self, side: str) -> np.ndarray | None:
        """The last commanded stance contact force of ``side`` (world, N; zero when it
        pulled; ``None`` before any or on Rabbit): copy. The spring model
        (``PBCGains.spring_model_offset``) deflects the springs by it."""
        f = self._last_force[side]
        return None if f is None else f.copy()

    def reset(self) -> None:
        """Forget the IK warm start, the last contact forces and the released contacts' count."""
        self.ik.reset()
        self._last_force = dict.fromkeys(self.robot.foot_sides)
        self.contact_releases = 0

    # ---------------------------------------------------------------- model
    def contact_constraints(self, kin: RobotKinematics, stance: str) -> tuple[np.ndarray, np.ndarray]:
        """Stance contact rows ``(J, Jdot_v)`` (see the module docstring)."""
        ncf = self._layout[stance].n_contact
        J, a = np.empty((ncf, self._nv)), np.empty(ncf)
        contact_rows(self.robot, kin, stance, self._blade[stance], J, a)
        return J, a

    def constraints(self, kin: RobotKinematics, stance: str) -> tuple[np.ndarray, np.ndarray]:
        """All constraint rows ``(J_c, Jdot_c v)``: stance contact, then the rigid springs."""
        Jf, af = self.contact_constraints(kin, stance)
        return np.vstack([Jf, self._J_springs]), np.concatenate([af, np.zeros(len(self._J_springs))])

    def assemble_dynamics(self, kin: RobotKinematics, stance: str, vdot_ctrl) -> None:
        """Write the system (1)-(3) for the controlled joints' accelerations ``vdot_ctrl`` into
        ``stance``'s layout (``K``, ``rhs``): the Python reference of the compiled assembly
        (:mod:`~amlip_qp.control.pbc.dynamics_compiled`)."""
        lay = self._layout[stance]
        nv, ncf = self._nv, lay.n_contact
        na = len(lay.ctrl_v)
        K, rhs = lay.K, lay.rhs
        K[:nv, :nv] = kin.mass_matrix()
        Jf = K[nv : nv + ncf, :nv]
        contact_rows(self.robot, kin, stance, self._blade[stance], Jf, rhs[nv : nv + ncf])
        np.negative(rhs[nv : nv + ncf], out=rhs[nv : nv + ncf])
        np.negative(Jf.T, out=K[:nv, nv + na : nv + na + ncf])
        np.subtract(kin.passive_forces(), kin.data.nle, out=rhs[:nv])
        rhs[len(rhs) - na :] = vdot_ctrl

    def solve_dynamics(self, kin: RobotKinematics, stance: str, vdot_ctrl) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Solve (1)-(3) for ``(vdot, tau_ctrl, lambda)`` given the controlled joints' accelerations
        (assembled by :attr:`dynamics_backend`'s code).

        Raises:
            numpy.linalg.LinAlgError: Singular system.
        """
        lay = self._layout[stance]
        if self._compiled is not None:
            self._compiled.assemble(kin, stance, vdot_ctrl)
        else:
            self.assemble_dynamics(kin, stance, vdot_ctrl)
        nv, na = self._nv, len(lay.ctrl_v)
        _, _, x, info = _dgesv(lay.K, lay.rhs, overwrite_a=0, overwrite_b=0)
        if info != 0:
            raise np.linalg.LinAlgError(f"singular PBC system (dgesv info {info})")
        return x[:nv], x[nv : nv + na], x[nv + na :]

    # ---------------------------------------------------------------- track
    def compute(self, kin: RobotKinematics, target: TrackingTarget) -> TrackerResult:
        """Torques (actuator order, joint side, N m) tracking ``target`` (see the module docstring)."""
        t0 = time.perf_counter()
        stance = target.stance
        lay = self._layout[stance]
        q, v = kin.state()
        held = None
        if self.gains.spring_model_offset and len(self._spring_rest):
            held = self._spring_rest.copy()
            g = self.gains
            load = self._last_force[stance] if g.spring_model_load == "commanded" else None
            defl = spring_deflections_rad(kin, stance, load, g.spring_model_linkage)
            if len(defl) == len(self._spring_idx[stance]):
                held[self._spring_idx[stance]] += defl
        h_d, dh_d = target.h_d, target.dh_d
        if self._yaw_feedback is not None:
            h_d, dh_d = self._yaw_feedback.references(kin, target)
        t_ik = time.perf_counter()  # the parts of compute, µs in info: the IK, the compensation, the dynamics
        ik = self.ik.solve(kin, stance, target.heading_rad, h_d, dh_d, target.ddh_d, held_springs=held)
        t_part = time.perf_counter()
        info = {"ik_iterations": float(ik.iterations), "ik_residual": float(ik.residual)}
        info["ik_us"] = (t_part - t_ik) * 1e6
        q_r = ik.q_r[lay.ctrl_q]  # index arrays: new arrays
        v_r = ik.v_r[lay.ctrl_v]
        a_r = ik.a_r[lay.ctrl_v]
        if not ik.ok:
            return self._fallback(kin, lay, q_r, "ik_failed", info, t0, use_ref=False)
        c = self.gains.swing_torso_compensation
        if c > 0.0 and self._has_torso_rows:
            self.compensate_swing(kin, target, lay, c, q_r, v_r)
            info["compensation_us"] = (time.perf_counter() - t_part) * 1e6
        e = q_r - q[lay.ctrl_q]
        ed = v_r - v[lay.ctrl_v]
        sw = self.gains.swing_scale(target.phase, target.swing_contact_weight)
        vdot_ctrl = lay.kd * ed
        vdot_ctrl += lay.kp * e
        if sw != 1.0:
            vdot_ctrl[lay.swing_mask] *= sw
        vdot_ctrl += a_r
        info["tracking_error_rad"] = float(abs(e).max())
        try:
            t_part = time.perf_counter()
            vdot, tau_c, lam = self.solve_dynamics(kin, stance, vdot_ctrl)
            if self.gains.release_pulling_contact and lam[self._fz_row] < 0.0:  # the ground would pull
                vdot, tau_c, lam = solve_released(lay.K, lay.rhs, self._nv, len(lay.ctrl_v), lay.n_contact)
                self.contact_releases += 1
                info["contact_released"] = 1.0
            info["dynamics_us"] = (time.perf_counter() - t_part) * 1e6
        except np.linalg.LinAlgError:
            return self._fallback(kin, lay, q_r, "singular_dynamics", info, t0)
        if not all_finite(tau_c, lam):
            return self._fallback(kin, lay, q_r, "non_finite_torque", info, t0)
        tau = np.zeros(self._nu)
        tau[lay.ctrl] = tau_c
        info["contact_force_z_N"] = float(lam[2] if not self._planar else lam[1])
        if not self._planar:
            f = lam[:3]
            self._last_force[stance] = f.copy() if f[2] > 0.0 else np.zeros(3)
        info["solve_time_us"] = (time.perf_counter() - t0) * 1e6
        return TrackerResult(tau_Nm=tau, ok=True, fallback=None, info=info)

    def compensate_swing(
        self, kin: RobotKinematics, target: TrackingTarget, lay: StanceLayout, c: float, q_r, v_r
    ) -> None:
        """Move the swing joints' references to the IK solution at the measured torso orientation.

        ``dq = A^-1 [dh; 0]`` with ``dh`` the torso rows' error (measured minus
        reference, and the same for the rates) and zero elsewhere: the IK
        solution whose torso is where the robot's is, with the same CoM-relative
        swing foot, held stance foot and springs. Only its swing-leg part is
        used (the stance leg keeps steering the torso to its reference).
        :meth:`compute` applies it when ``gains.swing_torso_compensation > 0``.

        Args:
            kin: The kinematics, updated this tick.
            target: The tick's references (stance, heading, ``h_d``, ``dh_d``).
            lay: :meth:`layout` of the stance side.
            c: The compensation fraction (``gains.swing_torso_compensation``).
            q_r, v_r: The controlled joints' position (rad) and velocity (rad/s)
                references, in ``lay``'s order; the swing entries are moved in place.

        Raises:
            InputError: The IK has no successful solve yet (:meth:`IterativeIK.solve_linear
                <amlip_qp.control.pbc.ik.IterativeIK.solve_linear>`).
        """
        y, J, _ = kin.outputs(target.stance, target.heading_rad)  # cached; the controller reuses it
        rows = self._torso_rows
        rhs = self._rhs_comp
        rhs[rows] = c * (y[rows] - target.h_d[rows])
        dq = self.ik.solve_linear(rhs)
        rhs[rows] = c * (np.dot(J[rows], kin.state()[1]) - target.dh_d[rows])
        dv = self.ik.solve_linear(rhs)
        rhs[rows] = 0.0
        sw, sw_v = lay.swing_pos, lay.swing_v
        q_r[sw] += dq[sw_v]
        v_r[sw] += dv[sw_v]

    def _fallback(
        self, kin: RobotKinematics, lay: StanceLayout, q_r, reason: str, info: dict, t0: float, use_ref: bool = True
    ) -> TrackerResult:
        """Damped joint PD towards the reference (or damping only), never NaN."""
        g = self.gains
        q_est, v_est = kin.state()
        q = q_est[lay.ctrl_q]
        qd = v_est[lay.ctrl_v]
        err = (q_r - q) if use_ref else np.zeros_like(q)
        err = np.where(np.isfinite(err), err, 0.0)
        tau = np.zeros(self._nu)
        tau[lay.ctrl] = g.fallback_kp_Nmprad * err - g.fallback_kd_Nmsprad * qd
        info["solve_time_us"] = (time.perf_counter() - t0) * 1e6
        return TrackerResult(tau_Nm=tau, ok=False, fallback=reason, info=info)
