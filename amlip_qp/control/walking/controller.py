"""The walking controller: estimator, step clock, gait logic, ALIP planner, references, tracker, saturation.

One :meth:`WalkingController.step` per control tick (2 kHz by default):

0. the base-state estimator (:mod:`amlip_qp.estimation`; by default the
   simulator's truth, passed through untouched) fills the base pose and
   velocity; a non-finite or diverged estimate switches to the damped safe
   mode for the tick (no planner, no tracker: ``tau = -kd * joint velocity``);
1. the estimator updates the Pinocchio kinematics once at the measured state;
2. the gait logic decides whether the swing foot touched down (from the step
   clock's phase); at touchdown the planner starts a new step, from the
   measured outputs, with the other stance leg on the step clock it shares
   with the controller;
3. the estimator computes ``p_st``, ``L`` (Kalman-filtered) and ``v_z``;
   off flat ground the :class:`~amlip_qp.control.walking.ground.GroundPredictor`
   gives the ground at the swing target (blind: from the footholds;
   terrain-aware: from the terrain's height function);
4. the planner (the code-generated kernels on the fast path) predicts ``L(T-)``,
   places the foot (the one-step law, or with ``planner="mpc"`` the step-timing
   MPC, which also plans the step's duration on the step clock) and evaluates ``h_d(s)`` and its derivatives (off flat
   ground with the height difference to the next contact, the swing foot's
   start and end heights and pitches, and a swing foot that keeps descending
   after ``T`` until it touches down);
5. the tracker (PBC or QP, same interface) computes joint torques, and
   returns the outputs ``h_0`` it evaluated (the controller evaluates them
   itself for a tracker that does not);
6. the torques are checked (never NaN: a damped fallback replaces them and the
   event is counted) and saturated at the motor limits.

The controller never touches MuJoCo: it sees :class:`~amlip_qp.messages.Measurement` only.
Data flows one way: the kinematics object is updated once per tick and only read
afterwards (its output map fixed when it was made); the tracker returns what it computed.
What it reports (:class:`StepRecord`, :class:`TickInfo`) is in :mod:`~amlip_qp.control.walking.records`.
"""

from __future__ import annotations

import math
import time
import warnings
from typing import TYPE_CHECKING

import numpy as np

from amlip_qp.alip import other_side
from amlip_qp.alip.clock import StepClock
from amlip_qp.alip.command_shaping import CommandShaper
from amlip_qp.alip.heading import world_to_heading
from amlip_qp.alip.mpc_planner import MPCSettings
from amlip_qp.alip.planner import Planner
from amlip_qp.control.tracker import Tracker, TrackingTarget
from amlip_qp.control.walking.estimator import Estimate, Estimator, planner_state
from amlip_qp.control.walking.gait import GaitLogic, GaitParams, swing_contact_weight
from amlip_qp.control.walking.ground import GroundPredictor, HeightFunction
from amlip_qp.control.walking.planners import check_planner, make_planner, plan_tick
from amlip_qp.control.walking.records import StepRecord, TickInfo, nan_tick_signals
from amlip_qp.control.walking.speed import CorrectedCommand, SpeedCorrection, SpeedIntegrator
from amlip_qp.control.walking.stage_timer import StageTimer
from amlip_qp.estimation.base_estimator import BaseStateEstimator, TruthBaseEstimator
from amlip_qp.exceptions import InputError
from amlip_qp.messages import Command, Measurement, PlannerOutput
from amlip_qp.profiles import NO_SHAPING, CommandShaping
from amlip_qp.robots.foot_extent import foot_extent_m
from amlip_qp.robots.kinematics import check_stand_output_rank
from amlip_qp.robots.outputs import check_output_map, output_names

if TYPE_CHECKING:  # pragma: no cover - typing only
    from amlip_qp.robots.kinematics import RobotKinematics
    from amlip_qp.robots.robot import Robot


class WalkingController:
    """ALIP walking controller around a :class:`~amlip_qp.control.tracker.Tracker`.

    Args:
        robot: A :class:`~amlip_qp.robots.robot.Robot`.
        tracker: The tracker (``tracker.compute(kinematics, target)`` every tick).
        kinematics: The :class:`~amlip_qp.robots.kinematics.RobotKinematics` the
            controller updates and the tracker reads, with its output map. Default:
            :func:`make_kinematics(robot) <amlip_qp.control.walking.outputs_compiled.make_kinematics>`,
            the generated-C output map (the same outputs as the Python
            :class:`~amlip_qp.robots.outputs.OutputMap` to rounding, about half the time; without
            a compiler the Python map with a warning).
        dt_s: Control period, s.
        planner_backend: ``"c"`` for the code-generated kernels (fast path;
            falls back to CasADi with a warning without a compiler) or ``"numpy"``.
        kalman: Filter ``L`` with the per-plane Kalman filters.
        gait: Touchdown detection settings.
        initial_stance: Stance side of the first step.
        fallback_damping_Nms: Damping of the safe fallback torque, N m s/rad.
        speed_correction: Integral action on the step-to-step velocity error
            (:class:`SpeedCorrection`; ``SpeedCorrection(enabled=False)`` gives
            the paper's controller unchanged).
        command_shaping: Rate limits of the velocity command before the planner
            sees it (:class:`~amlip_qp.alip.command_shaping.CommandShaper`);
            default: the robot's profile (:mod:`amlip_qp.profiles`), no limit
            for a robot without one.
        base_estimator: Where the base pose and velocity come from
            (:func:`~amlip_qp.estimation.base_estimator.make_base_estimator`);
            default: the measurement's own base state (the simulator's truth).
        ground_mode: The ground the steps are planned for
            (:data:`~amlip_qp.control.walking.ground.GROUND_MODES`): ``"flat"``
            (default: the flat-ground controller), ``"blind"`` (felt by the
            footholds) or ``"aware"`` (from ``terrain_height_fn``). Off flat
            ground the swing foot keeps descending after ``T`` until contact
            (the planner's ``late_descent="landing"``) and the QP's stance
            friction cone follows the ground.
        terrain_height_fn: World ``(x, y)`` m -> ground height m, for ``"aware"``
            (default mode then; given with another mode: InputError).
        planner: ``"one-step"`` (default): the one-step deadbeat law
            (:class:`~amlip_qp.alip.planner.Planner`); ``"mpc"``: the step-timing MPC, footholds
            and step durations four steps ahead (:class:`~amlip_qp.alip.mpc_planner.MPCPlanner`,
            docs/ALIP_MPC.md), which plans the step's end on the step clock.
        mpc_settings: The MPC's limits and weights (:class:`~amlip_qp.alip.mpc_planner.MPCSettings`;
            ``planner="mpc"`` only; ``step_time_min_s`` raised to the tracker's ``shortest_step_s``).
        stage_timer: Records each tick's kinematics update and tracker ``compute`` wall times
            (:class:`~amlip_qp.control.walking.stage_timer.StageTimer`); ``None`` (default): no timing.

    Raises:
        InputError: A bad argument (also: ``kinematics``' output map does not evaluate
            ``robot``'s outputs).
        MJCFError: The robot's outputs do not fit its legs
            (:func:`~amlip_qp.robots.outputs.output_names`), or their Jacobian loses rank at the
            stand pose (:func:`~amlip_qp.robots.kinematics.check_stand_output_rank`).
    """

    def __init__(
        self,
        robot: Robot,
        tracker: Tracker,
        kinematics: RobotKinematics | None = None,
        dt_s: float = 0.0005,
        planner_backend: str = "c",
        kalman: bool = True,
        gait: GaitParams | None = None,
        initial_stance: str = "left",
        fallback_damping_Nms: float = 5.0,
        speed_correction: SpeedCorrection | None = None,
        command_shaping: CommandShaping | None = None,
        base_estimator: BaseStateEstimator | None = None,
        ground_mode: str | None = None,
        terrain_height_fn: HeightFunction | None = None,
        planner: str = "one-step",
        mpc_settings: MPCSettings | None = None,
        stage_timer: StageTimer | None = None,
    ):
        check_planner(planner, mpc_settings)
        if initial_stance not in ("left", "right"):
            raise InputError(f"initial_stance must be 'left' or 'right', got {initial_stance!r}")
        if planner_backend not in ("c", "numpy"):
            raise InputError(f"planner_backend must be 'c' or 'numpy', got {planner_backend!r}")
        check_stand_output_rank(robot)  # each output movable on its own at the stand pose
        if kinematics is None:
            from amlip_qp.control.walking.outputs_compiled import make_kinematics

            kinematics = make_kinematics(robot, stacklevel=3)
        else:
            check_output_map(robot, kinematics.output_map)
        self.robot = robot
        self.tracker = tracker
        self.kin = kinematics
        self.dt_s = float(dt_s)
        #: Receives the stage times of each tick, or ``None``.
        self.stage_timer = stage_timer
        self.estimator = Estimator(kinematics, dt_s, kalman=kalman)
        #: The base-state estimator (called first in every :meth:`step`).
        self.base_estimator: BaseStateEstimator = base_estimator or TruthBaseEstimator()
        #: Ticks run in the damped safe mode (a non-finite or diverged base estimate).
        self.safe_mode_ticks = 0
        #: Times the controller entered the safe mode.
        self.estimator_divergences = 0
        self._in_safe_mode = False
        n_joints = len(robot.joint_names)
        self._n_base_q, self._n_base_v = robot.nq - n_joints, robot.nv - n_joints
        self._nan_tick_parts: tuple[Estimate, PlannerOutput, np.ndarray] | None = None
        if ground_mode is None:
            ground_mode = "flat" if terrain_height_fn is None else "aware"
        #: The ground the steps are planned for (flat, blind or terrain-aware).
        self.ground = GroundPredictor(ground_mode, terrain_height_fn, foot_extent_m(robot))
        self.gait = GaitLogic(gait)
        #: Stance side, start and phase of the current step: the one step clock,
        #: held by the planner, which starts its steps.
        self.clock = StepClock()
        descent = "landing" if self.ground.active else None
        shortest = tracker.shortest_step_s  # the MPC plans no step shorter than the tracker follows
        aware = self.ground.mode == "aware"  # nor, terrain-aware, shorter than T
        self.planner: Planner = make_planner(
            planner, output_names(robot), robot.mass_kg, self.clock, planner_backend, descent, mpc_settings, shortest,
            aware=aware,
        )  # fmt: skip
        self.initial_stance = initial_stance
        self._tau_lo = robot.actuated.torque_limit_Nm[:, 0].copy()
        self._tau_hi = robot.actuated.torque_limit_Nm[:, 1].copy()
        self._act_v = robot.actuated.pin_v_idx
        self._tau_shape = (len(self._act_v),)
        self._fallback_kd = float(fallback_damping_Nms)
        self.steps: list[StepRecord] = []
        #: Ticks whose tracker output was replaced by the damped fallback.
        self.fallback_ticks = 0
        #: The rate limiter of the velocity command (the planner sees its output).
        self.shaper = CommandShaper(command_shaping or (robot.profile.shaping if robot.profile else NO_SHAPING))
        self.speed = SpeedIntegrator(speed_correction or SpeedCorrection(), planar=robot.is_planar)
        self._last_plan: PlannerOutput | None = None
        self._L_target_this_step = np.full(2, np.nan)
        #: The command the planner sees: the shaped command plus the integral speed correction.
        self.corrector = CorrectedCommand()
        self._com_step_start = np.zeros(3)
        self._cmd_aimed = np.zeros(2)
        self._cmd_now = np.zeros(2)

    @property
    def speed_correction_mps(self) -> np.ndarray:
        """The integral speed correction now given to the planner, heading frame, m/s (copy)."""
        return self.corrector.correction_mps.copy()

    @property
    def stance(self) -> str | None:
        """Current stance side (``None`` before the first step)."""
        return self.clock.stance

    def reset(self) -> None:
        """Start over (a new run)."""
        self.tracker.reset()
        self.estimator.reset()
        self.planner.reset()
        self.shaper.reset()
        self.steps.clear()
        self.fallback_ticks = 0
        self.ground.reset()
        self.base_estimator.reset()
        self.safe_mode_ticks = 0
        self.estimator_divergences = 0
        self._in_safe_mode = False
        self._last_plan = None
        self._L_target_this_step = np.full(2, np.nan)
        self.speed.reset()
        self.corrector.correction_mps[:] = 0.0
        self._cmd_aimed[:] = 0.0
        self._cmd_now[:] = 0.0

    def _begin_step(self, stance: str, t_s: float) -> None:
        heading = self.planner.heading_next_rad
        h0, _, _ = self.kin.outputs(stance, heading)
        self.planner.start_step(stance, t_s, h0)  # starts the step on self.clock
        self._com_step_start = self.kin.com()

    def _record_step(self, t_s: float, est: Estimate, stance: str, plan: PlannerOutput) -> None:
        """Close the step of ``stance`` that ends at ``t_s`` (s), planned last by ``plan``."""
        t0 = self.clock.t_start_s
        disp = est.com_m - self._com_step_start
        dt = max(t_s - t0, 1e-9)
        v_mean = world_to_heading(disp[:2], plan.heading_rad) / dt
        self.steps.append(
            StepRecord(
                t_start_s=t0,
                t_end_s=t_s,
                stance=stance,
                swing_target_m=plan.swing_target_world_m.copy(),
                swing_actual_m=est.swing_contact_m.copy(),
                L_end_Nms=est.L_meas_Nms[:2].copy(),
                L_target_Nms=self._L_target_this_step.copy(),
                com_vel_end_mps=est.com_vel_mps.copy(),
                heading_rad=plan.heading_rad,
                mean_velocity_heading_mps=v_mean,
                speed_correction_mps=self.corrector.correction_mps.copy(),
            )
        )
        self._L_target_this_step = plan.L_des_Nms.copy()
        self.corrector.correction_mps[:] = self.speed.update(v_mean, self._cmd_aimed)
        # The command in force now is what the next step's foot placement aims at.
        self._cmd_aimed[:] = self._cmd_now

    def step(self, measurement: Measurement, command: Command) -> TickInfo:
        """One control tick: joint torques (actuator order, joint side, N m) and signals."""
        t = float(measurement.t_s)
        if self.ground.mode == "aware":  # the estimator takes a blade's contact against the known ground
            self.base_estimator.set_ground_pitch(self.ground.stance_pitch_rad)
        measurement = self.base_estimator.fill(measurement)
        q, v = measurement.q, measurement.v
        # A finite sum implies finite entries (NaN and inf propagate).
        nq, nv = self._n_base_q, self._n_base_v
        if self.base_estimator.diverged or not math.isfinite(sum(q[:nq].tolist()) + sum(v[:nv].tolist())):
            return self._safe_mode(t, v)
        self._in_safe_mode = False
        command = self.shaper.update(command, t)
        estimator = self.estimator
        timer = self.stage_timer
        t0_ns = time.perf_counter_ns() if timer is not None else 0
        estimator.observe(measurement)
        t1_ns = time.perf_counter_ns() if timer is not None else 0
        kin = self.kin
        touchdown = False
        new_step = False  # a first step or a touchdown: the ground gets a new stance foothold
        clock = self.clock
        stance = clock.stance
        if stance is None:
            stance = self.initial_stance
            self._begin_step(stance, t)
            est = estimator.estimate(stance)
            new_step = True
        else:
            # The estimate for the current stance serves the touchdown test (the
            # contact heights) and, without a touchdown, the planner; at a
            # touchdown it closes the old step and a new one is made about the
            # new stance contact (the filters restart there).
            est = estimator.estimate(stance)
            phase_raw = clock.phase_unclipped(t, clock.step_time_s(command.step_time_s))
            swing = other_side(stance)
            height = float(est.swing_contact_m[2] - est.stance_contact_m[2])
            contact = measurement.foot_contact.get(swing) if measurement.foot_contact else None
            last_plan = self._last_plan
            if last_plan is not None and self.gait.touchdown(phase_raw, contact, height):
                self._record_step(t, est, stance, last_plan)
                stance = swing
                self._begin_step(stance, t)
                touchdown = new_step = True
                est = estimator.estimate(stance, touchdown=True)
        self._cmd_now[0], self._cmd_now[1] = command.vx_mps, command.vy_mps
        command = self.corrector.apply(command)
        v_z = float(est.com_vel_mps[2])
        state = planner_state(stance, est.p_st_m, est.L_Nms, v_z, clock.time_in_step(t), est.com_m)
        ground = self.ground
        t2_ns = time.perf_counter_ns() if timer is not None else 0
        plan = self._last_plan = plan_tick(self.planner, ground, state, command, est, new_step, self._last_plan)
        t3_ns = time.perf_counter_ns() if timer is not None else 0
        target = TrackingTarget(
            stance=stance,
            phase=plan.s,
            heading_rad=plan.heading_rad,
            h_d=plan.h_d,
            dh_d=plan.dh_d,
            ddh_d=plan.ddh_d,
            swing_contact_weight=swing_contact_weight(plan.s),
            stance_ground_pitch_rad=ground.stance_pitch_rad if ground.active else None,
        )
        t4_ns = time.perf_counter_ns() if timer is not None else 0
        result = self.tracker.compute(kin, target)
        if timer is not None:
            timer.record(t1_ns - t0_ns, time.perf_counter_ns() - t4_ns, result.info, t2_ns - t1_ns, t3_ns - t2_ns)
        tau = result.tau_Nm
        ok = result.ok
        # A finite sum implies finite entries; only if it is not (or overflows), look closer.
        if tau.shape != self._tau_shape or (not math.isfinite(sum(tau.tolist())) and not np.isfinite(tau).all()):
            tau = -self._fallback_kd * kin.state()[1][self._act_v]
            ok = False
            self.fallback_ticks += 1
            if self.fallback_ticks == 1:
                warnings.warn(
                    f"tracker {self.tracker.name!r} returned non-finite torques at t={t:.4f} s; "
                    "using the damped fallback (counted in fallback_ticks)",
                    RuntimeWarning,
                    stacklevel=2,
                )
        tau = np.maximum(tau, self._tau_lo)
        np.minimum(tau, self._tau_hi, out=tau)
        # The outputs the tracker evaluated, else (a tracker that returns none) the kinematics' own.
        h = result.outputs[0] if result.outputs is not None else kin.outputs(stance, plan.heading_rad)[0]
        return TickInfo(
            t_s=t,
            stance=stance,
            phase=plan.s,
            estimate=est,
            plan=plan,
            h=h,
            tau_Nm=tau,
            tracker_ok=ok and result.ok,
            touchdown=touchdown,
            info=result.info,
        )

    def _safe_mode(self, t: float, v: np.ndarray) -> TickInfo:
        """The damped safe mode: ``tau = -kd * joint velocity`` from the encoders (zero if those are not finite)."""
        if not self._in_safe_mode:
            self._in_safe_mode = True
            self.estimator_divergences += 1
            if self.estimator_divergences == 1:
                warnings.warn(
                    f"the base-state estimate is non-finite or diverged at t={t:.4f} s; the controller is in its "
                    "damped safe mode (counted in safe_mode_ticks and estimator_divergences)",
                    RuntimeWarning,
                    stacklevel=3,
                )
        self.safe_mode_ticks += 1
        qd = np.asarray(v, dtype=float)[self._act_v]
        tau = -self._fallback_kd * qd if np.isfinite(qd).all() else np.zeros(self._tau_shape)
        tau = np.maximum(tau, self._tau_lo)
        np.minimum(tau, self._tau_hi, out=tau)
        est, plan, h = self._nan_parts()
        stance = self.clock.stance or self.initial_stance
        return TickInfo(
            t_s=t, stance=stance, phase=math.nan, estimate=est, plan=plan, h=h, tau_Nm=tau,
            tracker_ok=False, touchdown=False, info={"safe_mode": True},
        )  # fmt: skip

    def _nan_parts(self) -> tuple[Estimate, PlannerOutput, np.ndarray]:
        """NaN estimate, plan and outputs for the logs of a safe-mode tick (made once)."""
        if self._nan_tick_parts is None:
            self._nan_tick_parts = nan_tick_signals(len(self.planner.output_names))
        return self._nan_tick_parts
