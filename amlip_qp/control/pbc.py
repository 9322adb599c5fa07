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
  normal to the blade (2 rows; the roll about the blade is free); Rabbit's
  point foot: its in-plane translation (2 rows) -- and the springs treated as
  rigid, as the paper does: each coupling (Cassie's ``q_knee + q_tarsus``) and
  each passive joint outside a coupling (Cassie's shin). The spring forces lie
  in the span of these rows' ``J_c^T`` and are absorbed by their ``lambda``.
  The swing leg is in the same single-support model (it has no contact).

Control: the actuated coordinates other than the stance ankle (Cassie's stance
toe is passive, zero torque, as in the paper) follow

    vdot_a = qdd_r + K_d (qd_r - qd) + K_p (q_r - q)                      (3)

with ``(q_r, qd_r, qdd_r)`` from :class:`~amlip_qp.control.ik.IterativeIK`.
(1)-(3) are linear in ``x = (vdot, tau_ctrl, lambda)``; with ``n_c``
constraint rows and ``n_a`` controlled joints this is a square system of
``nv + n_c + n_a`` equations, solved each tick. Written as torques, (3) gives
``tau = Bbar^-1 (Mbar qdd_r + Cbar + Gbar) + Mbar-weighted PD``: the
feed-forward from the references plus PD on the errors of the paper's PBC.

Spring compensation: ``target.stance_knee_offset_rad`` (and, optionally,
:func:`amlip_qp.control.springs.stance_knee_offset_rad`) is added to the
stance knee reference.

Fallback: a failed or non-finite solve gives ``TrackerResult(ok=False,
fallback=reason)`` with a joint PD towards the IK reference (or pure damping
if the IK failed too); never NaN.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from amlip_qp.control.ik import IKSettings, IterativeIK
from amlip_qp.control.springs import stance_knee_offset_rad
from amlip_qp.control.tracker import Tracker, TrackerResult, TrackingTarget
from amlip_qp.exceptions import InputError


@dataclass(frozen=True)
class PBCGains:
    """Gains of the PBC (acceleration level) and of its fallback (torque level).

    Attributes:
        kp_stance_ps2: ``K_p`` on the stance leg's joints, 1/s^2.
        kd_stance_ps: ``K_d`` on the stance leg's joints, 1/s.
        kp_swing_ps2: ``K_p`` on the swing leg's joints, 1/s^2.
        kd_swing_ps: ``K_d`` on the swing leg's joints, 1/s.
        swing_start_fraction: Swing gains at the start of a step, as a fraction
            of the full gains (phase schedule: the swing leg leaves the ground
            with the old stance leg's velocity, far from the reference's).
        swing_ramp_phase: Phase over which the swing gains ramp linearly to full.
        touchdown_gain_drop: Fraction by which the swing gains drop as
            ``target.swing_contact_weight`` goes from 0 to 1 (softer landing).
        fallback_kp_Nmprad: Fallback joint stiffness, N m/rad.
        fallback_kd_Nmsprad: Fallback joint damping, N m s/rad.
        spring_model_offset: Add :func:`~amlip_qp.control.springs.stance_knee_offset_rad`
            to the stance knee reference (use with IK that holds the springs at rest).
    """

    kp_stance_ps2: float = 400.0
    kd_stance_ps: float = 40.0
    kp_swing_ps2: float = 400.0
    kd_swing_ps: float = 40.0
    swing_start_fraction: float = 1.0
    swing_ramp_phase: float = 0.2
    touchdown_gain_drop: float = 0.0
    fallback_kp_Nmprad: float = 100.0
    fallback_kd_Nmsprad: float = 5.0
    spring_model_offset: bool = False

    def __post_init__(self):
        vals = [getattr(self, f) for f in self.__dataclass_fields__ if f != "spring_model_offset"]
        if (
            not all(np.isfinite(v) and v >= 0 for v in vals)
            or self.touchdown_gain_drop > 1
            or self.swing_start_fraction > 1
            or self.swing_ramp_phase <= 0
        ):
            raise InputError(
                "PBC gains must be finite and >= 0 (touchdown_gain_drop, swing_start_fraction <= 1, "
                f"swing_ramp_phase > 0), got {self!r}"
            )

    def swing_scale(self, phase: float, contact_weight: float) -> float:
        """Factor (dimensionless) on the swing leg's gains at this phase and touchdown weight."""
        s = float(phase) if np.isfinite(phase) else 1.0
        w = float(np.clip(contact_weight, 0.0, 1.0)) if np.isfinite(contact_weight) else 0.0
        ramp = min(1.0, max(0.0, s) / self.swing_ramp_phase)
        start = self.swing_start_fraction + (1.0 - self.swing_start_fraction) * ramp
        return start * (1.0 - self.touchdown_gain_drop * w)


def default_gains(robot) -> PBCGains:
    """Tuned gains per robot (closed-loop MuJoCo runs, tests/test_walk_pbc.py).

    Cassie's stance leg gets softer gains (``K_p`` 200 1/s^2, ``K_d`` 28 1/s):
    with stiffer stance gains (900 1/s^2) the joint PD in series with the leg
    springs made the robot fall within 0.5 s. Rabbit (rigid) uses 400 / 40 on
    both legs.
    """
    if robot.couplings or len(robot.passive_v_idx):
        return PBCGains(kp_stance_ps2=200.0, kd_stance_ps=28.0, kp_swing_ps2=400.0, kd_swing_ps=40.0)
    return PBCGains()


@dataclass
class _Layout:
    """Index bookkeeping for one stance side."""

    ctrl: np.ndarray  # indices into the actuator list of the controlled joints
    ctrl_v: np.ndarray  # their Pinocchio v indices
    ctrl_q: np.ndarray  # their Pinocchio q indices
    kp: np.ndarray = field(default_factory=lambda: np.zeros(0))
    kd: np.ndarray = field(default_factory=lambda: np.zeros(0))
    swing_mask: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=bool))
    knee_k: int | None = None  # position of the stance knee in ctrl


class PBCTracker(Tracker):
    """Iterative IK + passivity-based controller on the constrained floating-base model.

    Args:
        robot: The :class:`~amlip_qp.robots.robot.Robot`.
        gains: Controller gains (default: :func:`default_gains`).
        ik_settings: IK iteration settings.
    """

    name = "pbc"

    def __init__(self, robot, gains: PBCGains | None = None, ik_settings: IKSettings | None = None):
        self.robot = robot
        self.gains = gains or default_gains(robot)
        self.ik = IterativeIK(robot, ik_settings)
        nv = robot.nv
        act = robot.actuated
        self._nu = len(act)
        coupled = {int(i) for c in robot.couplings for i in c.pin_v_idx}
        spring_v = [int(iv) for iv in robot.passive_v_idx if int(iv) not in coupled]
        rows = []
        for c in robot.couplings:
            g = np.zeros(nv)
            np.add.at(g, c.pin_v_idx, c.coefficients)
            rows.append(g)
        for iv in spring_v:
            e = np.zeros(nv)
            e[iv] = 1.0
            rows.append(e)
        self._J_springs = np.array(rows).reshape(len(rows), nv)
        self._layout: dict[str, _Layout] = {}
        smap = robot.state_map
        g = self.gains
        for side in robot.foot_sides:
            ctrl = self.ik.controlled_actuated(side)
            swing_side = robot.other_side(side)
            swing_mask = np.array([act.joint_names[k].startswith(swing_side) for k in ctrl], dtype=bool)
            kp = np.where(swing_mask, g.kp_swing_ps2, g.kp_stance_ps2)
            kd = np.where(swing_mask, g.kd_swing_ps, g.kd_stance_ps)
            knee_k = None
            knee = f"{side}-knee"
            if knee in smap.joint_pin_v:
                hits = [i for i, k in enumerate(ctrl) if act.pin_v_idx[k] == smap.joint_pin_v[knee]]
                knee_k = hits[0] if hits else None
            self._layout[side] = _Layout(
                ctrl=ctrl,
                ctrl_v=act.pin_v_idx[ctrl],
                ctrl_q=act.pin_q_idx[ctrl],
                kp=kp,
                kd=kd,
                swing_mask=swing_mask,
                knee_k=knee_k,
            )
        self._blade = {s: len(robot.force_frame_ids[s]) == 2 for s in robot.foot_sides}
        self._planar = robot.is_planar

    def reset(self) -> None:
        """Forget the IK warm start."""
        self.ik.reset()

    # ---------------------------------------------------------------- model
    def contact_constraints(self, kin, stance: str) -> tuple[np.ndarray, np.ndarray]:
        """Stance contact rows ``(J, Jdot_v)`` (see the module docstring)."""
        cid = self.robot.contact_frame_ids[stance]
        J6 = kin.frame_jacobian6(cid)
        a6 = kin.frame_jdot_v6(cid)
        if self._planar:
            return J6[[0, 2]], a6[[0, 2]]
        if self._blade[stance]:
            toe, heel = kin.force_point_positions(stance)
            u = (toe - heel) / np.linalg.norm(toe - heel)
            n1 = np.cross(u, [0.0, 0.0, 1.0])
            if np.linalg.norm(n1) < 1e-6:
                n1 = np.cross(u, [1.0, 0.0, 0.0])
            n1 /= np.linalg.norm(n1)
            n2 = np.cross(u, n1)
            N = np.vstack([n1, n2])
            return np.vstack([J6[:3], N @ J6[3:]]), np.concatenate([a6[:3], N @ a6[3:]])
        return J6[:3], a6[:3]

    def constraints(self, kin, stance: str) -> tuple[np.ndarray, np.ndarray]:
        """All constraint rows ``(J_c, Jdot_c v)``: stance contact, then the rigid springs."""
        Jf, af = self.contact_constraints(kin, stance)
        return np.vstack([Jf, self._J_springs]), np.concatenate([af, np.zeros(len(self._J_springs))])

    def solve_dynamics(self, kin, stance: str, vdot_ctrl) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Solve (1)-(3) for ``(vdot, tau_ctrl, lambda)`` given the controlled joints' accelerations.

        Raises:
            numpy.linalg.LinAlgError: Singular system.
        """
        lay = self._layout[stance]
        nv = kin.model.nv
        M = kin.mass_matrix()
        rhs_dyn = kin.passive_forces() - kin.nonlinear_effects()
        Jc, jdv = self.constraints(kin, stance)
        nc, na = Jc.shape[0], len(lay.ctrl_v)
        K = np.zeros((nv + nc + na, nv + na + nc))
        K[:nv, :nv] = M
        K[lay.ctrl_v, nv + np.arange(na)] = -1.0
        K[:nv, nv + na :] = -Jc.T
        K[nv : nv + nc, :nv] = Jc
        K[nv + nc + np.arange(na), lay.ctrl_v] = 1.0
        rhs = np.concatenate([rhs_dyn, -jdv, vdot_ctrl])
        x = np.linalg.solve(K, rhs)
        return x[:nv], x[nv : nv + na], x[nv + na :]

    # ---------------------------------------------------------------- track
    def compute(self, kin, target: TrackingTarget) -> TrackerResult:
        """Torques (actuator order, joint side, N m) tracking ``target`` (see the module docstring)."""
        t0 = time.perf_counter()
        stance = target.stance
        lay = self._layout[stance]
        q, v = kin.q, kin.v
        ik = self.ik.solve(kin, stance, target.heading_rad, target.h_d, target.dh_d, target.ddh_d)
        info = {"ik_iterations": float(ik.iterations), "ik_residual": float(ik.residual)}
        q_r = ik.q_r[lay.ctrl_q].copy()
        v_r = ik.v_r[lay.ctrl_v]
        a_r = ik.a_r[lay.ctrl_v]
        if lay.knee_k is not None:
            offset = float(target.stance_knee_offset_rad) if np.isfinite(target.stance_knee_offset_rad) else 0.0
            if self.gains.spring_model_offset:
                offset += stance_knee_offset_rad(kin, stance)
            q_r[lay.knee_k] += offset
            info["knee_offset_rad"] = offset
        if not ik.ok:
            return self._fallback(kin, lay, q_r, "ik_failed", info, t0, use_ref=False)
        e = q_r - q[lay.ctrl_q]
        ed = v_r - v[lay.ctrl_v]
        scale = np.where(lay.swing_mask, self.gains.swing_scale(target.phase, target.swing_contact_weight), 1.0)
        vdot_ctrl = a_r + scale * (lay.kd * ed + lay.kp * e)
        info["tracking_error_rad"] = float(np.max(np.abs(e)))
        try:
            vdot, tau_c, lam = self.solve_dynamics(kin, stance, vdot_ctrl)
        except np.linalg.LinAlgError:
            return self._fallback(kin, lay, q_r, "singular_dynamics", info, t0)
        if not (np.all(np.isfinite(tau_c)) and np.all(np.isfinite(lam))):
            return self._fallback(kin, lay, q_r, "non_finite_torque", info, t0)
        tau = np.zeros(self._nu)
        tau[lay.ctrl] = tau_c
        info["contact_force_z_N"] = float(lam[2] if not self._planar else lam[1])
        info["solve_time_us"] = (time.perf_counter() - t0) * 1e6
        return TrackerResult(tau_Nm=tau, ok=True, fallback=None, info=info)

    def _fallback(self, kin, lay: _Layout, q_r, reason: str, info: dict, t0: float, use_ref: bool = True) -> TrackerResult:
        """Damped joint PD towards the reference (or damping only), never NaN."""
        g = self.gains
        q = kin.q[lay.ctrl_q]
        qd = kin.v[lay.ctrl_v]
        err = (q_r - q) if use_ref else np.zeros_like(q)
        err = np.where(np.isfinite(err), err, 0.0)
        tau = np.zeros(self._nu)
        tau[lay.ctrl] = g.fallback_kp_Nmprad * err - g.fallback_kd_Nmsprad * qd
        info["solve_time_us"] = (time.perf_counter() - t0) * 1e6
        return TrackerResult(tau_Nm=tau, ok=False, fallback=reason, info=info)
