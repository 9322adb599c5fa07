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

Evaluation: at each iterate, Pinocchio updates the IK's own
:class:`~amlip_qp.robots.kinematics.RobotKinematics` (its own Pinocchio data; the light
:meth:`~amlip_qp.robots.kinematics.RobotKinematics.update_positions`, or the kinematics-only
update when the drift is taken there), then one evaluation
(:mod:`~amlip_qp.control.pbc.ik_evaluation`) gives the varying rows of ``A``, the residual
and the drift: by default one call of generated C reading Pinocchio's arrays in place
(:class:`~amlip_qp.control.pbc.ik_compiled.CompiledIKEvaluation`), else Pinocchio's getters
and the output map of the kinematics :meth:`IterativeIK.solve` is given (the Python
reference, :class:`~amlip_qp.control.pbc.ik_evaluation.PythonIKEvaluation`; also for an
output map other than the robot's standard ``h_0``). The generated evaluation computes the
standard outputs itself, as the generated output map does: on the walking controller's
kinematics (that map, by default) the two give the same bits; on kinematics with the Python
:class:`~amlip_qp.robots.outputs.OutputMap`, the same numbers to rounding.

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
import warnings
from typing import TYPE_CHECKING

import numpy as np

from amlip_qp.codegen.runtime import CodegenFallbackWarning
from amlip_qp.control.pbc.ik_compiled import CompiledIKEvaluation
from amlip_qp.control.pbc.ik_equations import IKEquations
from amlip_qp.control.pbc.ik_evaluation import PythonIKEvaluation
from amlip_qp.control.pbc.ik_newton import all_finite, lu_factor, lu_solve, newton_step
from amlip_qp.control.pbc.ik_settings import IKResult, IKSettings
from amlip_qp.control.pbc.knee_limits import KneeLimits, swap_rows
from amlip_qp.exceptions import CompilerUnavailableError, InputError
from amlip_qp.robots.outputs import computes_standard_outputs

if TYPE_CHECKING:  # pragma: no cover - typing only
    from amlip_qp.robots.kinematics import RobotKinematics
    from amlip_qp.robots.robot import Robot


class IterativeIK:
    """Damped-Newton IK from ``h_d`` to joint references (formulation in the module docstring).

    Args:
        robot: The :class:`~amlip_qp.robots.robot.Robot`.
        settings: Iteration settings.
        compiled: Evaluate with the generated C of
            :class:`~amlip_qp.control.pbc.ik_compiled.CompiledIKEvaluation` (the Python
            reference's numbers; see the module doc): ``None`` (default) when a C compiler is
            found, else the Python reference with a
            :class:`~amlip_qp.codegen.runtime.CodegenFallbackWarning`; ``True`` requires it
            (:class:`~amlip_qp.exceptions.CompilerUnavailableError` without a compiler);
            ``False``: the Python reference. Either way, kinematics with an output map other than
            the robot's standard ``h_0`` are evaluated in Python.

    Attributes:
        kin: The IK's own :class:`~amlip_qp.robots.kinematics.RobotKinematics`
            (light position updates at the iterates), on the output map of the
            kinematics last given to :meth:`solve` (the Python
            :class:`~amlip_qp.robots.outputs.OutputMap` before any).
        size: Number of outputs.

    Raises:
        InputError: ``compiled`` is not ``None``, ``True`` or ``False``.
        MJCFError: The model does not give a square system
            (:class:`~amlip_qp.control.pbc.ik_equations.IKEquations`).
    """

    def __init__(self, robot: Robot, settings: IKSettings | None = None, compiled: bool | None = None):
        import pinocchio as pin

        if not any(compiled is allowed for allowed in (None, True, False)):  # not 0, 1 or 'yes'
            raise InputError(f"compiled must be None, True or False, got {compiled!r}")

        from amlip_qp.robots.kinematics import RobotKinematics
        from amlip_qp.robots.outputs import OutputMap

        self._pin = pin
        self.robot = robot
        self.settings = settings or IKSettings()
        self.model = m = robot.pin_model
        self.kin = RobotKinematics(robot)
        output_map = OutputMap(robot)
        self.size = output_map.size
        nv = m.nv
        #: The equations of the system (held coordinates and their rows per stance).
        self.equations = eq = IKEquations(robot, self.size)
        self._rows = eq.rows
        self._python = PythonIKEvaluation(eq, self.size)
        self._compiled: CompiledIKEvaluation | None = None
        if compiled is None or compiled:
            try:
                self._compiled = CompiledIKEvaluation(eq, output_map)
            except CompilerUnavailableError as exc:
                if compiled:
                    raise
                warnings.warn(
                    f"IterativeIK: no compiled evaluation ({exc}); using the Python one (same numbers, slower)",
                    CodegenFallbackWarning,
                    stacklevel=2,
                )
        self._eval: CompiledIKEvaluation | PythonIKEvaluation = self._compiled or self._python
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
    def evaluation_backend(self) -> str:
        """Who evaluates the system: ``"c-in-place"``
        (:class:`~amlip_qp.control.pbc.ik_compiled.CompiledIKEvaluation`) or ``"python"``
        (:class:`~amlip_qp.control.pbc.ik_evaluation.PythonIKEvaluation`; also for an output map
        other than the robot's standard ``h_0``)."""
        return self._eval.backend

    @property
    def evaluation(self) -> CompiledIKEvaluation | PythonIKEvaluation:
        """The evaluation in use (:attr:`evaluation_backend`); its ``evaluate`` updates the IK's
        own kinematics :attr:`kin`."""
        return self._eval

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
        standard = computes_standard_outputs(output_map)
        self._eval = self._compiled if (self._compiled is not None and standard) else self._python

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
        ev = self._eval
        kin_ik = self.kin
        try:
            fixed = self.equations.held_quantities(kin, stance)
            if held_springs is not None:
                ns = len(self.equations.held_springs)
                fixed["lin"][len(fixed["lin"]) - ns :] = held_springs
            ev.set_targets(stance, h_d, fixed)
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
                F = ev.kept_residual(stance, q)
                swap_rows(cache[3], q, A, F)
                q = self._step(q, self._newton_step(F, A, cache[2]))
                it = 1
            self._cache = None
            limit_handled = False
            hold_tried = exact or not s.knee_hold_short_of_limit  # the hold needs the default counts
            knees = self._knees
            while True:
                F = ev.evaluate(kin_ik, stance, q, heading_rad, v_pred)
                y = ev.y
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
            cache = (stance, heading_rad, lu, swap)
            m = rows.n_var
            rhs = np.zeros(self.model.nv)
            if v_pred is not None:
                drift = ev.drift(kin_ik, stance, heading_rad)
                np.subtract(ddh_d, drift[:n], out=rhs[:n])
                rhs[n:m] = -drift[n:m]
            else:
                # exact: finite difference of A along v_r
                eps = s.fd_step_s
                q_eps = pin.integrate(self.model, q, eps * v_r)
                ev.evaluate(kin_ik, stance, q_eps, heading_rad, eps=True)
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
        ev.keep(stance)
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
