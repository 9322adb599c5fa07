"""The :class:`~amlip_qp.sim.scenarios.scenarios.Scenario` of a walk's options: the one constructor of ``walk``'s
scenario, for the command line and a sweep cell alike.

The options (:class:`~amlip_qp.sim.scenarios.options.WalkOptions`, their
values already checked) start from a named scenario or a steady walk; every
option given overrides it. The result is checked against the robot's bounds.
"""

from __future__ import annotations

import math
from dataclasses import replace

from amlip_qp.exceptions import InputError
from amlip_qp.profiles import DEFAULT_ROBOT, NO_SHAPING, get_profile
from amlip_qp.sim.loop.run_types import PlantSetting, Push
from amlip_qp.sim.scenarios.named import get_scenario
from amlip_qp.sim.scenarios.options import WalkOptions
from amlip_qp.sim.scenarios.scenarios import Scenario, check_scenario
from amlip_qp.sim.scenarios.speed_profile import SpeedProfile
from amlip_qp.sim.world.plant_modifiers import parse_payload
from amlip_qp.sim.world.terrain import parse_terrain

#: Simulated time of a walk without a scenario or a duration, s.
DEFAULT_WALK_DURATION_S = 10.0


def scenario_from_options(options: WalkOptions) -> Scenario:
    """The scenario of ``options``: ``options.scenario`` (or a steady walk) with every option given applied.

    Speeds are m/s, the turn rate deg/s (converted to rad/s here, once); a
    turn rate turns from the start and keeps turning. Pushes are added to the
    scenario's.

    Raises:
        InputError: An unknown scenario, a robot that contradicts it, a command,
            duration or push outside the robot's bounds
            (:func:`~amlip_qp.sim.scenarios.scenarios.check_scenario`), or a bad
            plant setting (:func:`setting_from_options`).
    """
    o = options
    if o.scenario is not None:
        base = get_scenario(o.scenario)
        if o.robot is not None and o.robot != base.robot:
            raise InputError(f"scenario {base.name!r} is for {base.robot}, but --robot {o.robot} was given")
    else:
        base = Scenario("custom", o.robot or DEFAULT_ROBOT, DEFAULT_WALK_DURATION_S)
    changes: dict = {}
    if o.speed_profile is not None:
        changes["vx"] = SpeedProfile.parse(o.speed_profile)
    elif o.vx is not None:
        changes["vx"] = SpeedProfile.constant(o.vx)
    if o.vy is not None:
        changes["vy_mps"] = o.vy
    if o.turn_rate is not None:
        changes["turn_rate_radps"] = math.radians(o.turn_rate)
        changes["turn_start_s"] = 0.0
        changes["turn_angle_rad"] = math.inf
    if o.duration is not None:
        changes["duration_s"] = o.duration
    if o.push:
        changes["pushes"] = tuple(base.pushes) + tuple(Push(t, f, d) for t, f, d in o.push)
    if o.no_command_shaping:
        changes["shaping"] = NO_SHAPING
    elif o.accel_limit is not None:
        shaping = base.shaping or get_profile(base.robot).shaping
        changes["shaping"] = replace(shaping, vx_accel_mps2=o.accel_limit, vy_accel_mps2=o.accel_limit)
    setting = setting_from_options(o, base.setting)
    if setting != base.setting:
        changes["setting"] = setting
    if changes and base.name != "custom":
        changes["name"] = f"{base.name}+options"
    scenario = base.with_(**changes) if changes else base
    check_scenario(scenario)
    return scenario


def setting_from_options(options: WalkOptions, base: PlantSetting) -> PlantSetting:
    """``base`` (a scenario's setting, its IMU mounting kept) with the options' plant, sensors, estimator,
    terrain and plant modifiers applied.

    Raises:
        InputError: ``noise`` with robot sensors, a malformed payload or terrain, or
            a nonsensical modifier value (one line saying what to fix).
    """
    o = options
    mods: dict = {}
    if o.plant_mass_scale is not None:
        mods["mass_scale"] = o.plant_mass_scale
    if o.payload is not None:
        mods["payload_kg"], mods["payload_pos_m"] = parse_payload(o.payload)
    if o.plant_spring_scale is not None:
        mods["spring_scale"] = o.plant_spring_scale
    if o.friction is not None:
        mods["friction"] = o.friction
    if o.limb_collisions:
        mods["limb_collisions"] = True
    if o.actuator_delay is not None:
        mods["actuator_delay_ticks"] = o.actuator_delay
    terrain = base.terrain
    if o.terrain is not None:
        terrain = parse_terrain(o.terrain).text
    setting = PlantSetting(
        plant=base.plant if o.plant is None else o.plant,
        sensors=base.sensors if o.sensors is None else o.sensors,
        estimator=base.estimator if o.estimator is None else o.estimator,
        modifiers=replace(base.modifiers, **mods) if mods else base.modifiers,
        terrain=terrain,
        terrain_aware=base.terrain_aware if o.terrain_aware is None else o.terrain_aware,
        clearance_m=base.clearance_m if o.clearance is None else o.clearance,
        imu=base.imu,
    )
    if o.noise and setting.sensors != "ideal":
        raise InputError("--noise adds Gaussian noise to the ideal sensors; --sensors robot has its own: give one")
    return setting
