"""Iterative inverse kinematics: reference outputs ``h_d`` -> actuated-joint references.

The paper (section "Inverse Kinematics") converts the reference outputs
``h_d(s)`` into references for the actuated joints so that a joint-space
passivity-based controller can track them. This module does that conversion
by damped Newton iterations on the full Pinocchio configuration.

Formulation (square system, ``nv`` equations in the ``nv`` velocity coordinates)
------------------------------------------------------------------------------
Unknown: the full configuration ``q`` (base and all joints). Equations:

1. **Outputs**: ``h_0(q) = h_d`` (the ``n_h`` outputs of
   :mod:`amlip_qp.robots.outputs`; Cassie 9, Rabbit 4).
2. **Stance contact pose held at its estimate**: the pose of the stance
   ``{st}-contact`` frame equals the estimated one: position (m) and
   orientation (rad, world-axes rotation vector ``log3(R R_est^T)``). For a
   planar robot only its in-plane rows (x, z, pitch) exist. For Rabbit the
   contact frame rides on the shin, so this fixes the stance shin's absolute
   angle (the unactuated coordinate) at its estimate; for Cassie it fixes the
   foot on the ground, including its roll about the blade.
3. **Unactuated stance ankle held at its estimate**: if the stance contact
   frame's parent joint is actuated and the system would otherwise be
   under-determined (Cassie's stance toe, passive in the paper), its angle
   equals the estimate.
4. **Springs held at their estimates**: each passive joint that is not in a
   coupling (Cassie's shins) equals its estimate, and each coupling length
   (Cassie's ``q_knee + q_tarsus``) equals its estimated length, so the
   tarsus moves with the knee as through a rigid achilles rod.

Consequently the free coordinates are: the actuated joints other than the
stance ankle (Cassie: stance hip roll/yaw/pitch and knee, swing hip
roll/yaw/pitch, knee and toe: 9 = ``n_h``; Rabbit: both hips and knees, 4 =
``n_h``) -- the base pose and the tarsi are then dependent (the base follows
from the stance leg standing on the fixed foot; each tarsus from its knee).
Fixed (at the estimate): the stance contact pose, the stance ankle (Cassie),
the shins and the coupling lengths. Cassie: 9 + 6 + 1 + 2 + 2 = 20 = nv;
Rabbit: 4 + 3 = 7 = nv.

Velocity and acceleration references use the same matrix ``A(q_r)`` (the
stacked Jacobians of the equations above):

- ``A v_r = [dh_d; b_fix]``, with ``b_fix`` the estimated rates of the held
  contact pose and stance ankle (they are the robot's unactuated motion,
  e.g. Rabbit's stance shin rotating) and 0 for the spring rows (rigid springs).
- ``A a_r = [ddh_d; 0] - Adot v_r`` (drift by a finite difference of ``A``
  along ``v_r``); the unactuated accelerations are taken as 0.

Robustness: each Newton step is a damped least-squares step, its joint part
is limited to :attr:`IKSettings.max_step_rad`, the actuated joints are clamped
to their ranges; any non-finite result falls back to the previous reference.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from amlip_qp.exceptions import InputError, MJCFError


@dataclass(frozen=True)
class IKSettings:
    """Settings of :class:`IterativeIK`.

    Attributes:
        iterations: Newton iterations per call when warm-started.
        cold_iterations: Newton iterations when starting from the estimate
            (first call, after a stance switch or a failure).
        damping: Levenberg damping ``mu`` of ``(A^T A + mu I) dq = A^T r``
            (dimensionless; the rows are in m and rad).
        max_step_rad: Largest joint change per Newton step, rad (m for slide joints).
        fd_step_s: Time step of the finite difference for ``Adot v``, s.
    """

    iterations: int = 2
    cold_iterations: int = 8
    damping: float = 1e-10
    max_step_rad: float = 0.3
    fd_step_s: float = 1e-6

    def __post_init__(self):
        if self.iterations < 1 or self.cold_iterations < 1:
            raise InputError("IK iteration counts must be >= 1")
        if not (self.damping >= 0 and self.max_step_rad > 0 and self.fd_step_s > 0):
            raise InputError("IK damping must be >= 0, max_step_rad and fd_step_s > 0")


@dataclass
class IKResult:
    """References for all coordinates (Pinocchio convention) from one IK call.

    Attributes:
        q_r: Reference configuration, shape (nq,).
        v_r: Reference velocity, shape (nv,).
        a_r: Reference acceleration, shape (nv,).
        iterations: Newton iterations done.
        residual: Max-norm of the equation residual at ``q_r`` (m / rad).
        ok: False when the solve failed and the previous reference was kept.
    """

    q_r: np.ndarray
    v_r: np.ndarray
    a_r: np.ndarray
    iterations: int
    residual: float
    ok: bool = True


class _OutputEval:
    """``h_0(q)`` and its Jacobian on a private Pinocchio data (same definitions as
    :class:`amlip_qp.robots.outputs.OutputMap`, without the drift terms)."""

    def __init__(self, robot):
        import pinocchio as pin

        from amlip_qp.robots.outputs import OutputMap

        self._pin = pin
        self.robot = robot
        self.model = robot.pin_model
        self.data = self.model.createData()
        omap = OutputMap(robot)
        self.layout = omap.layout
        self.size = omap.size
        if self.layout == "cassie":
            smap = robot.state_map
            self._yaw_v = {s: smap.joint_pin_v[f"{s}-hip-yaw"] for s in robot.foot_sides}
            self._yaw_q = {s: smap.joint_pin_q[f"{s}-hip-yaw"] for s in robot.foot_sides}
        self._lwa = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED

    def compute(self, q) -> None:
        """Kinematic passes at ``q`` (positions, joint Jacobians, CoM and its Jacobian)."""
        pin, m, d = self._pin, self.model, self.data
        pin.computeJointJacobians(m, d, q)
        pin.updateFramePlacements(m, d)
        pin.jacobianCenterOfMass(m, d, q, False)

    def jac6(self, frame_id: int) -> np.ndarray:
        return self._pin.getFrameJacobian(self.model, self.data, frame_id, self._lwa)

    def pos(self, frame_id: int) -> np.ndarray:
        return self.data.oMf[frame_id].translation

    def rot(self, frame_id: int) -> np.ndarray:
        return self.data.oMf[frame_id].rotation

    def outputs(self, q, stance: str, heading_rad: float) -> tuple[np.ndarray, np.ndarray]:
        """``(h, J_h)`` at the last :meth:`compute` (``q`` must be the same)."""
        robot, d = self.robot, self.data
        swing = "right" if stance == "left" else "left"
        bid = robot.base_frame_id
        R = self.rot(bid)
        Jw = self.jac6(bid)[3:]
        c, Jc = d.com[0], d.Jcom
        cst, csw = robot.contact_frame_ids[stance], robot.contact_frame_ids[swing]
        p_st, J_st = c - self.pos(cst), Jc - self.jac6(cst)[:3]
        p_sw, J_sw = c - self.pos(csw), Jc - self.jac6(csw)[:3]

        col_jac: dict[int, np.ndarray] = {}

        def entry_jac(i: int, j: int) -> np.ndarray:
            # d/dt R_ij = e_i . (w x r_j) = (skew(r_j) w)_i ... with skew(r) w = r x w, sign flipped
            cj = col_jac.get(j)
            if cj is None:
                x, y, z = R[:, j]
                cj = np.array([[0.0, z, -y], [-z, 0.0, x], [y, -x, 0.0]]) @ Jw
                col_jac[j] = cj
            return cj[i]

        if self.layout == "planar":
            a, b = R[0, 2], R[2, 2]
            r2 = a * a + b * b
            pitch = np.arctan2(a, b)
            J_pitch = (b * entry_jac(0, 2) - a * entry_jac(2, 2)) / r2
            xD = np.array([np.cos(heading_rad), np.sin(heading_rad), 0.0])
            h = np.array([pitch, p_st[2], xD @ p_sw, p_sw[2]])
            J = np.vstack([J_pitch, J_st[2], xD @ J_sw, J_sw[2]])
            return h, J
        # Cassie layout
        r00, r10, r20, r21, r22 = R[0, 0], R[1, 0], R[2, 0], R[2, 1], R[2, 2]
        rho = np.hypot(r00, r10)
        J_rho = (r00 * entry_jac(0, 0) + r10 * entry_jac(1, 0)) / rho
        pitch = np.arctan2(-r20, rho)
        den = r20 * r20 + rho * rho
        J_pitch = (rho * -entry_jac(2, 0) - (-r20) * J_rho) / den
        roll = np.arctan2(r21, r22)
        J_roll = (r22 * entry_jac(2, 1) - r21 * entry_jac(2, 2)) / (r21 * r21 + r22 * r22)
        nv = self.model.nv
        J_yaw_st = np.zeros(nv)
        J_yaw_st[self._yaw_v[stance]] = 1.0
        J_yaw_sw = np.zeros(nv)
        J_yaw_sw[self._yaw_v[swing]] = 1.0
        xD = np.array([np.cos(heading_rad), np.sin(heading_rad), 0.0])
        yD = np.array([-np.sin(heading_rad), np.cos(heading_rad), 0.0])
        toe, heel = robot.force_frame_ids[swing]
        dv = self.pos(toe) - self.pos(heel)
        Jd = self.jac6(toe)[:3] - self.jac6(heel)[:3]
        rxy = np.hypot(dv[0], dv[1])
        J_rxy = (dv[0] * Jd[0] + dv[1] * Jd[1]) / rxy
        toe_pitch = np.arctan2(-dv[2], rxy)
        J_toe = (rxy * -Jd[2] - (-dv[2]) * J_rxy) / (dv[2] ** 2 + rxy**2)
        h = np.array(
            [
                pitch,
                roll,
                q[self._yaw_q[stance]],
                q[self._yaw_q[swing]],
                p_st[2],
                xD @ p_sw,
                yD @ p_sw,
                p_sw[2],
                toe_pitch,
            ]
        )
        J = np.vstack([J_pitch, J_roll, J_yaw_st, J_yaw_sw, J_st[2], xD @ J_sw, yD @ J_sw, J_sw[2], J_toe])
        return h, J


class IterativeIK:
    """Damped-Newton IK from ``h_d`` to joint references (formulation in the module docstring).

    Args:
        robot: The :class:`~amlip_qp.robots.robot.Robot`.
        settings: Iteration settings.

    Raises:
        MJCFError: The model does not give a square system (outputs + held
            coordinates != nv).
    """

    def __init__(self, robot, settings: IKSettings | None = None):
        import pinocchio as pin

        self._pin = pin
        self.robot = robot
        self.settings = settings or IKSettings()
        self.model = robot.pin_model
        self.ev = _OutputEval(robot)
        nv = self.model.nv
        m = self.model
        # in-plane rows of the contact pose (planar robots: x, z, pitch)
        if robot.is_planar:
            self._pose_rows = np.array([0, 2, 4])
        else:
            self._pose_rows = np.arange(6)
        # spring rows: passive joints outside couplings, and coupling lengths
        coupled_v = {int(i) for c in robot.couplings for i in c.pin_v_idx}
        self._spring_q = np.array(
            [qi for qi, vi in zip(robot.passive_q_idx, robot.passive_v_idx) if int(vi) not in coupled_v], dtype=int
        )
        self._spring_v = np.array([vi for vi in robot.passive_v_idx if int(vi) not in coupled_v], dtype=int)
        n_fixed = len(self._pose_rows) + len(self._spring_v) + len(robot.couplings)
        # the stance ankle: the contact frame's parent joint, if actuated and needed
        self._ankle_v: dict[str, int | None] = {}
        self._ankle_q: dict[str, int | None] = {}
        need_ankle = nv - (self.ev.size + n_fixed)
        if need_ankle not in (0, 1):
            raise MJCFError(
                f"{robot.name}: IK needs {nv} equations, has {self.ev.size} outputs + {n_fixed} held coordinates"
            )
        act_v = [int(i) for i in robot.actuated.pin_v_idx]
        for side in robot.foot_sides:
            jid = m.frames[robot.contact_frame_ids[side]].parentJoint
            iv, iq = m.joints[jid].idx_v, m.joints[jid].idx_q
            if need_ankle == 1:
                if iv not in act_v:
                    raise MJCFError(f"{robot.name}: the {side} contact's parent joint is not actuated")
                self._ankle_v[side], self._ankle_q[side] = iv, iq
            else:
                self._ankle_v[side] = self._ankle_q[side] = None
        self._n_fixed = n_fixed + need_ankle
        self._act_q = robot.actuated.pin_q_idx
        self._lo = m.lowerPositionLimit[self._act_q].copy()
        self._hi = m.upperPositionLimit[self._act_q].copy()
        self._prev: IKResult | None = None
        self._prev_stance: str | None = None
        self._prev_heading = 0.0

    def reset(self) -> None:
        """Forget the warm start."""
        self._prev = None
        self._prev_stance = None

    # ---------------------------------------------------------------- pieces
    def controlled_actuated(self, stance: str) -> np.ndarray:
        """Indices into the actuator list of the joints the IK solves for (all but the stance ankle)."""
        ankle = self._ankle_v[stance]
        return np.array([k for k, iv in enumerate(self.robot.actuated.pin_v_idx) if iv != ankle], dtype=int)

    def _system(self, q, stance, heading, h_d, fixed) -> tuple[np.ndarray, np.ndarray]:
        """Residual ``F(q)`` and matrix ``A(q)`` at ``q`` (kinematics computed here)."""
        ev, robot = self.ev, self.robot
        ev.compute(q)
        h, Jh = ev.outputs(q, stance, heading)
        cid = robot.contact_frame_ids[stance]
        p_err = ev.pos(cid) - fixed["contact_pos"]
        r_err = self._pin.log3(ev.rot(cid) @ fixed["contact_rot"].T)
        pose_err = np.concatenate([p_err, r_err])[self._pose_rows]
        J_pose = ev.jac6(cid)[self._pose_rows]
        nv = self.model.nv
        rows_F = [h - h_d, pose_err]
        rows_A = [Jh, J_pose]
        if self._ankle_v[stance] is not None:
            e = np.zeros((1, nv))
            e[0, self._ankle_v[stance]] = 1.0
            rows_A.append(e)
            rows_F.append(np.array([q[self._ankle_q[stance]] - fixed["ankle"]]))
        if len(self._spring_v):
            E = np.zeros((len(self._spring_v), nv))
            E[np.arange(len(self._spring_v)), self._spring_v] = 1.0
            rows_A.append(E)
            rows_F.append(q[self._spring_q] - fixed["springs"])
        for k, c in enumerate(robot.couplings):
            g = np.zeros((1, nv))
            np.add.at(g[0], c.pin_v_idx, c.coefficients)
            rows_A.append(g)
            rows_F.append(np.array([c.coefficients @ q[c.pin_q_idx] - fixed["couplings"][k]]))
        return np.concatenate(rows_F), np.vstack(rows_A)

    def _fixed_from(self, kin, stance: str) -> dict:
        """The held quantities and their estimated rates, from the updated kinematics."""
        robot = self.robot
        q, v = kin.q, kin.v
        cid = robot.contact_frame_ids[stance]
        twist = kin.frame_jacobian6(cid) @ v
        fixed = {
            "contact_pos": kin.frame_position(cid),
            "contact_rot": kin.frame_rotation(cid),
            "springs": q[self._spring_q].copy(),
            "couplings": np.array([c.coefficients @ q[c.pin_q_idx] for c in robot.couplings]),
        }
        rates = [twist[self._pose_rows]]
        if self._ankle_v[stance] is not None:
            fixed["ankle"] = float(q[self._ankle_q[stance]])
            rates.append(np.array([v[self._ankle_v[stance]]]))
        rates.append(np.zeros(len(self._spring_v) + len(robot.couplings)))
        fixed["rates"] = np.concatenate(rates)
        return fixed

    def _newton_step(self, F: np.ndarray, A: np.ndarray) -> np.ndarray:
        mu = self.settings.damping
        dq = np.linalg.solve(A.T @ A + mu * np.eye(A.shape[1]), -A.T @ F)
        nb = self.model.nv - len(self.robot.actuated) - len(self.robot.passive_v_idx)
        jmax = float(np.max(np.abs(dq[nb:]))) if dq.size > nb else 0.0
        if jmax > self.settings.max_step_rad:
            dq *= self.settings.max_step_rad / jmax
        return dq

    # ------------------------------------------------------------------ solve
    def solve(self, kin, stance: str, heading_rad: float, h_d, dh_d, ddh_d, iterations: int | None = None) -> IKResult:
        """Joint references for the outputs ``h_d`` (m, rad) and their rates.

        Args:
            kin: The controller's :class:`~amlip_qp.robots.kinematics.RobotKinematics`,
                updated at the estimate (read only).
            stance: Stance side.
            heading_rad: Step heading ``D`` (rad).
            h_d, dh_d, ddh_d: Reference outputs and their first and second time derivatives.
            iterations: Newton iterations (default: settings, cold or warm).

        Returns:
            An :class:`IKResult`; on failure (non-finite values or a singular
            system) the previous reference with ``ok=False`` (the estimate
            with zero rates if there is none).
        """
        pin = self._pin
        h_d = np.asarray(h_d, dtype=float)
        dh_d = np.asarray(dh_d, dtype=float)
        ddh_d = np.asarray(ddh_d, dtype=float)
        n = self.ev.size
        if h_d.shape != (n,) or dh_d.shape != (n,) or ddh_d.shape != (n,):
            raise InputError(f"h_d, dh_d, ddh_d must have shape ({n},)")
        try:
            fixed = self._fixed_from(kin, stance)
            warm = (
                self._prev is not None
                and self._prev.ok
                and self._prev_stance == stance
                and np.all(np.isfinite(h_d))
            )
            # warm start: the previous solution (its held coordinates are pulled to
            # this tick's estimates by the linear rows in one step); cold: the estimate
            q = self._prev.q_r.copy() if warm else kin.q.copy()
            n_it = iterations or (self.settings.iterations if warm else self.settings.cold_iterations)
            for _ in range(n_it):
                F, A = self._system(q, stance, heading_rad, h_d, fixed)
                q = pin.integrate(self.model, q, self._newton_step(F, A))
                q[self._act_q] = np.clip(q[self._act_q], self._lo, self._hi)
            F, A = self._system(q, stance, heading_rad, h_d, fixed)
            residual = float(np.max(np.abs(F)))
            v_r = np.linalg.solve(A, np.concatenate([dh_d, fixed["rates"]]))
            eps = self.settings.fd_step_s
            q_eps = pin.integrate(self.model, q, eps * v_r)
            _, A_eps = self._system(q_eps, stance, heading_rad, h_d, fixed)
            adot_v = (A_eps - A) @ v_r / eps
            a_r = np.linalg.solve(A, np.concatenate([ddh_d, np.zeros(self._n_fixed)]) - adot_v)
            if not (np.all(np.isfinite(q)) and np.all(np.isfinite(v_r)) and np.all(np.isfinite(a_r))):
                raise FloatingPointError("non-finite IK result")
        except (np.linalg.LinAlgError, FloatingPointError, ValueError) as exc:
            if isinstance(exc, InputError):
                raise
            return self._failed(kin.q)
        res = IKResult(q_r=q, v_r=v_r, a_r=a_r, iterations=n_it, residual=residual, ok=True)
        self._prev, self._prev_stance = res, stance
        return res

    def _failed(self, q_est: np.ndarray) -> IKResult:
        """The previous reference (or the estimate) with zero rates, flagged ``ok=False``."""
        prev = self._prev
        q_r = prev.q_r.copy() if prev is not None else q_est.copy()
        nv = self.model.nv
        self._prev = None
        return IKResult(q_r, np.zeros(nv), np.zeros(nv), 0, float("nan"), ok=False)
