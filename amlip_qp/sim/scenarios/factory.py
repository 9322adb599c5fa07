"""Assemble a closed loop (robot, tracker, controller, plant) from names.

A tracker given by name is made by the trackers' registry
(:mod:`amlip_qp.control.registry`).
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Sequence

import numpy as np

from amlip_qp.control import registry
from amlip_qp.control.tracker import Tracker
from amlip_qp.control.walking.controller import WalkingController
from amlip_qp.control.walking.stage_timer import StageTimer
from amlip_qp.estimation import make_base_estimator
from amlip_qp.estimation.invariant_ekf import noise_from_table
from amlip_qp.exceptions import InputError
from amlip_qp.robots import load_robot
from amlip_qp.robots.robot import Robot
from amlip_qp.sim.loop.harness import Simulation
from amlip_qp.sim.loop.run_types import CONTROL_DT_S, PlantSetting, RunResult, SensorNoise, TickCallback
from amlip_qp.sim.scenarios.scenarios import Scenario
from amlip_qp.sim.world.actuator_delay import ActuatorDelay
from amlip_qp.sim.world.imu_site import imu_mount_edit
from amlip_qp.sim.world.plant import Plant, SpecEdit
from amlip_qp.sim.world.plant_loader import load_plant
from amlip_qp.sim.world.terrain import parse_terrain, terrain_edit
from amlip_qp.sim.world.terrain_rays import ground_height_function

#: The base estimators of ``--estimator``: the simulator's truth, or the contact-aided invariant EKF.
ESTIMATORS: tuple[str, ...] = ("truth", "ekf")


@functools.cache
def load(robot_name: str) -> Robot:
    """The :class:`~amlip_qp.robots.robot.Robot` named ``robot_name`` (loaded once per process)."""
    return load_robot(robot_name)


def check_estimator(name: str) -> str:
    """``name`` if it is a base estimator of :data:`ESTIMATORS`; InputError naming them otherwise."""
    if name not in ESTIMATORS:
        raise InputError(f"unknown estimator {name!r}; known: {', '.join(ESTIMATORS)}")
    return name


def setting_edits(setting: PlantSetting, robot: Robot) -> list[SpecEdit]:
    """The spec edits of a plant setting, in order: the plant modifiers', the terrain's (none on flat),
    then the setting's IMU site (none without ``setting.imu``: :func:`~amlip_qp.sim.world.plant_loader.load_plant`
    then adds the profile's).

    Raises:
        InputError: A malformed ``setting.terrain`` (:func:`~amlip_qp.sim.world.terrain.parse_terrain`).
    """
    edits = setting.modifiers.spec_edits(robot.base_body)
    terrain = parse_terrain(setting.terrain)
    if not terrain.is_flat:
        edits.append(terrain_edit(terrain))
    if setting.imu is not None:
        edits.append(imu_mount_edit(setting.imu, robot.base_body))
    return edits


def _with_delay(
    ticks: int, nu: int, ctrl_filter: Callable[[np.ndarray], np.ndarray] | None
) -> Callable[[np.ndarray], np.ndarray] | None:
    """``ctrl_filter`` preceded by an actuator delay of ``ticks`` control ticks (none for 0)."""
    if ticks == 0:
        return ctrl_filter
    delay = ActuatorDelay(ticks, nu)
    if ctrl_filter is None:
        return delay.push
    then = ctrl_filter
    return lambda ctrl: then(delay.push(ctrl))


def build_simulation(
    scenario: Scenario,
    tracker: str | Tracker,
    seed: int = 0,
    noise: SensorNoise | None = None,
    planner_backend: str = "c",
    plant: str | Plant | None = None,
    sensors: str | None = None,
    estimator: str | None = None,
    plant_edits: Sequence[SpecEdit] = (),
    ctrl_filter: Callable[[np.ndarray], np.ndarray] | None = None,
    planner: str = "one-step",
    stage_timer: StageTimer | None = None,
) -> Simulation:
    """The :class:`Simulation` of ``scenario`` with ``tracker`` (a name or an instance).

    Args:
        scenario: Robot, commands, pushes, duration and command shaping.
        tracker: ``"pbc"``, ``"qp"``, or a ready :class:`Tracker` instance
            (e.g. a test stand-in; it must be built for the scenario's robot).
        seed: Seed of the sensor-noise generators.
        noise: Gaussian noise on the ideal sensors, or ``None`` for exact measurements.
        planner_backend: ``"c"`` (generated kernels) or ``"numpy"``.
        plant: A plant name of the robot or an MJCF path (loaded with
            :func:`~amlip_qp.sim.world.plant_loader.load_plant`), a loaded
            :class:`~amlip_qp.sim.world.plant.Plant`, or ``None``: the scenario's
            (``scenario.setting.plant``; ``None`` there: the robot's own model).
        sensors: ``"ideal"`` or ``"robot"`` (:mod:`~amlip_qp.sim.sensing.sensors`); ``None``: the scenario's.
        estimator: The controller's base estimator, ``"truth"`` or ``"ekf"``
            (:func:`amlip_qp.estimation.make_base_estimator`); ``None``: the scenario's.
        plant_edits: Further changes of the plant's model before it is compiled,
            after the scenario's plant modifiers and terrain (:func:`setting_edits`),
            for a plant given by name or path.
        ctrl_filter: Applied to the actuator controls before they reach the plant,
            after the scenario's actuator delay; see :class:`Simulation`.
        planner: The controller's foot-placement planner, ``"one-step"`` or ``"mpc"``
            (``WalkingController(planner=...)``).
        stage_timer: Receives the controller's stage times per tick
            (``WalkingController(stage_timer=...)``); ``None``: no timing.
    """
    setting = scenario.setting
    plant = setting.plant if plant is None else plant
    sensors = setting.sensors if sensors is None else sensors
    estimator = check_estimator(setting.estimator if estimator is None else estimator)
    robot = load(scenario.robot)
    edits = [*setting_edits(setting, robot), *plant_edits]
    terrain = parse_terrain(setting.terrain)
    if isinstance(plant, Plant):
        if edits:
            raise InputError(
                "plant edits and modifiers change a plant before it is compiled: give the plant by name or path"
            )
        the_plant = plant
    else:
        the_plant = load_plant(robot.name if plant is None else plant, robot, edits=edits)
    ctrl_filter = _with_delay(setting.modifiers.actuator_delay_ticks, len(robot.actuated.names), ctrl_filter)
    trk = registry.make_tracker(tracker, robot) if isinstance(tracker, str) else tracker
    if not isinstance(trk, Tracker):
        raise InputError(f"tracker must be a name or a Tracker instance, got {type(trk).__name__}")
    options: dict = {}
    if estimator != "truth":  # the truth needs no estimator object: the harness gives the true base
        table = robot.profile.estimator if robot.profile is not None else {}
        imu = robot.imu_mount if setting.imu is None else setting.imu
        ekf_noise = noise_from_table(table) if table else None
        options["base_estimator"] = make_base_estimator(estimator, robot, CONTROL_DT_S, imu, ekf_noise)
    if setting.terrain_aware:
        options["terrain_height_fn"] = ground_height_function(the_plant, terrain)
    elif not terrain.is_flat:
        options["ground_mode"] = "blind"
    controller = WalkingController(
        robot,
        trk,
        dt_s=CONTROL_DT_S,
        planner_backend=planner_backend,
        command_shaping=scenario.shaping,
        planner=planner,
        stage_timer=stage_timer,
        **options,
    )
    return Simulation(
        robot,
        controller,
        scenario.command_function(),
        pushes=scenario.pushes,
        noise=noise,
        seed=seed,
        plant=the_plant,
        sensors=sensors,
        estimator=estimator,
        ctrl_filter=ctrl_filter,
        ground_height_m=None if terrain.is_flat else terrain.height_m,
        terrain=setting.terrain,
    )


def run_scenario(
    scenario: Scenario,
    tracker: str | Tracker,
    seed: int = 0,
    noise: SensorNoise | None = None,
    progress: bool = False,
    on_tick: TickCallback | None = None,
    plant: str | Plant | None = None,
    sensors: str | None = None,
    estimator: str | None = None,
    plant_edits: Sequence[SpecEdit] = (),
    ctrl_filter: Callable[[np.ndarray], np.ndarray] | None = None,
    log: str = "full",
    planner: str = "one-step",
) -> RunResult:
    """Build and run ``scenario`` for its full duration (see :func:`build_simulation`).

    ``log``: ``"full"`` or ``"summary"`` (only what :func:`~amlip_qp.sim.reports.summary.summarize` reads;
    the same trajectory), see :meth:`Simulation.run`.
    """
    sim = build_simulation(
        scenario,
        tracker,
        seed=seed,
        noise=noise,
        plant=plant,
        sensors=sensors,
        estimator=estimator,
        plant_edits=plant_edits,
        ctrl_filter=ctrl_filter,
        planner=planner,
    )
    result = sim.run(scenario.duration_s, progress=progress, on_tick=on_tick, log=log)
    result.info["scenario"] = scenario.name
    result.info["modifiers"] = scenario.setting.modifiers.describe()
    return result
