"""Iterative inverse kinematics: reference outputs ``h_d`` -> actuated-joint references.

The paper (section "Inverse Kinematics") converts the reference outputs
``h_d(s)`` into references for the actuated joints so that a joint-space
passivity-based controller can track them. This module does that conversion
by damped Newton iterations on the full Pinocchio configuration.

The equations (a square system of ``nv`` equations in the ``nv`` velocity
coordinates: the outputs, the held stance contact pose, stance ankle and
springs) are :mod:`amlip_qp.control.pbc.ik_equations`.

Velocity and acceleration references use the same matrix ``A(q_r)`` (the
stacked Jacobians of these equations):

- ``A v_r = [dh_d; b_fix]``, with ``b_fix`` the estimated rates of the held
  contact pose and stance ankle (they are the robot's unactuated motion,
  e.g. Rabbit's stance shin rotating) and 0 for the spring rows (rigid springs).
- ``A a_r = [ddh_d; 0] - Adot v_r``; the unactuated accelerations are taken
  as 0. The drift ``Adot v`` is exact (a finite difference of ``A`` along
  ``v_r``) on cold solves and whenever ``iterations`` is given; on warm
  default solves it is the analytic drift of the output map and contact frame
  at the previous tick's ``v_r`` (one kinematics update at ``(q, v_r^-)``
  replaces the finite difference's extra evaluation). ``Adot v`` is quadratic
  in ``v``, so the error is about ``2 |dAdot/dv| |v_r| |v_r - v_r^-|``, i.e.
  of the order of ``|a_r| dt`` relative to the drift (checked in
  tests/test_control_pbc_ik.py).

Evaluation: ``h_0(q)`` and its Jacobian come from the output map of the
kinematics :meth:`IterativeIK.solve` is given (the controller's: by default the
generated-C :class:`~amlip_qp.control.walking.outputs_compiled.CompiledOutputMap`,
else the Python :class:`amlip_qp.robots.outputs.OutputMap`; the same outputs to
rounding), evaluated on the IK's own
:class:`~amlip_qp.robots.kinematics.RobotKinematics` (its own Pinocchio data)
through the light :meth:`~amlip_qp.robots.kinematics.RobotKinematics.update_positions`.

Robustness: each Newton step (:mod:`~amlip_qp.control.pbc.ik_newton`) solves
``A dq = -F`` (LU; a damped least-squares step ``(A^T A + mu I) dq = -A^T F``
only if the LU step is not finite), its joint part is limited to
:attr:`IKSettings.max_step_rad`, the actuated joints are clamped to their
ranges; any non-finite result falls back to the previous reference.

Cost (per warm tick): the evaluation at the final ``q_r`` of one tick (its
values, ``A`` and the LU of ``A``) is kept and gives the first Newton step of
the next tick for free (``A`` depends on ``q`` only; the residual is rebuilt
with the new targets and estimates), then one evaluation at the new ``q``
(more steps only while the residual is above :attr:`IKSettings.tolerance`),
which also gives the drift: typically one output-map evaluation per tick
(measured in ``docs/TUNING.md``, "PBC tracker and walking loop").
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from amlip_qp.control.pbc.ik_equations import IKEquations, StanceRows
from amlip_qp.control.pbc.ik_newton import all_finite, lu_factor, lu_solve, newton_step
from amlip_qp.control.pbc.ik_settings import IKResult, IKSettings
from amlip_qp.control.pbc.knee_limits import KneeLimits, swap_rows
from amlip_qp.exceptions import InputError

if TYPE_CHECKING:  # pragma: no cover - typing only
    from amlip_qp.robots.kinematics import RobotKinematics
    from amlip_qp.robots.robot import Robot


class IterativeIK:
    """Damped-Newton IK from ``h_d`` to joint references (formulation in the module docstring).

    Args:
        robot: The :class:`~amlip_qp.robots.robot.Robot`.
        settings: Iteration settings.

    Attributes:
        kin: The IK's own :class:`~amlip_qp.robots.kinematics.RobotKinematics`
            (light position updates at the iterates), on the output map of the
            kinematics last given to :meth:`solve` (the Python
            :class:`~amlip_qp.robots.outputs.OutputMap` before any).
        size: Number of outputs.

    Raises:
        MJCFError: The model does not give a square system
            (:class:`~amlip_qp.control.pbc.ik_equations.IKEquations`).
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
        nv = m.nv
        #: The equations of the system (held coordinates and their rows per stance).
        self.equations = eq = IKEquations(robot, self.size)
        # the same rows as a slice (x, z, pitch: every other row; all six), read as a view
        self._pose = slice(0, 5, 2) if robot.is_planar else slice(0, 6)
        self._npose = len(eq.pose_rows)
        self._planar = robot.is_planar
        self._rows = eq.rows
        # knee <-> output exchanges when a leg cannot reach (see IKSettings.knee_limit_swap)
        self._knees = KneeLimits(robot, self.settings) if self.settings.knee_limit_swap else None
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

    @property
    def last_result(self) -> IKResult | None:
        """The last successful solve's result (the next solve's warm start); ``None``
        before any, after :meth:`reset` or after a failed solve. Read-only."""
        return self._prev

    def reset(self) -> None:
        """Forget the warm start."""
        self._prev = None
        self._prev_stance = None
        self._cache = None
        self.lu = None

    # ---------------------------------------------------------------- pieces
    def _adopt_output_map(self, output_map) -> None:
        """Evaluate ``output_map`` (the caller's kinematics' map) from now on, on fresh kinematics."""
        from amlip_qp.robots.kinematics import RobotKinematics

        self.kin = RobotKinematics(self.robot, output_map)
        self._cache = None  # the last evaluation was another map's

    def _evaluate(self, q, stance: str, heading: float, A: np.ndarray, v=None):
        """Kinematics at ``q``: fill the varying rows of ``A``; return ``(y, contact pos, contact rot)``.

        With a velocity ``v`` the IK's kinematics get the kinematics-only update at ``(q, v)``
        (the same bits as the full update's kinematics; then :meth:`_drift` gives ``Adot v``);
        without, the light position update.
        """
        kin = self.kin
        if v is None:
            kin.update_positions(q)
        else:
            kin.update_kinematics(q, v)
        y, J, _ = kin.outputs(stance, heading)
        n = self.size
        A[:n] = J
        cid = self.robot.contact_frame_ids[stance]
        A[n : n + self._npose] = kin.frame_jacobian6(cid)[self._pose]
        return y, kin.frame_position(cid), kin.frame_rotation(cid)

    def _drift(self, stance: str, heading: float, out: np.ndarray) -> None:
        """``Adot v`` of the varying rows at the last :meth:`_evaluate` with a ``v`` into ``out``."""
        kin = self.kin
        n = self.size
        out[:n] = kin.outputs(stance, heading)[2]
        out[n : n + self._npose] = kin.frame_jdot_v6(self.robot.contact_frame_ids[stance])[self._pose]

    def _residual(self, rows: StanceRows, q, y, pos, rot, h_d, fixed) -> np.ndarray:
        """Fill and return ``F(q)`` from the evaluated values and this tick's targets/estimates."""
        F, n = rows.F, self.size
        np.subtract(y, h_d, out=F[:n])
        r_err = self._pin.log3(rot @ fixed["contact_rot"].T)
        if self._planar:
            p_err = pos - fixed["contact_pos"]
            F[n], F[n + 1], F[n + 2] = p_err[0], p_err[2], r_err[1]
        else:
            np.subtract(pos, fixed["contact_pos"], out=F[n : n + 3])
            F[n + 3 : n + 6] = r_err
        np.subtract(np.dot(rows.lin_q, q), fixed["lin"], out=F[rows.n_var :])
        return F

    def _fixed_from(self, kin: RobotKinematics, stance: str) -> dict:
        """The held quantities and their estimated rates, from the updated kinematics."""
        rows = self._rows[stance]
        q, v = kin.state()
        cid = self.robot.contact_frame_ids[stance]
        twist = np.dot(kin.frame_jacobian6(cid), v)
        rates = np.empty(self.model.nv - self.size)
        npose = self._npose
        rates[:npose] = twist[self._pose]
        rates[npose:] = np.dot(rows.lin_rate, v)
        lin = np.dot(rows.lin_q, q)
        lin[rows.posture] = rows.posture_target  # posture joints: at the stand pose (their rates are 0)
        return {
            "contact_pos": kin.frame_position(cid),
            "contact_rot": kin.frame_rotation(cid),
            "lin": lin,
            "rates": rates,
        }

    def _newton_step(self, F: np.ndarray, A: np.ndarray, lu) -> np.ndarray:
        s = self.settings
        return newton_step(F, A, lu, s.damping, s.max_step_rad, self._nb, self._eye)

    def _step(self, q, dq) -> np.ndarray:
        q = self._pin.integrate(self.model, q, dq)
        aq = self._act_q
        q[aq] = np.minimum(np.maximum(q[aq], self._lo), self._hi)
        return q

    def solve_linear(self, rhs) -> np.ndarray:
        """``A(q_r)^-1 rhs`` with the last successful solve's matrix (sensitivity of ``q_r`` to the
        targets: a change ``[dh; 0]`` of the right-hand side moves ``q_r`` by ``A^-1 [dh; 0]``).

        Raises:
            InputError: No successful solve yet.
        """
        if self.lu is None:
            raise InputError("IterativeIK.solve_linear: no successful solve yet")
        return lu_solve(self.lu, np.asarray(rhs, dtype=float))

    # ------------------------------------------------------------------ solve
    def solve(
        self,
        kin: RobotKinematics,
        stance: str,
        heading_rad: float,
        h_d,
        dh_d,
        ddh_d,
        iterations: int | None = None,
        held_springs=None,
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
                estimates (order of :meth:`IKEquations.spring_rest_values
                <amlip_qp.control.pbc.ik_equations.IKEquations.spring_rest_values>`; e.g. the rest
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
        if not all_finite(h_d, dh_d, ddh_d) or not math.isfinite(heading_rad):
            return self._failed(kin)
        if kin.output_map is not self.kin.output_map:
            self._adopt_output_map(kin.output_map)
        rows = self._rows[stance]
        A = rows.A
        s = self.settings
        try:
            fixed = self._fixed_from(kin, stance)
            if held_springs is not None:
                ns = len(self.equations.held_springs)
                fixed["lin"][len(fixed["lin"]) - ns :] = held_springs
            prev = self._prev
            warm_start = prev if prev is not None and prev.ok and self._prev_stance == stance else None
            warm = warm_start is not None
            # warm start: the previous solution (its held coordinates are pulled to
            # this tick's estimates by the linear rows in one step); cold: the estimate
            q = warm_start.q_r.copy() if warm_start is not None else kin.state()[0].copy()
            exact = iterations is not None
            n_max = iterations if iterations is not None else (s.iterations if warm else s.cold_iterations)
            it = 0
            cache = self._cache
            # warm default solves take the drift Adot v at the previous v_r (see the module docstring)
            v_pred = warm_start.v_r if (warm_start is not None and not exact) else None
            swap = None
            if warm and cache is not None and cache[0] == stance and cache[1] == heading_rad:
                # first step from the previous tick's final evaluation (same q, A)
                F = self._residual(rows, q, cache[2], cache[3], cache[4], h_d, fixed)
                swap_rows(cache[6], q, A, F)
                q = self._step(q, self._newton_step(F, A, cache[5]))
                it = 1
            self._cache = None
            limit_handled = False
            hold_tried = exact or not s.knee_hold_short_of_limit  # the hold needs the default counts
            knees = self._knees
            while True:
                y, pos, rot = self._evaluate(q, stance, heading_rad, A, v_pred)
                F = self._residual(rows, q, y, pos, rot, h_d, fixed)
                swap_rows(swap, q, A, F)
                residual = float(abs(F).max())
                lu = lu_factor(A)
                done = it >= n_max or (not exact and residual < s.tolerance)
                if (
                    done
                    and residual > s.swap_threshold  # converged: nothing to exchange (split would say so)
                    and swap is None
                    and knees is not None
                    and knees.entries(stance)
                    and not limit_handled
                ):
                    if not hold_tried and knees.short_of_limit(stance, q, F, y, h_d):
                        # a fold? more iterations first: a reachable CoM height converges in them
                        hold_tried = True
                        n_max = it + s.cold_iterations
                        continue
                    q_est = None if exact or not s.knee_hold_short_of_limit else kin.state()[0]
                    swap, back = knees.split(stance, q, F, y, h_d, q_est)
                    limit_handled = True
                    if swap is not None:
                        # out of iterations, a knee straight (or short of it, at a fold) and its output
                        # out of reach: trade that output for the knee held there, and iterate on
                        swap_rows(swap, q, A, F)
                        residual = float(abs(F).max())
                        lu = lu_factor(A)
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
            v_r = lu_solve(lu, rhs_v)
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
                swap_rows(swap, q_eps, rows.A_eps, None)
                rhs[:n] = ddh_d
                rhs[:m] -= (rows.A_eps[:m] - A[:m]) @ v_r / eps
            if swap is not None:
                for sp in swap:
                    rhs[sp[0]] = 0.0
            a_r = lu_solve(lu, rhs)
            if not all_finite(q, v_r, a_r):
                raise FloatingPointError("non-finite IK result")
        except (np.linalg.LinAlgError, FloatingPointError, ValueError) as exc:
            if isinstance(exc, InputError):
                raise
            return self._failed(kin)
        res = IKResult(
            q_r=q, v_r=v_r, a_r=a_r, iterations=it, residual=residual, ok=True, knee_at_limit=swap is not None
        )
        self._prev, self._prev_stance = res, stance
        self._cache, self.lu = cache, lu
        return res

    def _failed(self, kin: RobotKinematics) -> IKResult:
        """The previous reference (or the estimate of ``kin``) with zero rates, flagged ``ok=False``."""
        prev = self._prev
        q_r = prev.q_r.copy() if prev is not None else kin.state()[0].copy()
        nv = self.model.nv
        self._prev = None
        self._cache = None
        self.lu = None
        return IKResult(q_r, np.zeros(nv), np.zeros(nv), 0, float("nan"), ok=False)
