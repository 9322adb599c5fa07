"""The walking controller: estimator, gait logic, ALIP planner, references, tracker, saturation.

One :meth:`WalkingController.step` per control tick (2 kHz by default):

1. the estimator updates the Pinocchio kinematics once at the measured state;
2. the gait logic decides whether the swing foot touched down; at touchdown the
   stance switches and the planner starts a new step from the measured outputs;
3. the estimator computes ``p_st``, ``L`` (Kalman-filtered) and ``v_z``;
4. the planner (the code-generated kernels on the fast path) predicts ``L(T-)``,
   places the foot and evaluates ``h_d(s)`` and its derivatives;
5. the tracker (PBC or QP, same interface) computes joint torques;
6. the torques are checked (never NaN: a damped fallback replaces them and the
   event is counted) and saturated at the motor limits.

The controller never touches MuJoCo: it sees :class:`~amlip_qp.control.estimator.Measurement` only.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field

import numpy as np

from amlip_qp.alip.planner import Command, Planner, PlannerOutput, StateEstimate
from amlip_qp.control.estimator import Estimate, Estimator, Measurement
from amlip_qp.control.gait import GaitLogic, GaitParams
from amlip_qp.control.tracker import Tracker, TrackingTarget
from amlip_qp.exceptions import InputError


@dataclass
class StepRecord:
    """What happened in one completed step (recorded at its touchdown).

    Attributes:
        t_start_s: When the step began, s.
        t_end_s: Touchdown time ending it, s.
        stance: Its stance side.
        swing_target_m: The planner's last swing-contact target (world), m.
        swing_actual_m: Where the swing contact was at touchdown (world), m.
        L_end_Nms: ``(L_x, L_y)`` about the stance contact at the end of the step (measured), kg m^2/s.
        L_target_Nms: The ``L_des`` the planner aimed at for the end of this
            step (chosen during the previous step), or NaN for the first step.
        com_vel_end_mps: CoM velocity at the end of the step, m/s.
        heading_rad: The step's heading ``D_k``, rad.
    """

    t_start_s: float
    t_end_s: float
    stance: str
    swing_target_m: np.ndarray
    swing_actual_m: np.ndarray
    L_end_Nms: np.ndarray
    L_target_Nms: np.ndarray
    com_vel_end_mps: np.ndarray
    heading_rad: float


@dataclass
class TickInfo:
    """This tick's signals, for logging (all references, not copies: copy to keep)."""

    t_s: float
    stance: str
    phase: float
    estimate: Estimate
    plan: PlannerOutput
    h: np.ndarray
    tau_Nm: np.ndarray
    tracker_ok: bool
    touchdown: bool
    info: dict = field(default_factory=dict)


class WalkingController:
    """ALIP walking controller around a :class:`~amlip_qp.control.tracker.Tracker`.

    Args:
        robot: A :class:`~amlip_qp.robots.robot.Robot`.
        tracker: The tracker (shares ``kinematics``).
        kinematics: The :class:`~amlip_qp.robots.kinematics.RobotKinematics` the tracker uses.
        dt_s: Control period, s.
        planner_backend: ``"c"`` for the code-generated kernels (fast path;
            falls back to CasADi with a warning without a compiler) or ``"numpy"``.
        kalman: Filter ``L`` with the per-plane Kalman filters.
        gait: Touchdown detection settings.
        initial_stance: Stance side of the first step.
        fallback_damping_Nms: Damping of the safe fallback torque, N m s/rad.
    """

    def __init__(
        self,
        robot,
        tracker: Tracker,
        kinematics,
        dt_s: float = 0.0005,
        planner_backend: str = "c",
        kalman: bool = True,
        gait: GaitParams | None = None,
        initial_stance: str = "left",
        fallback_damping_Nms: float = 5.0,
    ):
        if initial_stance not in ("left", "right"):
            raise InputError(f"initial_stance must be 'left' or 'right', got {initial_stance!r}")
        if planner_backend not in ("c", "numpy"):
            raise InputError(f"planner_backend must be 'c' or 'numpy', got {planner_backend!r}")
        self.robot = robot
        self.tracker = tracker
        self.kin = kinematics
        self.dt_s = float(dt_s)
        self.estimator = Estimator(kinematics, dt_s, kalman=kalman)
        self.gait = GaitLogic(gait)
        plan_fn = reference_fn = None
        if planner_backend == "c":
            from amlip_qp.codegen import load_kernels

            kernels = load_kernels()
            plan_fn, reference_fn = kernels.alip_plan, kernels.swing_reference
        planner_robot = "rabbit" if robot.is_planar else "cassie"
        self.planner = Planner(planner_robot, robot.mass_kg, plan_fn=plan_fn, reference_fn=reference_fn)
        self.initial_stance = initial_stance
        self._tau_lim = robot.actuated.torque_limit_Nm
        self._act_v = robot.actuated.pin_v_idx
        self._fallback_kd = float(fallback_damping_Nms)
        self.steps: list[StepRecord] = []
        #: Ticks whose tracker output was replaced by the damped fallback.
        self.fallback_ticks = 0
        self._stance: str | None = None
        self._last_plan: PlannerOutput | None = None
        self._L_target_this_step = np.full(2, np.nan)

    @property
    def stance(self) -> str | None:
        """Current stance side (``None`` before the first step)."""
        return self._stance

    def reset(self) -> None:
        """Start over (a new run)."""
        self.tracker.reset()
        self.estimator.reset()
        self.steps.clear()
        self.fallback_ticks = 0
        self._stance = None
        self._last_plan = None
        self._L_target_this_step = np.full(2, np.nan)

    def _begin_step(self, stance: str, t_s: float) -> None:
        heading = self.planner.heading_next_rad
        h0, _, _ = self.kin.outputs(stance, heading)
        self.planner.start_step(stance, t_s, h0)
        self._stance = stance

    def _record_step(self, t_s: float, est: Estimate) -> None:
        plan = self._last_plan
        self.steps.append(
            StepRecord(
                t_start_s=self.planner.t_step_start_s,
                t_end_s=t_s,
                stance=self._stance,
                swing_target_m=plan.swing_target_world_m.copy(),
                swing_actual_m=est.swing_contact_m.copy(),
                L_end_Nms=est.L_meas_Nms[:2].copy(),
                L_target_Nms=self._L_target_this_step.copy(),
                com_vel_end_mps=est.com_vel_mps.copy(),
                heading_rad=plan.heading_rad,
            )
        )
        self._L_target_this_step = plan.L_des_Nms.copy()

    def step(self, measurement: Measurement, command: Command) -> TickInfo:
        """One control tick: joint torques (actuator order, joint side, N m) and signals."""
        t = float(measurement.t_s)
        self.estimator.observe(measurement)
        kin = self.kin
        touchdown = False
        if self._stance is None:
            self._begin_step(self.initial_stance, t)
        else:
            T = command.step_time_s
            phase_raw = (t - self.planner.t_step_start_s) / T
            swing = "right" if self._stance == "left" else "left"
            height = float(kin.contact_position(swing)[2] - kin.contact_position(self._stance)[2])
            contact = measurement.foot_contact.get(swing) if measurement.foot_contact else None
            if self._last_plan is not None and self.gait.touchdown(phase_raw, contact, height):
                est_old = self.estimator.estimate(self._stance)
                self._record_step(t, est_old)
                self._begin_step(swing, t)
                touchdown = True
        est = self.estimator.estimate(self._stance, touchdown=touchdown)
        v_z = float(est.com_vel_mps[2])
        plan = self.planner.update(
            StateEstimate(
                stance=self._stance,
                p_st_m=est.p_st_m,
                L_Nms=est.L_Nms,
                v_z_mps=v_z,
                t_in_step_s=max(t - self.planner.t_step_start_s, 0.0),
                com_m=est.com_m,
            ),
            command,
        )
        self._last_plan = plan
        target = TrackingTarget(
            stance=self._stance,
            phase=plan.s,
            heading_rad=plan.heading_rad,
            h_d=plan.h_d,
            dh_d=plan.dh_d,
            ddh_d=plan.ddh_d,
            swing_contact_weight=self._swing_contact_weight(measurement, plan.s),
        )
        result = self.tracker.compute(kin, target)
        tau = result.tau_Nm
        ok = result.ok
        if tau.shape != (len(self._act_v),) or not np.all(np.isfinite(tau)):
            tau = -self._fallback_kd * kin.v[self._act_v]
            ok = False
            self.fallback_ticks += 1
            if self.fallback_ticks == 1:
                warnings.warn(
                    f"tracker {self.tracker.name!r} returned non-finite torques at t={t:.4f} s; "
                    "using the damped fallback (counted in fallback_ticks)",
                    RuntimeWarning,
                    stacklevel=2,
                )
        tau = np.clip(tau, self._tau_lim[:, 0], self._tau_lim[:, 1])
        h, _, _ = kin.outputs(self._stance, plan.heading_rad)
        return TickInfo(
            t_s=t,
            stance=self._stance,
            phase=plan.s,
            estimate=est,
            plan=plan,
            h=h,
            tau_Nm=tau,
            tracker_ok=ok and result.ok,
            touchdown=touchdown,
            info=result.info,
        )

    @staticmethod
    def _swing_contact_weight(measurement: Measurement, phase: float) -> float:
        """0 in the air; rises over the last 10% of the step so trackers can blend forces in."""
        if phase <= 0.9:
            return 0.0
        return min(1.0, (phase - 0.9) / 0.1) if math.isfinite(phase) else 0.0
