"""The MuJoCo harness: the plant, its sensors, pushes, and the closed loop.

The harness is the only code that knows the plant. Every control tick it
reads the plant's state in the controller's Pinocchio convention through the
:class:`~amlip_qp.sim.world.plant.Plant` (which maps any plant model to the
controller's by name), optionally adds Gaussian noise (``--noise``), hands the
sensors' :class:`~amlip_qp.messages.Measurement`
(:mod:`~amlip_qp.sim.sensing.sensors`: ``ideal`` or ``robot``) to the controller,
turns the joint torques into the plant's actuator controls
(``ctrl = tau / gear``), applies pushes on the base body, and steps MuJoCo.
Its inputs and result are the plain types of :mod:`~amlip_qp.sim.loop.run_types`.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from typing import cast

import mujoco
import numpy as np

from amlip_qp.control.walking.controller import WalkingController
from amlip_qp.exceptions import InputError
from amlip_qp.messages import Command, Measurement
from amlip_qp.robots.robot import Robot
from amlip_qp.sim.loop.pushes import PushSchedule
from amlip_qp.sim.loop.run_log import BLOCK_ROWS, LOG_MODES, RowBlocks, TickLog
from amlip_qp.sim.loop.run_types import (
    FallCriteria,
    Push,
    RunResult,
    SensorNoise,
    TickCallback,
    TickRecord,
)
from amlip_qp.sim.sensing.sensors import PlantSensors, SensorSettings, base_indices, quat_mul_small_rotation
from amlip_qp.sim.world.plant import Plant
from amlip_qp.sim.world.plant_loader import load_plant

#: MuJoCo warnings that mean the simulation diverged (it then resets the state).
_DIVERGENCE_WARNINGS = (
    mujoco.mjtWarning.mjWARN_BADQACC,
    mujoco.mjtWarning.mjWARN_BADQPOS,
    mujoco.mjtWarning.mjWARN_BADQVEL,
)
#: The status of a :meth:`Simulation.ticker` tick: standing, diverged (MuJoCo reset an unstable state), fallen.
TICK_OK, TICK_DIVERGED, TICK_FELL = 0, 1, 2


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
        keyframe: Initial keyframe name (of the plant); ``None``: MuJoCo's default state.
        plant: The plant (default: the robot's own model, :func:`~amlip_qp.sim.world.plant_loader.load_plant`).
        sensors: ``"ideal"`` or ``"robot"`` (:mod:`~amlip_qp.sim.sensing.sensors`).
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
        keyframe: str | None = "stand",
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
        self._keyframe_id = -1 if keyframe is None else mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_KEY, keyframe)
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
        """World force on the base at time ``t_s`` (N) and step phase ``phase`` (:mod:`~amlip_qp.sim.loop.pushes`)."""
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
                :func:`~amlip_qp.sim.reports.summary.summarize` reads
                (:data:`~amlip_qp.sim.loop.run_log.SUMMARY_LOG_KEYS`). The trajectory is
                the same in both modes.

        The log's entries are those of :class:`~amlip_qp.sim.loop.run_log.TickLog`.

        Per tick, the result also has the wall times (µs) of the controller
        (``tick_time_us``), of MuJoCo's plant steps (``mujoco_time_us``) and of
        the rest of the loop, the harness's own (``harness_time_us``).
        """
        if log not in LOG_MODES:
            raise InputError(f"log must be one of {', '.join(LOG_MODES)}, got {log!r}")
        if not (duration_s > 0 and math.isfinite(duration_s)):
            raise InputError(f"duration must be a positive number of seconds, got {duration_s!r}")
        ctrl = self.controller
        n_ticks = int(round(duration_s / ctrl.dt_s))
        if n_ticks < 1:
            raise InputError(f"duration {duration_s!r} s is shorter than one control tick ({ctrl.dt_s} s)")
        floating = self.robot.is_floating
        tick_log = TickLog(
            n_ticks, ctrl.planner.n_outputs, self.robot.nu, log == "full", floating, self._base_size,
            self.true_base and self.noise is None, self.data.xpos[self._base_body], ctrl.kin.state,
            self._base_q, self._base_v,
        )  # fmt: skip
        # per tick, ns: its start, the controller's start and end, MuJoCo's start and end, its end
        stamps = RowBlocks(6, np.int64)
        tick = self.ticker(tick_log.record, on_tick, stamps.rows.extend)
        fell, fall_time, bar = False, float("nan"), None
        if progress:
            from tqdm import tqdm

            bar = tqdm(total=n_ticks, unit="tick", desc=f"{self.robot.name}/{ctrl.tracker.name}", leave=False)
        wall0 = time.perf_counter()
        sim_time = float(self.data.time)
        k = 0
        for k in range(n_ticks):
            status, t, sim_time = tick()
            if status:
                fell, fall_time = True, t
                break
            if bar is not None and (k + 1) % 200 == 0:
                bar.update(200)
            if k % BLOCK_ROWS == BLOCK_ROWS - 1:
                stamps.flush()
                tick_log.flush()
        wall = time.perf_counter() - wall0
        n = k + 1
        if bar is not None:
            bar.update(n - bar.n)
            bar.close()
        ns = stamps.array()
        tick_us, mujoco_us = (ns[:, 2] - ns[:, 1]) * 1e-3, (ns[:, 4] - ns[:, 3]) * 1e-3
        return RunResult(
            robot=self.robot.name,
            tracker=ctrl.tracker.name,
            duration_s=float(duration_s),
            sim_time_s=sim_time,
            wall_time_s=wall,
            fell=fell,
            fall_time_s=fall_time,
            log=tick_log.log(n),
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

    # -------------------------------------------------------------- tick
    def ticker(
        self,
        record: TickRecord | None = None,
        on_tick: TickCallback | None = None,
        stamp: Callable[[tuple[int, ...]], object] | None = None,
    ) -> Callable[[], tuple[int, float, float]]:
        """Start a run from the plant's state now (the controller and pushes start over); return its tick.

        Each call of the tick is one control tick: the sensors, the controller on
        ``command_fn(t)``, the controls and the push, the plant steps, the fall checks. It
        returns ``(status, t_s, t_after_s)``: :data:`TICK_OK`, :data:`TICK_DIVERGED` (MuJoCo reset
        an unstable state; ``t_after_s`` is then ``t_s``) or :data:`TICK_FELL`, the tick's time and
        the simulated time after its plant steps, s. After a status other than :data:`TICK_OK`
        the run is over. :meth:`reset_to_keyframe` puts the plant back at the start.

        Args:
            record: ``record(t_s, command, tick_info, push_N, root, r00, r10, r22)`` after the
                controller, before the plant steps (:class:`~amlip_qp.sim.loop.run_log.TickLog`): ``root``
                the measured base's ``(q, v)`` (a list, empty without a floating base), ``r00, r10,
                r22`` the base's rotation entries at the last plant step's start.
            on_tick: ``on_tick(t_after_s, data)`` after the plant steps unless they diverged; it
                must not modify ``data``.
            stamp: Takes the tick's clock stamps (ns): its start, the controller's start and end,
                MuJoCo's start and end, its end.
        """
        m, d, ctrl = self.model, self.data, self.controller
        ctrl.reset()
        self.push_schedule.reset()
        # Hoisted lookups: views into MjData stay valid across mj_step.
        plant, ctrl_filter, command_fn = self.plant, self.ctrl_filter, self.command_fn
        read_state, sense, push_force = plant.array_reader(d), self.sensors.bind(d, self.true_base), self.push_force
        read_next = plant.compiled_reader(d)  # as generated C, after each tick's steps for the next (or None)
        add_noise = None if self.noise is None else self._add_noise
        write_ctrl = plant.ctrl_writer(d, compiled=ctrl_filter is None)  # with a filter: apply_ctrl
        ctrl_from_tau, apply_ctrl, ctrl_step = plant.ctrl_from_tau, plant.apply_ctrl, ctrl.step
        step, plant_steps, dt_s, qpos = mujoco.mj_step, range(self.substeps), self.dt_s, d.qpos
        later_steps = range(self.substeps - 1)  # the plant steps after a tick's first
        xpos_b, xmat_b, xfrc_b = d.xpos[self._base_body], d.xmat[self._base_body], d.xfrc_applied[self._base_body, :3]
        pushes, no_push = bool(self.pushes), np.zeros(3)
        if not pushes:
            xfrc_b[:] = no_push  # and so it stays
        warn_number, warn_idx = d.warning.number, [int(w) for w in _DIVERGENCE_WARNINGS]
        warn_number[warn_idx] = 0  # an earlier run's divergence on this data must not hide one of this run
        warn_all0 = warn_number.tolist()
        perf_ns, acos, isfinite = time.perf_counter_ns, math.acos, math.isfinite
        stamp_row = stamp or (lambda row: None)
        ground = self.ground_height_m  # None on flat ground: the height is z itself
        z0 = float(xpos_b[2]) if ground is None else float(xpos_b[2]) - ground(float(xpos_b[0]), float(xpos_b[1]))
        min_z, max_tilt = self.fall.min_height_fraction * z0, self.fall.max_tilt_rad
        # Above this cosine the tilt is surely not over max_tilt (acos decreases; its error << the margin).
        upright_cos = math.cos(min(max(max_tilt, 0.0), math.pi)) + 1e-12
        t_next = float(d.time)
        state = None  # this tick's (q, v, root) if read already (after the last tick's plant steps)
        qpos_list = qpos.tolist()
        total = sum(qpos_list)

        def tick() -> tuple[int, float, float]:
            nonlocal t_next, state, qpos_list, total, warn_all0
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
            if add_noise is not None:
                add_noise(q, v)
            meas = sense(t, q, v)
            t_c0 = perf_ns()
            info = ctrl_step(meas, cmd)
            t_c1 = perf_ns()
            tau = info.tau_Nm
            if ctrl_filter is None:
                write_ctrl(tau)
            else:  # e.g. an actuator delay
                apply_ctrl(d, ctrl_filter(ctrl_from_tau(tau)))
            if pushes:
                push = push_force(t, info.phase)
                xfrc_b[:] = push
            else:
                push = no_push
            if record is not None:
                record(t, cmd, info, push, root, r00, r10, r22)
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
                stamp_row((t_tick, t_c0, t_c1, t_m0, t_m1, perf_ns()))
                return TICK_DIVERGED, t, t
            warn_all0 = warn_all
            if on_tick is not None:
                on_tick(t_next, d)
            # A finite sum implies finite entries (NaN and inf propagate); only if not, look closer.
            if read_next is None:  # the next tick's read_state takes the list and its sum
                qpos_list = qpos.tolist()
                state, total = None, sum(qpos_list)
            else:  # the next tick's state, and the sum of qpos and qvel
                state, total = read_next()
            tilted = r22 < upright_cos and acos(max(-1.0, min(1.0, r22))) > max_tilt
            fallen = z < min_z or tilted or (not isfinite(total) and not np.all(np.isfinite(qpos)))
            stamp_row((t_tick, t_c0, t_c1, t_m0, t_m1, perf_ns()))
            return (TICK_FELL if fallen else TICK_OK), t, t_next

        return tick

    def reset_to_keyframe(self) -> None:
        """Put the plant back at its start: :attr:`data` (the same object) to the keyframe, forwarded.

        The next run (:meth:`run`, or a new :meth:`ticker`) starts from it as from a new
        :class:`Simulation`'s. The sensors' and the actuator delay's own state go on.
        """
        if self._keyframe_id < 0:
            mujoco.mj_resetData(self.model, self.data)
        else:
            mujoco.mj_resetDataKeyframe(self.model, self.data, self._keyframe_id)
        mujoco.mj_forward(self.model, self.data)
