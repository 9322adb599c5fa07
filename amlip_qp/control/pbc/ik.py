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
- ``A a_r = [ddh_d; 0] - Adot v_r``; the unactuated accelerations are taken
  as 0. The drift ``Adot v`` is exact (a finite difference of ``A`` along
  ``v_r``) on cold solves and whenever ``iterations`` is given; on warm
  default solves it is the analytic drift of the output map and contact frame
  at the previous tick's ``v_r`` (one full kinematics update at ``(q, v_r^-)``
  replaces the finite difference's extra evaluation). ``Adot v`` is quadratic
  in ``v``, so the error is about ``2 |dAdot/dv| |v_r| |v_r - v_r^-|``, i.e.
  of the order of ``|a_r| dt`` relative to the drift (checked in
  tests/test_control_ik.py).

Evaluation: ``h_0(q)`` and its Jacobian come from the one output map,
:class:`amlip_qp.robots.outputs.OutputMap`, evaluated on the IK's own
:class:`~amlip_qp.robots.kinematics.RobotKinematics` (its own Pinocchio data)
through the light :meth:`~amlip_qp.robots.kinematics.RobotKinematics.update_positions`.

Robustness: each Newton step solves ``A dq = -F`` (LU; a damped least-squares
step ``(A^T A + mu I) dq = -A^T F`` only if the LU step is not finite), its
joint part is limited to :attr:`IKSettings.max_step_rad`, the actuated joints
are clamped to their ranges; any non-finite result falls back to the previous
reference.

Cost (per warm tick): the evaluation at the final ``q_r`` of one tick (its
values, ``A`` and the LU of ``A``) is kept and gives the first Newton step of
the next tick for free (``A`` depends on ``q`` only; the residual is rebuilt
with the new targets and estimates), then one evaluation at the new ``q``
(more steps only while the residual is above :attr:`IKSettings.tolerance`),
which also gives the drift: typically one output-map evaluation per tick
(about 160 us for Cassie, against about 1 ms with the previous duplicate
output code and four evaluations).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from scipy.linalg.lapack import dgetrf as _dgetrf
from scipy.linalg.lapack import dgetrs as _dgetrs

from amlip_qp.alip import other_side
from amlip_qp.exceptions import InputError, MJCFError

if TYPE_CHECKING:  # pragma: no cover - typing only
    from amlip_qp.robots.kinematics import RobotKinematics
    from amlip_qp.robots.robot import Robot


@dataclass(frozen=True)
class IKSettings:
    """Settings of :class:`IterativeIK`.

    Attributes:
        iterations: Most Newton iterations per call when warm-started (the
            first one reuses the previous tick's final evaluation).
        cold_iterations: Most Newton iterations when starting from the estimate
            (first call, after a stance switch or a failure).
        tolerance: Stop iterating once the max-norm residual is below this
            (m / rad); only for the default iteration counts, an explicit
            ``iterations`` argument of :meth:`IterativeIK.solve` runs them all.
        damping: Levenberg damping ``mu`` of the fallback step
            ``(A^T A + mu I) dq = -A^T F``, used only when the LU step is not
            finite (dimensionless; the rows are in m and rad).
        max_step_rad: Largest joint change per Newton step, rad (m for slide joints).
        fd_step_s: Time step of the finite difference for ``Adot v``, s.
        knee_limit_swap: When the iterations end unconverged (max-norm
            residual above ``swap_threshold``, m / rad) with a knee clamped at
            its straight-leg range limit: if that knee's output is out of reach
            (``com_z_over_stance`` for the stance knee, ``com_x_over_swing`` for
            the swing knee, with ``|y| < |h_d|``) exchange it for "knee = limit"
            (a square system again) and iterate on -- that output gives way
            (CoM height; how far the swing foot reaches) and all the others
            stay exact; otherwise restart the iterations with the knee moved
            ``knee_back_off_rad`` off the limit (the straight leg is a
            near-singular iterate). Without this the clamp breaks the rows
            through the knee (Cassie's coupling), the next step undoes it, and
            the iterates wander with residuals of order 1 (seen after the long
            steps of a push recovery).
        swap_threshold: See ``knee_limit_swap``.
        knee_back_off_rad: See ``knee_limit_swap``, rad.
    """

    iterations: int = 2
    cold_iterations: int = 8
    tolerance: float = 1e-6
    damping: float = 1e-10
    max_step_rad: float = 0.3
    fd_step_s: float = 1e-6
    knee_limit_swap: bool = True
    swap_threshold: float = 1e-3
    knee_back_off_rad: float = 0.2

    def __post_init__(self):
        if self.iterations < 1 or self.cold_iterations < 1:
            raise InputError("IK iteration counts must be >= 1")
        if not (self.damping >= 0 and self.max_step_rad > 0 and self.fd_step_s > 0 and self.tolerance >= 0):
            raise InputError("IK damping and tolerance must be >= 0, max_step_rad and fd_step_s > 0")


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
        knee_at_limit: A knee was held at its straight-leg limit in place of an
            unreachable output (``com_z_over_stance`` for the stance knee,
            ``com_x_over_swing`` for the swing knee).
    """

    q_r: np.ndarray
    v_r: np.ndarray
    a_r: np.ndarray
    iterations: int
    residual: float
    ok: bool = True
    knee_at_limit: bool = False


def _finite(*arrays) -> bool:
    """True if every entry is finite (a NaN or inf makes the sum non-finite; cheaper than
    ``np.all(np.isfinite(.))`` on these small arrays)."""
    return all(math.isfinite(float(np.sum(a))) for a in arrays)


def _lu_solve(lu, b: np.ndarray) -> np.ndarray:
    """Solve with LU factors from :meth:`IterativeIK._lu` (LAPACK getrs)."""
    x, info = _dgetrs(lu[0], lu[1], b)
    if info != 0:
        raise np.linalg.LinAlgError(f"getrs info {info}")
    return x


class _StanceRows:
    """Per-stance constant parts of the system (built once)."""

    def __init__(self, nv: int, n_out: int, n_pose: int, lin_q: np.ndarray, lin_v: np.ndarray, lin_rate: np.ndarray):
        self.n_var = n_out + n_pose  # rows that change with q
        self.lin_q = lin_q  # (n_lin, nq): linear residual rows  L_q q - b
        self.lin_rate = lin_rate  # (n_lin, nv): held rates = lin_rate @ v_est
        self.A = np.zeros((nv, nv))
        self.A[self.n_var :] = lin_v
        self.A_eps = self.A.copy()
        self.drift = np.zeros(self.n_var)
        self.F = np.zeros(nv)


class IterativeIK:
    """Damped-Newton IK from ``h_d`` to joint references (formulation in the module docstring).

    Args:
        robot: The :class:`~amlip_qp.robots.robot.Robot`.
        settings: Iteration settings.

    Attributes:
        kin: The IK's own :class:`~amlip_qp.robots.kinematics.RobotKinematics`
            (light position updates at the iterates).
        size: Number of outputs.

    Raises:
        MJCFError: The model does not give a square system (outputs + held
            coordinates != nv).
    """

    def __init__(self, robot: Robot, settings: IKSettings | None = None):
        import pinocchio as pin

        from amlip_qp.robots.kinematics import RobotKinematics
        from amlip_qp.robots.outputs import OutputMap

        self._pin = pin
        self.robot = robot
        self.settings = settings or IKSettings()
        self.model = m = robot.pin_model
        self.kin = RobotKinematics(robot)
        self.size = OutputMap(robot).size
        nv, nq = m.nv, m.nq
        # in-plane rows of the contact pose (planar robots: x, z, pitch)
        self._pose_rows = np.array([0, 2, 4]) if robot.is_planar else np.arange(6)
        self._planar = robot.is_planar
        # Held springs: the passive joints outside couplings, then the coupling lengths.
        springs = robot.springs
        #: The springs the IK holds, in the order of ``held_springs`` of :meth:`solve`.
        self.held_springs = tuple(r for r in springs if r.kind == "joint") + tuple(
            r for r in springs if r.kind == "coupling"
        )
        n_fixed = len(self._pose_rows) + len(self.held_springs)
        need_ankle = nv - (self.size + n_fixed)
        if need_ankle not in (0, 1):
            raise MJCFError(
                f"{robot.name}: IK needs {nv} equations, has {self.size} outputs + {n_fixed} held coordinates"
            )
        # the stance ankle: the contact frame's parent joint, if actuated and needed
        self._ankle_v: dict[str, int | None] = {}
        self._ankle_q: dict[str, int | None] = {}
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
        # linear rows per stance: ankle (held, with its estimated rate), springs and couplings (rate 0)
        self._rows: dict[str, _StanceRows] = {}
        for side in robot.foot_sides:
            lq, lv, lr = [], [], []
            if self._ankle_v[side] is not None:
                r_q, r_v = np.zeros(nq), np.zeros(nv)
                r_q[self._ankle_q[side]] = 1.0
                r_v[self._ankle_v[side]] = 1.0
                lq.append(r_q), lv.append(r_v), lr.append(r_v.copy())
            for spring in self.held_springs:
                lq.append(spring.row_q(nq)), lv.append(spring.row_v(nv)), lr.append(np.zeros(nv))
            self._rows[side] = _StanceRows(
                nv, self.size, len(self._pose_rows), np.array(lq).reshape(-1, nq),
                np.array(lv).reshape(-1, nv), np.array(lr).reshape(-1, nv)
            )
        # knee <-> output exchanges when a leg cannot reach (see IKSettings.knee_limit_swap):
        # (output row, knee q index, knee v index, straight-leg limit)
        names = list(OutputMap(robot).names)
        smap = robot.state_map
        self._knee_swap: dict[str, list] = {side: [] for side in robot.foot_sides}
        if self.settings.knee_limit_swap and all(f"{sd}-knee" in smap.joint_pin_q for sd in robot.foot_sides):
            k0 = RobotKinematics(robot)
            k0.update_positions(robot.q_stand)
            for side in robot.foot_sides:
                other = other_side(side)
                _, J0, _ = k0.outputs(side, 0.0)
                for row_name, knee_side in (("com_z_over_stance", side), ("com_x_over_swing", other)):
                    if row_name not in names:
                        continue
                    iq, iv = smap.joint_pin_q[f"{knee_side}-knee"], smap.joint_pin_v[f"{knee_side}-knee"]
                    # straight leg = the limit towards which the stance CoM height grows
                    grow = J0[names.index("com_z_over_stance"), smap.joint_pin_v[f"{side}-knee"]]
                    lo_, hi_ = float(m.lowerPositionLimit[iq]), float(m.upperPositionLimit[iq])
                    limit, other_end = (hi_, lo_) if grow > 0 else (lo_, hi_)
                    self._knee_swap[side].append((names.index(row_name), iq, iv, limit, other_end))
        self._act_q = robot.actuated.pin_q_idx
        self._lo = m.lowerPositionLimit[self._act_q].copy()
        self._hi = m.upperPositionLimit[self._act_q].copy()
        self._nb = nv - len(robot.actuated) - len(robot.passive_v_idx)  # base coordinates
        self._eye = np.eye(nv)
        self._prev: IKResult | None = None
        self._prev_stance: str | None = None
        # the last final evaluation: (stance, heading, y, contact pos, contact rot, LU of A)
        self._cache: tuple | None = None
        #: LU factors of ``A(q_r)`` of the last successful solve (see :meth:`solve_linear`).
        self.lu = None

    def reset(self) -> None:
        """Forget the warm start."""
        self._prev = None
        self._prev_stance = None
        self._cache = None
        self.lu = None

    # ---------------------------------------------------------------- pieces
    def controlled_actuated(self, stance: str) -> np.ndarray:
        """Indices into the actuator list of the joints the IK solves for (all but the stance ankle)."""
        ankle = self._ankle_v[stance]
        return np.array([k for k, iv in enumerate(self.robot.actuated.pin_v_idx) if iv != ankle], dtype=int)

    def _evaluate(self, q, stance: str, heading: float, A: np.ndarray, v=None):
        """Kinematics at ``q``: fill the varying rows of ``A``; return ``(y, contact pos, contact rot)``.

        With a velocity ``v`` the IK's kinematics get a full update at ``(q, v)``
        (then :meth:`_drift` gives ``Adot v``); without, the light position update.
        """
        kin = self.kin
        if v is None:
            kin.update_positions(q)
        else:
            kin.update(q, v)
        y, J, _ = kin.outputs(stance, heading)
        n = self.size
        A[:n] = J
        cid = self.robot.contact_frame_ids[stance]
        A[n : n + len(self._pose_rows)] = kin.frame_jacobian6(cid)[self._pose_rows]
        oMf = kin.data.oMf[cid]
        return y, oMf.translation.copy(), oMf.rotation.copy()

    def _drift(self, stance: str, heading: float, out: np.ndarray) -> None:
        """``Adot v`` of the varying rows at the last full :meth:`_evaluate` (its ``v``) into ``out``."""
        kin = self.kin
        n = self.size
        out[:n] = kin.outputs(stance, heading)[2]
        out[n : n + len(self._pose_rows)] = kin.frame_jdot_v6(self.robot.contact_frame_ids[stance])[self._pose_rows]

    def _residual(self, rows: _StanceRows, q, y, pos, rot, h_d, fixed) -> np.ndarray:
        """Fill and return ``F(q)`` from the evaluated values and this tick's targets/estimates."""
        F, n = rows.F, self.size
        np.subtract(y, h_d, out=F[:n])
        p_err = pos - fixed["contact_pos"]
        r_err = self._pin.log3(rot @ fixed["contact_rot"].T)
        if self._planar:
            F[n], F[n + 1], F[n + 2] = p_err[0], p_err[2], r_err[1]
        else:
            F[n : n + 3] = p_err
            F[n + 3 : n + 6] = r_err
        F[rows.n_var :] = rows.lin_q @ q - fixed["lin"]
        return F

    def _fixed_from(self, kin: RobotKinematics, stance: str) -> dict:
        """The held quantities and their estimated rates, from the updated kinematics."""
        rows = self._rows[stance]
        q, v = kin.q, kin.v
        cid = self.robot.contact_frame_ids[stance]
        twist = kin.frame_jacobian6(cid) @ v
        rates = np.empty(self.model.nv - self.size)
        npose = len(self._pose_rows)
        rates[:npose] = twist[self._pose_rows]
        rates[npose:] = rows.lin_rate @ v
        return {
            "contact_pos": kin.frame_position(cid),
            "contact_rot": kin.frame_rotation(cid),
            "lin": rows.lin_q @ q,
            "rates": rates,
        }

    def _limit_handling(self, stance: str, q, F, y, h_d) -> tuple[list | None, list]:
        """For an unconverged solve: the knees clamped at their straight-leg limit, split into
        ``(swap, back_off)``.

        A clamp breaks the rows through the knee (Cassie's coupling ``q_knee +
        q_tarsus``), which the next step undoes: the iterates then wander with
        residuals of order 1. If the knee's output is out of reach
        (``|y| < |h_d|``: CoM too low over the stance foot, swing foot short
        of its target) the output is exchanged for "knee = limit" (``swap``);
        otherwise the straight leg is only a bad (near-singular) iterate and
        the knee is moved back off the limit (``back_off``).
        """
        thr = self.settings.swap_threshold
        if float(np.max(np.abs(F))) <= thr:
            return None, []
        swap, back = [], []
        for sp in self._knee_swap[stance]:
            row, iq = sp[0], sp[1]
            if abs(q[iq] - sp[3]) < 1e-9:
                (swap if abs(y[row]) < abs(h_d[row]) - thr else back).append(sp)
        return (swap or None), back

    @staticmethod
    def _swap_rows(swap, q, A, F) -> None:
        """Replace each exchanged output row by ``q_knee - limit`` (row of that knee)."""
        if swap is None:
            return
        for row, iq, iv, limit, _ in swap:
            A[row] = 0.0
            A[row, iv] = 1.0
            if F is not None:
                F[row] = q[iq] - limit

    def _newton_step(self, F: np.ndarray, A: np.ndarray, lu) -> np.ndarray:
        dq = -_lu_solve(lu, F) if lu is not None else np.full(F.shape, np.nan)
        if not _finite(dq):
            mu = self.settings.damping
            dq = np.linalg.solve(A.T @ A + mu * self._eye, -A.T @ F)
        nb = self._nb
        jmax = float(np.max(np.abs(dq[nb:]))) if dq.size > nb else 0.0
        if jmax > self.settings.max_step_rad:
            dq *= self.settings.max_step_rad / jmax
        return dq

    def _step(self, q, dq) -> np.ndarray:
        q = self._pin.integrate(self.model, q, dq)
        aq = self._act_q
        q[aq] = np.minimum(np.maximum(q[aq], self._lo), self._hi)
        return q

    @staticmethod
    def _lu(A: np.ndarray):
        """LU factors of ``A`` (LAPACK getrf), or ``None`` if ``A`` is singular."""
        lu, piv, info = _dgetrf(A)
        return (lu, piv) if info == 0 else None

    def solve_linear(self, rhs) -> np.ndarray:
        """``A(q_r)^-1 rhs`` with the last successful solve's matrix (sensitivity of ``q_r`` to the
        targets: a change ``[dh; 0]`` of the right-hand side moves ``q_r`` by ``A^-1 [dh; 0]``).

        Raises:
            InputError: No successful solve yet.
        """
        if self.lu is None:
            raise InputError("IterativeIK.solve_linear: no successful solve yet")
        return _lu_solve(self.lu, np.asarray(rhs, dtype=float))

    # ------------------------------------------------------------------ solve
    def spring_rest_values(self) -> np.ndarray:
        """Rest values (rad) of :attr:`held_springs`, in the order of ``held_springs`` of
        :meth:`solve`: the passive joints outside couplings (their spring reference),
        then each coupling's rest length."""
        return np.array([spring.rest for spring in self.held_springs], dtype=float)

    def solve(
        self, kin: RobotKinematics, stance: str, heading_rad: float, h_d, dh_d, ddh_d, iterations: int | None = None, held_springs=None
    ) -> IKResult:
        """Joint references for the outputs ``h_d`` (m, rad) and their rates.

        Args:
            kin: The controller's :class:`~amlip_qp.robots.kinematics.RobotKinematics`,
                updated at the estimate (read only).
            stance: Stance side.
            heading_rad: Step heading ``D`` (rad).
            h_d, dh_d, ddh_d: Reference outputs and their first and second time derivatives.
            iterations: Newton iterations, all done (default: settings, cold or
                warm, stopping early below the tolerance).
            held_springs: Values at which to hold the springs instead of their
                estimates (order of :meth:`spring_rest_values`; e.g. the rest
                values, for the paper's rigid-spring IK plus a knee offset).

        Returns:
            An :class:`IKResult`; on failure (non-finite values or a singular
            system) the previous reference with ``ok=False`` (the estimate
            with zero rates if there is none).
        """
        pin = self._pin
        h_d = np.asarray(h_d, dtype=float)
        dh_d = np.asarray(dh_d, dtype=float)
        ddh_d = np.asarray(ddh_d, dtype=float)
        n = self.size
        if h_d.shape != (n,) or dh_d.shape != (n,) or ddh_d.shape != (n,):
            raise InputError(f"h_d, dh_d, ddh_d must have shape ({n},)")
        if stance not in self._rows:
            raise InputError(f"stance must be 'left' or 'right', got {stance!r}")
        if not _finite(h_d, dh_d, ddh_d) or not math.isfinite(heading_rad):
            return self._failed(kin.q)
        rows = self._rows[stance]
        A = rows.A
        s = self.settings
        try:
            fixed = self._fixed_from(kin, stance)
            if held_springs is not None:
                ns = len(self.held_springs)
                fixed["lin"][len(fixed["lin"]) - ns :] = held_springs
            warm = self._prev is not None and self._prev.ok and self._prev_stance == stance
            # warm start: the previous solution (its held coordinates are pulled to
            # this tick's estimates by the linear rows in one step); cold: the estimate
            q = self._prev.q_r.copy() if warm else kin.q.copy()
            exact = iterations is not None
            n_max = iterations if exact else (s.iterations if warm else s.cold_iterations)
            it = 0
            cache = self._cache
            # warm default solves take the drift Adot v at the previous v_r (see the module docstring)
            v_pred = self._prev.v_r if (warm and not exact) else None
            swap = None
            if warm and cache is not None and cache[0] == stance and cache[1] == heading_rad:
                # first step from the previous tick's final evaluation (same q, A)
                F = self._residual(rows, q, cache[2], cache[3], cache[4], h_d, fixed)
                self._swap_rows(cache[6], q, A, F)
                q = self._step(q, self._newton_step(F, A, cache[5]))
                it = 1
            self._cache = None
            limit_handled = False
            while True:
                y, pos, rot = self._evaluate(q, stance, heading_rad, A, v_pred)
                F = self._residual(rows, q, y, pos, rot, h_d, fixed)
                self._swap_rows(swap, q, A, F)
                residual = float(np.max(np.abs(F)))
                lu = self._lu(A)
                done = it >= n_max or (not exact and residual < s.tolerance)
                if done and swap is None and self._knee_swap[stance] and not limit_handled:
                    swap, back = self._limit_handling(stance, q, F, y, h_d)
                    limit_handled = True
                    if swap is not None:
                        # out of iterations, a knee straight and its output out of reach: trade
                        # that output for the knee held at the limit, and iterate on
                        self._swap_rows(swap, q, A, F)
                        residual = float(np.max(np.abs(F)))
                        lu = self._lu(A)
                        n_max = it + s.cold_iterations
                        done = not exact and residual < s.tolerance
                    elif back:
                        # reachable: restart the iterations with the knee off the singular straight leg
                        for sp in back:
                            q[sp[1]] = sp[3] + (s.knee_back_off_rad if sp[3] < sp[4] else -s.knee_back_off_rad)
                        n_max = it + s.cold_iterations
                        continue
                if done:
                    break
                q = self._step(q, self._newton_step(F, A, lu))
                it += 1
            if lu is None:
                raise np.linalg.LinAlgError("singular IK system")
            rhs_v = np.concatenate([dh_d, fixed["rates"]])
            if swap is not None:
                for sp in swap:
                    rhs_v[sp[0]] = 0.0
            v_r = _lu_solve(lu, rhs_v)
            cache = (stance, heading_rad, y, pos, rot, lu, swap)
            m = rows.n_var
            rhs = np.zeros(self.model.nv)
            if v_pred is not None:
                self._drift(stance, heading_rad, rows.drift)
                np.subtract(ddh_d, rows.drift[:n], out=rhs[:n])
                rhs[n:m] = -rows.drift[n:m]
            else:
                # exact: finite difference of A along v_r
                eps = s.fd_step_s
                q_eps = pin.integrate(self.model, q, eps * v_r)
                self._evaluate(q_eps, stance, heading_rad, rows.A_eps)
                self._swap_rows(swap, q_eps, rows.A_eps, None)
                rhs[:n] = ddh_d
                rhs[:m] -= (rows.A_eps[:m] - A[:m]) @ v_r / eps
            if swap is not None:
                for sp in swap:
                    rhs[sp[0]] = 0.0
            a_r = _lu_solve(lu, rhs)
            if not _finite(q, v_r, a_r):
                raise FloatingPointError("non-finite IK result")
        except (np.linalg.LinAlgError, FloatingPointError, ValueError) as exc:
            if isinstance(exc, InputError):
                raise
            return self._failed(kin.q)
        res = IKResult(q_r=q, v_r=v_r, a_r=a_r, iterations=it, residual=residual, ok=True, knee_at_limit=swap is not None)
        self._prev, self._prev_stance = res, stance
        self._cache, self.lu = cache, lu
        return res

    def _failed(self, q_est: np.ndarray) -> IKResult:
        """The previous reference (or the estimate) with zero rates, flagged ``ok=False``."""
        prev = self._prev
        q_r = prev.q_r.copy() if prev is not None else q_est.copy()
        nv = self.model.nv
        self._prev = None
        self._cache = None
        self.lu = None
        return IKResult(q_r, np.zeros(nv), np.zeros(nv), 0, float("nan"), ok=False)
