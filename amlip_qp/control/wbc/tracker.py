"""The task-space whole-body QP tracker.

Every tick: build the QP of :mod:`amlip_qp.control.wbc.builder` for the
current state and references, solve it with ONE persistent solver (the
profile's: the hot-started :class:`~amlip_qp.qp.daqp_solver.DAQPSolver` or the
warm-started :class:`~amlip_qp.qp.solver.ProxQPSolver`), check the status, and recover the
joint torques from the actuated rows of the dynamics.

While the swing foot is in the air (force ramp ``w = 0``) its force
variables are pinned to zero and its friction rows are lifted; the tracker
then solves the problem without them (``airborne_reduction``, on by default:
the same optimum, a smaller problem) as a second persistent problem shape of
the same solver; both stay warm- or hot-started. With the in-place assembly
that problem has its own buffers, which the generated C writes with the same
entries as the full problem's leading block
(:attr:`InPlaceBuild.airborne_problem
<amlip_qp.control.wbc.compiled_in_place.InPlaceBuild.airborne_problem>`);
the other builds solve the leading block's views
(:meth:`QPProblem.leading <amlip_qp.qp.problem.QPProblem.leading>`).
``airborne_reduction=False`` solves the full problem in every tick (the same
walks to rounding, about 1.5x the solve time with DAQP on Cassie; docs/TUNING.md).

Infeasible ticks get a second chance without the torque-limit rows (counted
in :attr:`QPTracker.relaxed_solves`; the controller saturates the torques).
Safe fallback: when the problem cannot be built or solved (non-finite data,
infeasible, iteration cap) the tracker returns the previous tick's good
torques decayed by ``fallback_decay`` per failed tick plus joint damping
``-fallback_damping_Nms * v_a`` (a damped hold of the current posture), with
``ok=False`` and the reason in ``fallback``; the count is in
:attr:`QPTracker.fallbacks` and ``info["fallbacks"]``. It never returns NaN.
"""

from __future__ import annotations

import math
import time
import warnings
from typing import TYPE_CHECKING

import numpy as np

from amlip_qp.codegen.daqp_step import load_daqp_step
from amlip_qp.codegen.runtime import CodegenFallbackWarning
from amlip_qp.control.tracker import Tracker
from amlip_qp.control.wbc.builder import WholeBodyQP
from amlip_qp.control.wbc.compiled import CompiledBuild
from amlip_qp.control.wbc.compiled_in_place import InPlaceBuild, airborne_dims
from amlip_qp.control.wbc.config import QP_SOLVERS, QPConfig
from amlip_qp.control.wbc.constraints import FrictionPyramid
from amlip_qp.exceptions import AmlipError, CompilerUnavailableError, InputError, InvalidQPError, QPError
from amlip_qp.messages import TrackerResult
from amlip_qp.qp.daqp_solver import DAQPSolver
from amlip_qp.qp.problem import QPProblem
from amlip_qp.qp.solver import ProxQPSolver, QPSolution

if TYPE_CHECKING:
    from amlip_qp.control.tracker import TrackingTarget
    from amlip_qp.robots.kinematics import RobotKinematics
    from amlip_qp.robots.robot import Robot


class QPTracker(Tracker):
    """Whole-body QP tracker (one persistent QP solver, warm-started; a problem shape more with ``airborne_reduction``).

    Args:
        robot: The robot.
        config: The :class:`~amlip_qp.control.wbc.config.QPConfig` (default: the robot's profile's).
        eps_abs: ProxQP absolute tolerance on the primal and dual residuals
            (N, N m, m/s^2 in the constraint rows); measured: docs/TUNING.md.
        max_iter: ProxQP iteration cap per tick.
        warm_start: Warm-start from the previous solution (default) or re-initialise every tick.
        record: Keep a copy of every solved problem in :attr:`recorded` (bench, tests).
        fallback_decay: Factor applied to the last good torques per failed tick (0..1).
        fallback_damping_Nms: Joint damping of the fallback, N m s/rad.
        compiled_build: Assemble the QP with generated C
            (:mod:`amlip_qp.control.wbc.compiled_in_place` by default, or
            :mod:`amlip_qp.control.wbc.compiled`, see ``in_place_assembly``; the same problem to rounding,
            about 3x less time; compiled once per robot and config into the
            codegen cache, ~7 s for Cassie). ``None`` (default): when a C
            compiler is available, else the Python
            :meth:`~amlip_qp.control.wbc.builder.WholeBodyQP.build` with one
            warning; ``True``: required (raises without a compiler);
            ``False``: the Python build.
        airborne_reduction: While the swing foot's force ramp is 0, solve the problem without
            its force variables and friction rows (default; the same optimum; with DAQP on Cassie
            about 0.65× of the full problem's solve time). ``False``: the full problem every tick.
        qp_solver: ``None`` (default): the config's
            :attr:`~amlip_qp.control.wbc.config.QPConfig.qp_solver` (``"proxqp"``
            unless the profile's ``[trackers.qp]`` names another); ``"proxqp"``
            (:class:`~amlip_qp.qp.solver.ProxQPSolver`,
            ``eps_abs`` and ``max_iter`` its settings) or ``"daqp"``
            (:class:`~amlip_qp.qp.daqp_solver.DAQPSolver`, a dual active-set
            method, hot-started from the last working set; ``max_iter`` its
            iteration cap, ``eps_abs`` unused). Both solve the same problem;
            their solutions differ by the solvers' tolerances, so the walks
            differ a little (docs/BENCH_QP.md).
        in_place_assembly: Assemble with the generated C of
            :mod:`amlip_qp.control.wbc.compiled_in_place`, which reads
            Pinocchio's arrays in place (the same problem as the other
            builds to rounding; the controller's tick about a quarter shorter
            than with :mod:`~amlip_qp.control.wbc.compiled`, which gathers
            its inputs in Python). ``None`` (default) or ``True``: whenever
            the compiled build is used (``True`` with
            ``compiled_build=False`` is an :class:`InputError`); ``False``:
            the compiled build that gathers its inputs
            (``build_backend == "c"``).

    Attributes:
        last_problem: The last built :class:`QPProblem` (the builder's live
            buffers: copy it to keep it).
        last_solution: The last primal solution, or ``None``.
        recorded: ``(problem copy, solution x)`` pairs when ``record`` is on.
        fallbacks: Number of ticks that used the fallback.
        cold_retries: Ticks whose warm-started solve failed and was retried
            from scratch (once) before any fallback.
        build_backend: ``"c-in-place"`` (the default with a C compiler),
            ``"c"`` (``in_place_assembly=False``) or ``"python"``.
        build_problem: The assembly in use, ``(kin, target) -> QPProblem``
            (the builder's live arrays).
    """

    name = "qp"

    def __init__(
        self,
        robot: Robot,
        config: QPConfig | None = None,
        eps_abs: float = 1e-3,
        max_iter: int = 200,
        warm_start: bool = True,
        record: bool = False,
        fallback_decay: float = 0.9,
        fallback_damping_Nms: float = 5.0,
        compiled_build: bool | None = None,
        airborne_reduction: bool = True,
        in_place_assembly: bool | None = None,
        qp_solver: str | None = None,
    ):
        if not 0.0 <= fallback_decay <= 1.0:
            raise InputError(f"fallback_decay must be in [0, 1], got {fallback_decay!r}")
        if not (fallback_damping_Nms >= 0.0 and math.isfinite(fallback_damping_Nms)):
            raise InputError(f"fallback_damping_Nms must be finite and >= 0, got {fallback_damping_Nms!r}")
        if not (eps_abs > 0.0 and math.isfinite(eps_abs)):
            raise InputError(f"eps_abs must be a positive tolerance, got {eps_abs!r}")
        if compiled_build not in (None, True, False):
            raise InputError(f"compiled_build must be None, True or False, got {compiled_build!r}")
        if airborne_reduction not in (True, False):
            raise InputError(f"airborne_reduction must be True or False, got {airborne_reduction!r}")
        python_build = compiled_build is not None and not compiled_build
        if in_place_assembly not in (None, True, False) or (in_place_assembly and python_build):
            raise InputError(
                "in_place_assembly must be None, True or False (True needs the compiled build), "
                f"got {in_place_assembly!r} with compiled_build={compiled_build!r}"
            )
        if int(max_iter) < 1:
            raise InputError(f"max_iter must be >= 1, got {max_iter!r}")
        if qp_solver is not None and qp_solver not in QP_SOLVERS:
            raise InputError(f"qp_solver must be one of {', '.join(QP_SOLVERS)}, got {qp_solver!r}")
        self.robot = robot
        self.builder = WholeBodyQP(robot, config)
        self._n_outputs = self.builder.output_task.size
        self.build_problem = self.builder.build
        self.build_backend = "python"
        self._in_place: InPlaceBuild | None = None  # its outputs go into the result
        # The airborne swing foot's variables and friction rows trail the problem's (the layout and the
        # constraint order put them last): the problem without them is a leading block.
        dims = airborne_dims(self.builder)
        #: Whether airborne ticks solve the problem without the swing foot (``airborne_reduction`` and a
        #: layout that allows it): the in-place assembly's own airborne problem, else the leading block.
        self.airborne_reduction = bool(airborne_reduction) and dims is not None
        if compiled_build is None or compiled_build:
            try:
                if in_place_assembly is None or in_place_assembly:
                    self._in_place = InPlaceBuild(self.builder, airborne=self.airborne_reduction)
                    self.build_problem = self._in_place.build
                    self.build_backend = "c-in-place"
                else:
                    self.build_problem = CompiledBuild(self.builder).build
                    self.build_backend = "c"
            except CompilerUnavailableError as exc:
                if compiled_build:
                    raise
                warnings.warn(
                    f"QPTracker: no compiled QP assembly ({exc}); using the Python build (same problem, slower)",
                    CodegenFallbackWarning,
                    stacklevel=2,
                )
        self.config = self.builder.config
        if qp_solver is None:
            qp_solver = self.config.qp_solver
        self.qp_solver = qp_solver
        self.solver: ProxQPSolver | DAQPSolver
        if qp_solver == "daqp":
            self.solver = DAQPSolver(warm_start=warm_start, iter_limit=int(max_iter), fast_step=load_daqp_step())
        else:
            self.solver = ProxQPSolver(
                eps_abs=eps_abs,
                max_iter=max_iter,
                warm_start=warm_start,
                eps_primal_inf=1e-9,
                mu_eq=1e-4,
                mu_in=1e-3,
                update_preconditioner=False,
            )
        self.record = bool(record)
        self.fallback_decay = float(fallback_decay)
        self.fallback_kd = float(fallback_damping_Nms)
        self._act_v = np.asarray(robot.actuated.pin_v_idx, dtype=int)
        self._tau_lim = np.asarray(robot.actuated.torque_limit_Nm, dtype=float)
        self.recorded: list[tuple[QPProblem, np.ndarray]] = []
        self.last_problem: QPProblem | None = None
        self.last_solution: np.ndarray | None = None
        self.fallbacks = 0
        #: Ticks whose warm-started solve failed and was retried cold.
        self.cold_retries = 0
        #: Ticks solved only after dropping the torque-limit rows (then saturated by the controller).
        self.relaxed_solves = 0
        self._tau_prev = np.zeros(len(self._act_v))
        self._fail_streak = 0
        friction = self.builder.constraint("friction")
        assert isinstance(friction, FrictionPyramid)
        self._friction = friction
        # (ground pitch, heading) rad the stance pyramid is turned to; None: about the world's vertical
        self._friction_ground: tuple[float, float] | None = None
        self._airborne_dims = dims
        self._airborne: tuple[QPProblem, QPProblem] | None = None  # (full problem, its leading block of views)

    def _orient_friction(self, target: TrackingTarget) -> None:
        """Turn the stance friction pyramid to the target's stance ground (only when that changes)."""
        pitch = target.stance_ground_pitch_rad
        if pitch is None:
            if self._friction_ground is not None:
                self._friction.initialize(self.builder.problem)
                self._friction_ground = None
                self._constant_rows_changed()
            return
        key = (pitch, target.heading_rad)
        if key != self._friction_ground:
            self._friction.tilt_stance_rows(self.builder.problem, pitch, target.heading_rad)
            self._friction_ground = key
            self._constant_rows_changed()

    def reset(self) -> None:
        """New run: forget the warm start, the last torques and the counters."""
        self.solver.reset()
        self.builder.reset()
        self.recorded.clear()
        self.last_problem = None
        self.last_solution = None
        self.fallbacks = 0
        self.cold_retries = 0
        self.relaxed_solves = 0
        self._tau_prev[:] = 0.0
        self._fail_streak = 0
        if self._friction_ground is not None:
            self._friction.initialize(self.builder.problem)
            self._friction_ground = None
            self._constant_rows_changed()

    def _constant_rows_changed(self) -> None:
        """The full problem's constant rows changed: the in-place assembly's airborne problem copies them."""
        if self._in_place is not None:
            self._in_place.copy_constant_rows()

    def _fallback(self, kin: RobotKinematics, reason: str, info: dict, outputs: tuple | None = None) -> TrackerResult:
        self.fallbacks += 1
        self._fail_streak += 1
        v_a = kin.v[self._act_v] if kin.v is not None else np.zeros_like(self._tau_prev)
        v_a = np.where(np.isfinite(v_a), v_a, 0.0)
        tau = self.fallback_decay**self._fail_streak * self._tau_prev - self.fallback_kd * v_a
        tau = np.clip(np.nan_to_num(tau, nan=0.0, posinf=0.0, neginf=0.0), self._tau_lim[:, 0], self._tau_lim[:, 1])
        info.update(fallbacks=self.fallbacks, qp_ok=0.0)
        return TrackerResult(tau_Nm=tau, ok=False, fallback=reason, info=info, outputs=outputs)

    def compute(self, kin: RobotKinematics, target: TrackingTarget) -> TrackerResult:
        """Torques (N m, actuator order) from the QP; the fallback on failure (never NaN). With the
        in-place assembly the result carries the outputs ``h_0`` it evaluated (``outputs``, also in a
        fallback after the build); otherwise ``outputs`` is ``None``. ``kin`` is only read."""
        info: dict = {}
        if target.stance not in self.robot.foot_sides:
            raise InputError(f"target.stance must be one of {tuple(self.robot.foot_sides)}, got {target.stance!r}")
        h_d = target.h_d
        if (h_d.shape if isinstance(h_d, np.ndarray) else np.shape(h_d)) != (self._n_outputs,):
            raise InputError(f"target.h_d must have shape ({self._n_outputs},), got {np.shape(h_d)}")
        t0 = time.perf_counter_ns()
        self._orient_friction(target)
        outputs = None  # the output map h_0 of the in-place assembly, for the result
        try:
            problem = self.build_problem(kin, target)
            if self._in_place is not None and self.build_problem == self._in_place.build:
                outputs = self._in_place.outputs
            self.last_problem = problem
        except QPError as exc:
            return self._fallback(kin, f"invalid problem: {exc}", info, outputs)
        except (AmlipError, ValueError, ArithmeticError, np.linalg.LinAlgError) as exc:
            # ArithmeticError: e.g. a degenerate (vertical) blade in a fall.
            return self._fallback(kin, f"cannot build the QP: {exc}", info)
        t1 = time.perf_counter_ns()
        try:
            n_init = self.solver.n_init
            try:
                sol = self._solve(problem)  # validates the problem first (InvalidQPError)
            except QPError as exc:
                # A warm start from a far-away iterate can stall: retry once from scratch (the solver
                # re-initialises after a failure); not an invalid problem, nor a fresh start's failure.
                if isinstance(exc, InvalidQPError) or self.solver.n_init != n_init:
                    raise
                self.cold_retries += 1
                sol = self._solve(problem)
        except InvalidQPError as exc:
            return self._fallback(kin, f"invalid problem: {exc}", info, outputs)
        except QPError as exc:
            relaxed = self._solve_relaxed(problem)
            if relaxed is not None:
                return self._finish(kin, problem, relaxed, info, (t0, t1), outputs, relaxed=True)
            if self.record:
                self.recorded.append((problem.copy(), np.full(problem.n, np.nan)))
            return self._fallback(kin, f"solver: {exc.status or exc}", info, outputs)
        return self._finish(kin, problem, sol, info, (t0, t1), outputs, relaxed=False)

    def _solve(self, problem: QPProblem) -> QPSolution:
        """Validate (:class:`InvalidQPError`; the solver does, in its compiled call if any) and solve
        ``problem``; with :attr:`airborne_reduction`, while the swing foot is airborne, the problem
        without the swing forces: the in-place assembly's airborne problem (which :meth:`build_problem`
        then returns) or the full problem's leading block. The solution has the full problem's size."""
        if problem.n != self.builder.layout.n:  # the in-place assembly's airborne problem
            return self._full_size(self.solver.solve(problem, check=True))
        if not (self.airborne_reduction and self.builder.inputs.swing_force_weight == 0.0):
            return self.solver.solve(problem, check=True)
        problem.validate()  # the full problem, as the other paths validate what they solve
        pair = self._airborne
        if pair is None or pair[0] is not problem:
            # Views of the builder's live arrays: made once, valid for every later build.
            assert self._airborne_dims is not None
            pair = self._airborne = (problem, problem.leading(*self._airborne_dims))
        return self._full_size(self.solver.solve(pair[1]))

    def _full_size(self, sol: QPSolution) -> QPSolution:
        """``sol`` of a problem without the airborne swing foot's forces, with those forces
        (fixed at zero by their bounds) appended."""
        n = self.builder.layout.n
        if sol.x.shape[0] != n:
            x = np.zeros(n)
            x[: sol.x.shape[0]] = sol.x
            sol.x = x
        return sol

    def _solve_relaxed(self, problem: QPProblem) -> QPSolution | None:
        """Second chance after an infeasible tick: drop the torque-limit rows
        (the controller saturates the torques anyway); ``None`` if that fails too."""
        relaxed = problem.copy()
        rows = dict(relaxed.in_rows)["torque"]
        relaxed.l[rows] = -np.inf
        relaxed.u[rows] = np.inf
        try:
            sol = self._full_size(self.solver.solve(relaxed))
        except QPError:
            return None
        self.relaxed_solves += 1
        return sol

    def _finish(
        self,
        kin: RobotKinematics,
        problem: QPProblem,
        sol: QPSolution,
        info: dict,
        times_ns: tuple[int, int],
        outputs: tuple | None,
        relaxed: bool,
    ) -> TrackerResult:
        # The solver rejects a non-finite x, so the forces are finite; the torques
        # are checked before any state is updated.
        tau = self.builder.torques(sol.x)
        if not math.isfinite(sum(tau.tolist())):  # Python floats: cheaper than a numpy reduction here
            return self._fallback(kin, "non-finite torques", info, outputs)
        self.last_solution = sol.x
        if self.record:  # the full problem, also when its airborne block was solved (the same optimum)
            if problem.n != sol.x.shape[0] and self._in_place is not None:
                problem = self._in_place.full_problem()
            self.recorded.append((problem.copy(), sol.x.copy()))
        self._tau_prev[:] = tau
        self._fail_streak = 0
        stance_fz, swing_fz = self.builder.normal_force_totals(sol.x)
        info.update(
            qp_ok=1.0,
            build_us=(times_ns[1] - times_ns[0]) * 1e-3,
            solve_us=sol.solve_time_us,
            iterations=float(sol.iterations),
            fallbacks=self.fallbacks,
            cold_retries=self.cold_retries,
            relaxed_solves=self.relaxed_solves,
            relaxed=float(relaxed),
            stance_fz_N=stance_fz,
            swing_fz_N=swing_fz,
            swing_force_weight=self.builder.inputs.swing_force_weight,
        )
        return TrackerResult(tau_Nm=tau, ok=True, fallback=None, info=info, outputs=outputs)
