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
from typing import cast

import mujoco
import numpy as np

from amlip_qp.alip.planner import Command
from amlip_qp.control.walking.controller import WalkingController
from amlip_qp.control.walking.estimator import Measurement
from amlip_qp.exceptions import InputError
from amlip_qp.robots.robot import Robot
from amlip_qp.sim.plant import Plant, load_plant
from amlip_qp.sim.pushes import PushSchedule
from amlip_qp.sim.run_log import (
    BLOCK_ROWS,
    LOG_MODES,
    SCALAR_KEYS,
    SCALAR_KEYS_FULL,
    VECTOR_GROUPS_FULL,
    RowBlocks,
    unpack_log,
    vector_groups,
)
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
        ground_height_m: World (x, y) m -> ground height m (the terrain's); the fall
            check then takes the base height above the ground under the base.
            ``None``: above z = 0 (flat ground).
        terrain: The terrain's spec text (``--terrain``), reported in the result's ``info``.
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
        ground_height_m: Callable[[float, float], float] | None = None,
        terrain: str = "flat",
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
        self.substeps = self.plant.substeps(controller.dt_s)
        self._base_body = self.plant.base_body_id
        self.sensors = PlantSensors(
            self.plant, sensors, dt_s=controller.dt_s, seed=self.seed, settings=sensor_settings,
            contact_threshold_N=self.contact_threshold_N,
        )  # fmt: skip
        self.estimator = str(estimator)
        self.true_base = self.estimator == "truth"
        self.ctrl_filter = ctrl_filter
        self.ground_height_m = ground_height_m
        self.terrain = str(terrain)
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
            self._add_noise(q, v)
        return self.sensors.measure(self.data, q, v, base_known=self.true_base)

    def _add_noise(self, q: np.ndarray, v: np.ndarray) -> None:
        """``--noise`` (not ``None``) on the state ``(q, v)``, in place."""
        n, rng = cast(SensorNoise, self.noise), self.rng
        q[self._scalar_pin_q] += rng.normal(0.0, n.joint_pos_rad, self._scalar_pin_q.size)
        v[self._scalar_pin_v] += rng.normal(0.0, n.joint_vel_radps, self._scalar_pin_v.size)
        if self.robot.is_floating:
            q[:3] += rng.normal(0.0, n.base_pos_m, 3)
            q[3:7] = quat_mul_small_rotation(q[3:7], rng.normal(0.0, n.base_rot_rad, 3))
            v[:3] += rng.normal(0.0, n.base_lin_vel_mps, 3)
            v[3:6] += rng.normal(0.0, n.base_ang_vel_radps, 3)

    # ------------------------------------------------------------ pushes
    def push_force(self, t_s: float, phase: float = math.nan) -> np.ndarray:
        """World force on the base at time ``t_s`` (N) and step phase ``phase`` (see :mod:`~amlip_qp.sim.pushes`)."""
        return self.push_schedule.force(t_s, phase)

    # --------------------------------------------------------------- run
    def run(
        self,
        duration_s: float,
        progress: bool = False,
        on_tick: TickCallback | None = None,
        log: str = "full",
    ) -> RunResult:
        """Simulate ``duration_s`` seconds (stops early at a fall).

        Args:
            duration_s: Simulated time, s.
            progress: Show a tqdm progress bar on stderr.
            on_tick: Optional ``on_tick(t_s, data)`` called after every control
                tick's plant steps (e.g. a video recorder); it must not modify ``data``.
            log: ``"full"``: every signal below; ``"summary"``: only the entries
                :func:`~amlip_qp.sim.summary.summarize` reads
                (:data:`~amlip_qp.sim.summary.SUMMARY_LOG_KEYS`). The trajectory is
                the same in both modes.

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

        Per tick, the result also has the wall times (µs) of the controller
        (``tick_time_us``), of MuJoCo's plant steps (``mujoco_time_us``) and of
        the rest of the loop, the harness's own (``harness_time_us``).
        """
        if log not in LOG_MODES:
            raise InputError(f"log must be one of {', '.join(LOG_MODES)}, got {log!r}")
        if not (duration_s > 0 and math.isfinite(duration_s)):
            raise InputError(f"duration must be a positive number of seconds, got {duration_s!r}")
        m, d, ctrl = self.model, self.data, self.controller
        ctrl.reset()
        self.push_schedule.reset()
        n_ticks = int(round(duration_s / ctrl.dt_s))
        if n_ticks < 1:
            raise InputError(f"duration {duration_s!r} s is shorter than one control tick ({ctrl.dt_s} s)")
        full = log == "full"
        n_out = ctrl.planner.n_outputs
        # One row per tick: the Python scalars and the base states go to row blocks (flat lists turned
        # into arrays every BLOCK_ROWS ticks), the vectors to one preallocated row (one np.concatenate).
        scalar_keys = SCALAR_KEYS + (SCALAR_KEYS_FULL if full else ())
        vector_keys = vector_groups(n_out, self.robot.nu) + (VECTOR_GROUPS_FULL if full else ())
        vectors = np.zeros((n_ticks, sum(w for _, w in vector_keys)))
        scalars = RowBlocks(len(scalar_keys))
        floating = self.robot.is_floating
        bq, bv = cast(slice, self._base_q), cast(slice, self._base_v)  # used with a floating base: slices
        base_true = RowBlocks(sum(self._base_size))  # the measured base state's (q, v)
        # The controller's: with the true base and no --noise, the measured one itself (the
        # controller's kinematics take the measurement as it is; tested), not logged twice.
        est_is_true = self.true_base and self.noise is None
        base_est = base_true if est_is_true else RowBlocks(sum(self._base_size))
        # each tick extends these flat lists by its row
        scalar_rows, true_rows, est_rows = scalars.rows.extend, base_true.rows.extend, base_est.rows.extend
        # per tick, ns: its start, the controller's start and end, MuJoCo's start and end, its end
        stamps = RowBlocks(6, np.int64)
        stamp_rows = stamps.rows.extend
        # Hoisted lookups: views into MjData stay valid across mj_step.
        plant, ctrl_filter, command_fn = self.plant, self.ctrl_filter, self.command_fn
        read_state, sense, push_force = plant.array_reader(d), self.sensors.bind(d, self.true_base), self.push_force
        read_next = plant.compiled_reader(d)  # as generated C, after each tick's steps for the next (or None)
        add_noise = None if self.noise is None else self._add_noise
        write_ctrl = plant.ctrl_writer(d, compiled=ctrl_filter is None)  # with a filter: apply_ctrl
        ctrl_from_tau, apply_ctrl = plant.ctrl_from_tau, plant.apply_ctrl
        ctrl_step, kin_state = ctrl.step, ctrl.kin.state
        step, plant_steps, dt_s, qpos = mujoco.mj_step, range(self.substeps), self.dt_s, d.qpos
        later_steps = range(self.substeps - 1)  # the plant steps after a tick's first
        xpos_b, xmat_b, xfrc_b = d.xpos[self._base_body], d.xmat[self._base_body], d.xfrc_applied[self._base_body, :3]
        pushes, no_push = bool(self.pushes), np.zeros(3)
        if not pushes:
            xfrc_b[:] = no_push  # and so it stays
        warn_number, warn_idx = d.warning.number, [int(w) for w in _DIVERGENCE_WARNINGS]
        warn_number[warn_idx] = 0  # an earlier run's divergence on this data must not hide one of this run
        warn_all0 = warn_number.tolist()
        concatenate, perf_ns = np.concatenate, time.perf_counter_ns
        acos, atan2, isfinite = math.acos, math.atan2, math.isfinite
        ground = self.ground_height_m  # None on flat ground: the height is z itself
        z0 = float(xpos_b[2]) if ground is None else float(xpos_b[2]) - ground(float(xpos_b[0]), float(xpos_b[1]))
        min_z, max_tilt = self.fall.min_height_fraction * z0, self.fall.max_tilt_rad
        # Above this cosine the tilt is surely not over max_tilt (acos decreases; its error << the margin).
        upright_cos = math.cos(min(max(max_tilt, 0.0), math.pi)) + 1e-12
        fell, fall_time, bar = False, float("nan"), None
        if progress:
            from tqdm import tqdm

            bar = tqdm(total=n_ticks, unit="tick", desc=f"{self.robot.name}/{ctrl.tracker.name}", leave=False)
        wall0 = time.perf_counter()
        sim_time = t_next = float(d.time)
        state = None  # this tick's (q, v, root) if read already (after the last tick's plant steps)
        qpos_list = qpos.tolist()
        total = sum(qpos_list)
        k = 0
        for k in range(n_ticks):
            t_tick = perf_ns()
            t = t_next
            cmd = command_fn(t)
            if state is None:  # read here: the first tick, no compiled read, or a state it left to read_state's checks
                state = read_state(qpos_list, total) if read_next is None else read_state(qpos.tolist())
            q, v, root = state  # root: the base's (q, v) as one list
            r00, _, _, r10, _, _, _, _, r22 = xmat_b.tolist()  # the last plant step's start, read while cached
            if ground is None:
                z = xpos_b.item(2)
            else:  # height above the ground under the base
                x, y, z = xpos_b.tolist()
                z -= ground(x, y)
            if floating:
                true_rows(root)
            if add_noise is not None:
                add_noise(q, v)
            meas = sense(t, q, v)
            t_c0 = perf_ns()
            tick = ctrl_step(meas, cmd)
            t_c1 = perf_ns()
            if floating and not est_is_true:
                q_est, v_est = kin_state()
                est_rows(q_est.tolist()[bq] + v_est.tolist()[bv])
            tau = tick.tau_Nm
            if ctrl_filter is None:
                write_ctrl(tau)
            else:  # e.g. an actuator delay
                apply_ctrl(d, ctrl_filter(ctrl_from_tau(tau)))
            if pushes:
                push = push_force(t, tick.phase)
                xfrc_b[:] = push
            else:
                push = no_push
            est, plan = tick.estimate, tick.plan
            ok = 1.0 if tick.tracker_ok else 0.0
            if full:
                tilt = acos(max(-1.0, min(1.0, r22)))
                scalar_rows(
                    (
                        t, cmd.vx_mps, cmd.vy_mps, plan.heading_rad, atan2(r10, r00), ok,
                        tilt, 1.0 if tick.stance == "left" else 0.0, tick.phase, plan.t_remaining_s,
                        cmd.turn_rate_radps,
                    )
                )  # fmt: skip
                concatenate(
                    (
                        est.com_m, est.com_vel_mps, tick.h, plan.h_d, tau,
                        xpos_b, est.p_st_m, est.L_meas_Nms, est.L_Nms, plan.L_hat_Nms, plan.L_des_Nms,
                        plan.p_sw_des_world_m, plan.swing_target_world_m, push,
                    ),
                    out=vectors[k],
                )  # fmt: skip
            else:
                scalar_rows((t, cmd.vx_mps, cmd.vy_mps, plan.heading_rad, atan2(r10, r00), ok))
                concatenate((est.com_m, est.com_vel_mps, tick.h, plan.h_d, tau), out=vectors[k])
            t_m0 = perf_ns()
            for _ in plant_steps:
                step(m, d)
            t_m1 = perf_ns()
            t_next = t + dt_s  # MuJoCo's clock, time += timestep a step (d.time, a slow property: tested)
            for _ in later_steps:
                t_next += dt_s
            # MuJoCo resets an unstable state to qpos0 (and its clock) and counts a
            # warning; that is a divergence, reported as a fall.
            warn_all = warn_number.tolist()
            if warn_all != warn_all0 and any(warn_all[i] for i in warn_idx):
                fell, fall_time, sim_time = True, t, t
                stamp_rows((t_tick, t_c0, t_c1, t_m0, t_m1, perf_ns()))
                break
            warn_all0 = warn_all
            sim_time = t_next
            if on_tick is not None:
                on_tick(sim_time, d)
            if bar is not None and (k + 1) % 200 == 0:
                bar.update(200)
            # A finite sum implies finite entries (NaN and inf propagate); only if not, look closer.
            if read_next is None:  # the next tick's read_state takes the list and its sum
                qpos_list = qpos.tolist()
                state, total = None, sum(qpos_list)
            else:  # the next tick's state, and the sum of qpos and qvel
                state, total = read_next()
            tilted = r22 < upright_cos and acos(max(-1.0, min(1.0, r22))) > max_tilt
            if z < min_z or tilted or (not isfinite(total) and not np.all(np.isfinite(qpos))):
                fell, fall_time = True, t
                stamp_rows((t_tick, t_c0, t_c1, t_m0, t_m1, perf_ns()))
                break
            stamp_rows((t_tick, t_c0, t_c1, t_m0, t_m1, perf_ns()))
            if k % BLOCK_ROWS == BLOCK_ROWS - 1:
                stamps.flush()
                scalars.flush()
                base_true.flush()
                base_est.flush()
        wall = time.perf_counter() - wall0
        n = k + 1
        if bar is not None:
            bar.update(n - bar.n)
            bar.close()
        ns = stamps.array()
        tick_us, mujoco_us = (ns[:, 2] - ns[:, 1]) * 1e-3, (ns[:, 4] - ns[:, 3]) * 1e-3
        base_rows = base_true.array(), base_est.array()
        return RunResult(
            robot=self.robot.name,
            tracker=ctrl.tracker.name,
            duration_s=float(duration_s),
            sim_time_s=sim_time,
            wall_time_s=wall,
            fell=fell,
            fall_time_s=fall_time,
            log=unpack_log(scalars.array(), scalar_keys, vectors[:n], vector_keys, *base_rows, floating, full),
            steps=list(ctrl.steps),
            tick_time_us=tick_us,
            mujoco_time_us=mujoco_us,
            harness_time_us=(ns[:, 5] - ns[:, 0]) * 1e-3 - tick_us - mujoco_us,
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
                "terrain": self.terrain,
                "log": log,
            },
        )
