"""The plain data of a simulation run: pushes, sensor noise, fall criteria, the result.

:class:`~amlip_qp.sim.loop.harness.Simulation` takes :class:`Push`,
:class:`SensorNoise` and :class:`FallCriteria` and returns a :class:`RunResult`;
scenarios, summaries, plots and the comparison read these types without
needing the plant loop.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from amlip_qp.control.walking.controller import StepRecord
from amlip_qp.exceptions import InputError
from amlip_qp.profiles import ImuMount
from amlip_qp.sim.world.plant_modifiers import PlantModifiers

if TYPE_CHECKING:
    import mujoco

#: The control period of the closed loops (:func:`amlip_qp.sim.scenarios.factory.build_simulation`), s
#: (2 kHz, as on Cassie).
CONTROL_DT_S = 0.0005

#: Signature of the optional per-tick callback of :meth:`~amlip_qp.sim.loop.harness.Simulation.run`:
#: ``on_tick(t_s, data)`` with the simulated time after the tick's plant steps
#: (s) and MuJoCo's ``MjData`` (read only: do not modify it).
TickCallback = Callable[[float, "mujoco.MjData"], None]
#: Signature of the ``record`` hook of :meth:`~amlip_qp.sim.loop.harness.Simulation.ticker`:
#: ``record(t_s, command, tick_info, push_N, root, r00, r10, r22)``, called between the controller and the plant steps.
TickRecord = Callable[..., None]


@dataclass(frozen=True)
class Push:
    """A force on the base body.

    Attributes:
        t_s: Start time, s.
        force_N: World-frame force (fx, fy, fz), N.
        duration_s: How long it lasts, s.
        phase: ``None``: the push starts at ``t_s``. A number in [0, 1): the push starts at the
            first control tick at or after ``t_s`` where the controller's step phase reaches
            ``phase`` (crosses it from below, or a new step starts at or past it).
    """

    t_s: float
    force_N: tuple[float, float, float]
    duration_s: float
    phase: float | None = None

    def __post_init__(self):
        vals = (self.t_s, *self.force_N, self.duration_s)
        if len(self.force_N) != 3 or not all(math.isfinite(float(x)) for x in vals):
            raise InputError(f"a push needs finite t, (fx, fy, fz) and duration, got {self!r}")
        if self.t_s < 0 or self.duration_s <= 0:
            raise InputError(f"a push needs t >= 0 s and duration > 0 s, got t={self.t_s}, duration={self.duration_s}")
        if self.phase is not None and not 0.0 <= self.phase < 1.0:
            raise InputError(f"a push's step phase must be in [0, 1), got {self.phase!r}")

    @property
    def impulse_Ns(self) -> float:
        """Magnitude of the impulse, N s."""
        return float(np.linalg.norm(self.force_N) * self.duration_s)


@dataclass(frozen=True)
class SensorNoise:
    """Gaussian sensor noise (standard deviations), added to the measurement.

    Attributes:
        joint_pos_rad: Joint encoders, rad.
        joint_vel_radps: Joint velocities, rad/s.
        base_pos_m: Base position, m.
        base_rot_rad: Base orientation (small rotation vector), rad.
        base_lin_vel_mps: Base linear velocity, m/s.
        base_ang_vel_radps: Base angular velocity (IMU gyro), rad/s.
    """

    joint_pos_rad: float = 5e-4
    joint_vel_radps: float = 0.05
    base_pos_m: float = 1e-3
    base_rot_rad: float = 2e-3
    base_lin_vel_mps: float = 0.02
    base_ang_vel_radps: float = 0.02


@dataclass(frozen=True)
class PlantSetting:
    """The plant, sensors, base estimator and terrain of every run (``--plant``, ``--sensors``, ``--estimator``, ...).

    Attributes:
        plant: A plant name or MJCF path, or ``None``: each robot's own model.
        sensors: ``"ideal"`` or ``"robot"``.
        estimator: ``"truth"`` or ``"ekf"``.
        modifiers: Model mismatch applied to the plant (mass scale, payload,
            spring scale, friction, actuator delay); the defaults change nothing.
        terrain: The ``--terrain`` spec (:func:`amlip_qp.sim.world.terrain.parse_terrain`),
            ``"flat"``: the plant's floor.
        terrain_aware: The controller is given the terrain's height function
            (``--terrain-aware``); ``False``: blind, it feels the ground by contact only.
        clearance_m: Swing clearance ``z_cl`` of every step, m (``--clearance``);
            ``None``: the scenario's gait's.
        imu: Where the IMU sits in these runs (the plant's IMU site and the EKF's mounting);
            ``None``: where the robot's profile puts it (:attr:`~amlip_qp.robots.robot.Robot.imu_mount`).
    """

    plant: str | None = None
    sensors: str = "ideal"
    estimator: str = "truth"
    modifiers: PlantModifiers = field(default_factory=PlantModifiers)
    terrain: str = "flat"
    terrain_aware: bool = False
    clearance_m: float | None = None
    imu: ImuMount | None = None

    def __post_init__(self):
        c = self.clearance_m
        if c is not None and not (isinstance(c, (int, float)) and math.isfinite(c) and c >= 0.0):
            raise InputError(f"the swing clearance must be a finite height >= 0 m, got {c!r}")

    def describe(self) -> dict:
        """The setting as plain data for a summary (modifiers: only the non-default ones)."""
        return {
            "plant": self.plant,
            "sensors": self.sensors,
            "estimator": self.estimator,
            "modifiers": self.modifiers.describe(),
            "terrain": self.terrain,
            "terrain_aware": self.terrain_aware,
            "clearance_m": self.clearance_m,
        }


@dataclass(frozen=True)
class FallCriteria:
    """When a run counts as a fall.

    Attributes:
        min_height_fraction: Base height below this fraction of its initial value.
        max_tilt_rad: Base tilt (angle between its z axis and the world's) above this.
    """

    min_height_fraction: float = 0.6
    max_tilt_rad: float = math.radians(50.0)


@dataclass
class RunResult:
    """A finished simulation.

    Attributes:
        robot: Robot name.
        tracker: Tracker name.
        duration_s: Requested simulated time, s.
        sim_time_s: Simulated time reached (< duration after a fall), s.
        wall_time_s: Wall-clock time of the loop, s.
        fell: True if the fall criteria triggered.
        fall_time_s: When, or NaN.
        log: Name -> array with one row per control tick (see :meth:`~amlip_qp.sim.loop.harness.Simulation.run`).
        steps: The completed steps.
        tick_time_us: Controller wall time per tick, µs.
        mujoco_time_us: Wall time of MuJoCo's plant steps per tick, µs.
        harness_time_us: Wall time per tick of the rest of the loop (the harness's own:
            measurement, commands, controls, pushes, logging, checks), µs.
        fallback_ticks: Ticks that used the damped fallback torque.
        safe_mode_ticks: Ticks the controller spent in its safe mode after a diverged base estimate.
        estimator_divergences: How often the base estimate diverged.
        pushes: The pushes applied.
        info: Run metadata: ``output_names`` (the order of ``log["h"]``),
            ``actuator_names`` (the order of ``log["tau"]``), ``control_dt_s``,
            ``planar`` (True for a planar robot),
            ``seed``, ``noise`` (True if Gaussian noise was on), ``plant`` (its name or path),
            ``sensors`` (``"ideal"`` or ``"robot"``), ``estimator`` (the base estimator's name)
            and ``log`` (``"full"`` or ``"summary"``: which entries ``log`` has).
    """

    robot: str
    tracker: str
    duration_s: float
    sim_time_s: float
    wall_time_s: float
    fell: bool
    fall_time_s: float
    log: dict[str, np.ndarray]
    steps: list[StepRecord]
    tick_time_us: np.ndarray
    fallback_ticks: int
    safe_mode_ticks: int = 0
    estimator_divergences: int = 0
    pushes: tuple[Push, ...] = ()
    info: dict = field(default_factory=dict)
    mujoco_time_us: np.ndarray = field(default_factory=lambda: np.zeros(0))
    harness_time_us: np.ndarray = field(default_factory=lambda: np.zeros(0))
