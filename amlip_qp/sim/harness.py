"""The MuJoCo harness: the plant, its sensors, pushes, and the closed loop.

The harness is the only code that knows the plant. Every control tick it
reads the plant's state in the controller's Pinocchio convention through the
:class:`~amlip_qp.sim.plant.Plant` (which maps any plant model to the
controller's by name), optionally adds Gaussian noise (``--noise``), hands the
sensors' :class:`~amlip_qp.control.walking.estimator.Measurement`
(:mod:`~amlip_qp.sim.sensors`: ``ideal`` or ``robot``) to the controller,
turns the joint torques into the plant's actuator controls
(``ctrl = tau / gear``), applies pushes on the base body, and steps MuJoCo.
Its inputs and result are the plain types of :mod:`~amlip_qp.sim.run_types`.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable

import mujoco
import numpy as np

from amlip_qp.alip.planner import Command
from amlip_qp.control.walking.controller import WalkingController
from amlip_qp.control.walking.estimator import Measurement
from amlip_qp.exceptions import InputError
from amlip_qp.robots.robot import Robot
from amlip_qp.sim.plant import Plant, load_plant
from amlip_qp.sim.pushes import PushSchedule
from amlip_qp.sim.run_types import FallCriteria, Push, RunResult, SensorNoise, TickCallback, quat_mul_small_rotation
from amlip_qp.sim.sensors import PlantSensors, SensorSettings, base_indices

#: MuJoCo warnings that mean the simulation diverged (it then resets the state).
_DIVERGENCE_WARNINGS = (
    mujoco.mjtWarning.mjWARN_BADQACC,
    mujoco.mjtWarning.mjWARN_BADQPOS,
    mujoco.mjtWarning.mjWARN_BADQVEL,
)


class Simulation:
    """A MuJoCo plant closed around a :class:`WalkingController`.

    Args:
        robot: The controller's :class:`~amlip_qp.robots.robot.Robot`.
        controller: The controller.
        command_fn: Time (s) -> :class:`~amlip_qp.alip.planner.Command`.
        pushes: Forces on the base body.
        noise: Gaussian noise on the ``ideal`` measurement (``--noise``), or ``None``.
        seed: Seed of the noise generators (``noise`` and the ``robot`` sensors).
        contact_threshold_N: Normal force above which a foot's contact switch is on, N.
        fall: Fall criteria.
        keyframe: Initial keyframe name (of the plant).
        plant: The plant (default: the robot's own model, :func:`~amlip_qp.sim.plant.load_plant`).
        sensors: ``"ideal"`` or ``"robot"`` (:mod:`~amlip_qp.sim.sensors`).
        estimator: The controller's base estimator (its name, ``--estimator``): with
            ``"truth"`` the measurement carries the simulator's true base state; with any
            other, none (``base_known=False``): the controller's estimator fills it.
        sensor_settings: Noise of the ``robot`` sensors.
        ctrl_filter: Applied to the actuator controls (controller order, after
            ``tau / gear`` and clipping) before they are written to the plant, e.g.
            an actuator delay's ``push``; ``None``: written as they are.
    """

    def __init__(
        self,
        robot: Robot,
        controller: WalkingController,
        command_fn: Callable[[float], Command],
        pushes: tuple[Push, ...] | list[Push] = (),
        noise: SensorNoise | None = None,
        seed: int = 0,
        contact_threshold_N: float = 20.0,
        fall: FallCriteria | None = None,
        keyframe: str = "stand",
        plant: Plant | None = None,
        sensors: str = "ideal",
        estimator: str = "truth",
        sensor_settings: SensorSettings | None = None,
        ctrl_filter: Callable[[np.ndarray], np.ndarray] | None = None,
    ):
        self.robot = robot
        self.controller = controller
        self.command_fn = command_fn
        self.pushes = tuple(pushes)
        self.push_schedule = PushSchedule(self.pushes)
        self.noise = noise
        if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
            raise InputError(f"seed must be a non-negative integer, got {seed!r}")
        self.seed = int(seed)
        self.rng = np.random.default_rng(seed)
        self.contact_threshold_N = float(contact_threshold_N)
        self.fall = fall or FallCriteria()
        self.plant = plant if plant is not None else load_plant(robot.name, robot)
        if self.plant.robot is not robot:
            raise InputError(f"the plant {self.plant.name} was loaded for another robot object than the controller's")
        if noise is not None and sensors != "ideal":
            raise InputError("--noise adds Gaussian noise to the ideal sensors; the robot sensors have their own")
        self.model = self.plant.model
        self.data = self.plant.new_data(keyframe)
        self.dt_s = float(self.model.opt.timestep)
        ratio = controller.dt_s / self.dt_s
        self.substeps = int(round(ratio))
        if self.substeps < 1 or abs(ratio - self.substeps) > 1e-9:
            raise InputError(
                f"the control period ({controller.dt_s} s) must be a whole multiple of the plant step ({self.dt_s} s)"
            )
        self._base_body = self.plant.base_body_id
        self.sensors = PlantSensors(
            self.plant,
            sensors,
            dt_s=controller.dt_s,
            seed=self.seed,
            settings=sensor_settings,
            contact_threshold_N=self.contact_threshold_N,
        )
        self.estimator = str(estimator)
        self.true_base = self.estimator == "truth"
        self.ctrl_filter = ctrl_filter
        self._base_q, self._base_v = base_indices(robot)
        self._base_size = (np.zeros(robot.nq)[self._base_q].size, np.zeros(robot.nv)[self._base_v].size)
        self._scalar_pin_q = robot.state_map.scalar_pin_q
        self._scalar_pin_v = robot.state_map.scalar_pin_v

    # ----------------------------------------------------------- sensors
    def foot_contact(self) -> dict[str, bool]:
        """Exact contact switches: True when the floor pushes on the foot's body harder than the threshold."""
        return self.sensors.exact_contact(self.data)

    def measure(self) -> Measurement:
        """This tick's sensor data (see :meth:`measure_state`)."""
        q, v = self.plant.read_state(self.data)
        return self.measure_state(q, v)

    def measure_state(self, q: np.ndarray, v: np.ndarray) -> Measurement:
        """The measurement of the true state ``(q, v)`` (modified in place): ``--noise``, then the sensors."""
        if self.noise is not None:
            n, rng = self.noise, self.rng
            q[self._scalar_pin_q] += rng.normal(0.0, n.joint_pos_rad, self._scalar_pin_q.size)
            v[self._scalar_pin_v] += rng.normal(0.0, n.joint_vel_radps, self._scalar_pin_v.size)
            if self.robot.is_floating:
                q[:3] += rng.normal(0.0, n.base_pos_m, 3)
                q[3:7] = quat_mul_small_rotation(q[3:7], rng.normal(0.0, n.base_rot_rad, 3))
                v[:3] += rng.normal(0.0, n.base_lin_vel_mps, 3)
                v[3:6] += rng.normal(0.0, n.base_ang_vel_radps, 3)
        return self.sensors.measure(self.data, q, v, base_known=self.true_base)

    # ------------------------------------------------------------ checks
    def _base_height_and_tilt(self) -> tuple[float, float]:
        d = self.data
        z = float(d.xpos[self._base_body][2])
        R = d.xmat[self._base_body].reshape(3, 3)
        tilt = math.acos(max(-1.0, min(1.0, float(R[2, 2]))))
        return z, tilt

    def _base_yaw(self) -> float:
        """Yaw of the base body (rad, in (-pi, pi])."""
        R = self.data.xmat[self._base_body].reshape(3, 3)
        return math.atan2(float(R[1, 0]), float(R[0, 0]))

    def push_force(self, t_s: float, phase: float = math.nan) -> np.ndarray:
        """World force on the base at time ``t_s`` (N) and step phase ``phase`` (see :mod:`~amlip_qp.sim.pushes`)."""
        return self.push_schedule.force(t_s, phase)

    # --------------------------------------------------------------- run
    def run(self, duration_s: float, progress: bool = False, on_tick: TickCallback | None = None) -> RunResult:
        """Simulate ``duration_s`` seconds (stops early at a fall).

        Args:
            duration_s: Simulated time, s.
            progress: Show a tqdm progress bar on stderr.
            on_tick: Optional ``on_tick(t_s, data)`` called after every control
                tick's plant steps (e.g. a video recorder); it must not modify ``data``.

        The log holds, per control tick: ``t``, ``com`` (3), ``com_vel`` (3),
        ``base_pos`` (3), ``base_tilt``, ``base_yaw`` (rad, wrapped to (-pi, pi]),
        ``stance_left`` (1 if left stance), ``phase``, ``t_remaining`` (the
        planner's prediction horizon, s), ``heading``, ``p_st`` (3, CoM minus
        stance contact, m), ``L_meas`` (3), ``L`` (3, filtered),
        ``L_hat`` (2), ``L_des`` (2), ``p_sw_des`` (2), ``swing_target`` (3),
        ``h`` and ``h_d`` (outputs), ``tau`` (joint side, N m),
        ``tracker_ok``, ``push`` (3, N) and the command ``cmd_vx``, ``cmd_vy``,
        ``cmd_turn_rate``. ``base_pos`` and ``base_yaw`` are MuJoCo's body pose of
        the last plant step's start. For a floating-base robot, the base state
        the controller used against the truth at the measurement:
        ``base_pos_true``, ``base_vel_true`` (3, world, m/s), ``base_yaw_true``,
        and ``base_pos_est``, ``base_vel_est``, ``base_yaw_est`` (equal to the
        truth with ``--estimator truth`` and exact sensors).
        """
        if not (duration_s > 0 and math.isfinite(duration_s)):
            raise InputError(f"duration must be a positive number of seconds, got {duration_s!r}")
        m, d, ctrl = self.model, self.data, self.controller
        ctrl.reset()
        self.push_schedule.reset()
        n_ticks = int(round(duration_s / ctrl.dt_s))
        if n_ticks < 1:
            raise InputError(f"duration {duration_s!r} s is shorter than one control tick ({ctrl.dt_s} s)")
        nu = self.robot.nu
        n_out = ctrl.planner.n_outputs
        log = {
            "t": np.zeros(n_ticks),
            "com": np.zeros((n_ticks, 3)),
            "com_vel": np.zeros((n_ticks, 3)),
            "base_pos": np.zeros((n_ticks, 3)),
            "base_tilt": np.zeros(n_ticks),
            "base_yaw": np.zeros(n_ticks),
            "stance_left": np.zeros(n_ticks),
            "phase": np.zeros(n_ticks),
            "t_remaining": np.zeros(n_ticks),
            "heading": np.zeros(n_ticks),
            "p_st": np.zeros((n_ticks, 3)),
            "L_meas": np.zeros((n_ticks, 3)),
            "L": np.zeros((n_ticks, 3)),
            "L_hat": np.zeros((n_ticks, 2)),
            "L_des": np.zeros((n_ticks, 2)),
            "p_sw_des": np.zeros((n_ticks, 2)),
            "swing_target": np.zeros((n_ticks, 3)),
            "h": np.zeros((n_ticks, n_out)),
            "h_d": np.zeros((n_ticks, n_out)),
            "tau": np.zeros((n_ticks, nu)),
            "tracker_ok": np.zeros(n_ticks),
            "push": np.zeros((n_ticks, 3)),
            "cmd_vx": np.zeros(n_ticks),
            "cmd_vy": np.zeros(n_ticks),
            "cmd_turn_rate": np.zeros(n_ticks),
        }
        bq, bv = self._base_q, self._base_v
        nbq, nbv = self._base_size
        base_true = np.zeros((n_ticks, nbq + nbv))
        base_est = np.zeros((n_ticks, nbq + nbv))
        plant, ctrl_filter = self.plant, self.ctrl_filter
        tick_us = np.zeros(n_ticks)
        z0, _ = self._base_height_and_tilt()
        fell, fall_time = False, float("nan")
        bar = None
        if progress:
            from tqdm import tqdm

            bar = tqdm(total=n_ticks, unit="tick", desc=f"{self.robot.name}/{ctrl.tracker.name}", leave=False)
        wall0 = time.perf_counter()
        warn0 = [d.warning[w].number for w in _DIVERGENCE_WARNINGS]
        sim_time = float(d.time)
        k = 0
        for k in range(n_ticks):
            t = float(d.time)
            cmd = self.command_fn(t)
            q, v = plant.read_state(d)
            row = base_true[k]
            row[:nbq], row[nbq:] = q[bq], v[bv]
            meas = self.measure_state(q, v)
            t0 = time.perf_counter_ns()
            tick = ctrl.step(meas, cmd)
            tick_us[k] = (time.perf_counter_ns() - t0) * 1e-3
            q_est, v_est = ctrl.kin.state()
            row = base_est[k]
            row[:nbq], row[nbq:] = q_est[bq], v_est[bv]
            ctrl_now = plant.ctrl_from_tau(tick.tau_Nm)
            if ctrl_filter is not None:  # e.g. an actuator delay
                ctrl_now = ctrl_filter(ctrl_now)
            plant.apply_ctrl(d, ctrl_now)
            push = self.push_force(t, tick.phase)
            d.xfrc_applied[self._base_body, :3] = push
            # log
            est, plan = tick.estimate, tick.plan
            z, tilt = self._base_height_and_tilt()
            log["t"][k] = t
            log["com"][k] = est.com_m
            log["com_vel"][k] = est.com_vel_mps
            log["base_pos"][k] = d.xpos[self._base_body]
            log["base_tilt"][k] = tilt
            log["base_yaw"][k] = self._base_yaw()
            log["stance_left"][k] = 1.0 if tick.stance == "left" else 0.0
            log["phase"][k] = tick.phase
            log["t_remaining"][k] = plan.t_remaining_s
            log["heading"][k] = plan.heading_rad
            log["p_st"][k] = est.p_st_m
            log["L_meas"][k] = est.L_meas_Nms
            log["L"][k] = est.L_Nms
            log["L_hat"][k] = plan.L_hat_Nms
            log["L_des"][k] = plan.L_des_Nms
            log["p_sw_des"][k] = plan.p_sw_des_world_m
            log["swing_target"][k] = plan.swing_target_world_m
            log["h"][k] = tick.h
            log["h_d"][k] = plan.h_d
            log["tau"][k] = tick.tau_Nm
            log["tracker_ok"][k] = 1.0 if tick.tracker_ok else 0.0
            log["push"][k] = push
            log["cmd_vx"][k] = cmd.vx_mps
            log["cmd_vy"][k] = cmd.vy_mps
            log["cmd_turn_rate"][k] = cmd.turn_rate_radps
            t_before = d.time
            for _ in range(self.substeps):
                mujoco.mj_step(m, d)
            # MuJoCo resets an unstable state to qpos0 (time back to ~0) and
            # counts a warning; that is a divergence, reported as a fall.
            if d.time < t_before or any(d.warning[w].number > warn0[i] for i, w in enumerate(_DIVERGENCE_WARNINGS)):
                fell, fall_time, sim_time = True, t, t
                break
            sim_time = float(d.time)
            if on_tick is not None:
                on_tick(float(d.time), d)
            if bar is not None and (k + 1) % 200 == 0:
                bar.update(200)
            if (
                z < self.fall.min_height_fraction * z0
                or tilt > self.fall.max_tilt_rad
                or not np.all(np.isfinite(d.qpos))
            ):
                fell, fall_time = True, t
                break
        wall = time.perf_counter() - wall0
        n = k + 1
        if bar is not None:
            bar.update(n - bar.n)
            bar.close()
        log = {key: value[:n] for key, value in log.items()}
        if self.robot.is_floating:
            log.update(_world_base(base_true[:n], "true"))
            log.update(_world_base(base_est[:n], "est"))
        return RunResult(
            robot=self.robot.name,
            tracker=ctrl.tracker.name,
            duration_s=float(duration_s),
            sim_time_s=sim_time,
            wall_time_s=wall,
            fell=fell,
            fall_time_s=fall_time,
            log=log,
            steps=list(ctrl.steps),
            tick_time_us=tick_us[:n],
            fallback_ticks=ctrl.fallback_ticks,
            safe_mode_ticks=ctrl.safe_mode_ticks,
            estimator_divergences=ctrl.estimator_divergences,
            pushes=self.pushes,
            info={
                "output_names": tuple(ctrl.planner.output_names),
                "actuator_names": tuple(self.robot.actuated.names),
                "control_dt_s": ctrl.dt_s,
                "planar": bool(self.robot.is_planar),
                "seed": self.seed,
                "noise": self.noise is not None,
                "plant": self.plant.name,
                "sensors": self.sensors.model,
                "estimator": self.estimator,
            },
        )


def _world_base(rows: np.ndarray, suffix: str) -> dict[str, np.ndarray]:
    """``base_pos_*``, ``base_vel_*`` (world) and ``base_yaw_*`` from free-flyer rows ``(q[:7], v[:6])``."""
    pos, quat, vel_body = rows[:, :3], rows[:, 3:7], rows[:, 7:10]
    u, w = quat[:, :3], quat[:, 3:4]
    uv = np.cross(u, vel_body)
    vel_world = vel_body + 2.0 * w * uv + 2.0 * np.cross(u, uv)  # R(quat) @ v for unit quaternions
    x, y, z, qw = quat.T
    yaw = np.arctan2(2.0 * (qw * z + x * y), 1.0 - 2.0 * (y * y + z * z))
    return {f"base_pos_{suffix}": pos.copy(), f"base_vel_{suffix}": vel_world, f"base_yaw_{suffix}": yaw}
