"""A robot's named scenarios, built from its profile's tables.

A profile file holds the robot's scenarios as data (``docs/NEW_ROBOT.md``):

- ``[scenarios.KEY]``: one scenario, named ``ROBOT-KEY``. Keys: ``duration_s`` (required),
  ``description``, the forward speed as ``ramp = [V_MPS, RAMP_S]`` (0 m/s until 1 s, then up to
  ``V_MPS`` over ``RAMP_S`` seconds) or ``speed_profile = [[T_S, V_MPS], ...]``, ``vy_mps``,
  ``turn_rate_degps``, ``turn_start_s``, ``turn_angle_deg``, ``pushes = [{t_s, force_N,
  duration_s, phase}]``, a ``gait`` table (every :class:`~amlip_qp.profiles.GaitSettings`
  field), the terrain: ``terrain`` (a ``--terrain`` spec), ``terrain_aware``, ``clearance_m``, and
  ``setting``: the name of one of the ``[settings]``, whose plant, sensors, estimator and IMU the
  scenario runs on (it is then copied into no setting).
- ``[settings.NAME]``: a plant, sensor model and estimator (``plant``, ``sensors``,
  ``estimator``, ``description``), and where the IMU sits (``imu``: a table of the ``[imu]``
  keys, in place of the profile's ``[imu]``); every scenario on the robot's own model with ideal sensors
  (or those of its ``scenarios`` list of keys) gets a copy ``ROBOT-KEY-NAME`` in that setting.
- ``[mismatches]``: ``scenario`` names one scenario (a key, or a key with a setting suffix);
  each sub-table ``[mismatches.NAME]`` (plant modifiers: ``mass_scale``, ``payload_kg``,
  ``payload_pos_m``, ``spring_scale``, ``friction``, ``actuator_delay_ticks``, and a
  ``description``) gives a copy ``ROBOT-SCENARIO-NAME`` under that model mismatch.

The order: the plain scenarios, their copies in each setting, the mismatches, then the
scenarios with a terrain or a ``setting`` of their own. A key that is unknown or of the wrong type is a
:class:`~amlip_qp.exceptions.ProfileError` naming the file and the key.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import replace
from typing import Any

from amlip_qp.exceptions import InputError, ProfileError
from amlip_qp.profiles import GaitSettings, RobotProfile
from amlip_qp.profiles.reader import read_imu_table
from amlip_qp.sim.loop.run_types import PlantSetting, Push
from amlip_qp.sim.scenarios.scenarios import Scenario
from amlip_qp.sim.scenarios.speed_profile import SpeedProfile
from amlip_qp.sim.world.plant_modifiers import PlantModifiers

#: When a ``ramp`` starts, s.
RAMP_START_S = 1.0

_SCENARIO_KEYS = (
    "duration_s",
    "description",
    "ramp",
    "speed_profile",
    "vy_mps",
    "turn_rate_degps",
    "turn_start_s",
    "turn_angle_deg",
    "pushes",
    "gait",
    "terrain",
    "terrain_aware",
    "clearance_m",
    "setting",
)
_SETTING_KEYS = ("plant", "sensors", "estimator", "imu", "description", "scenarios")
_MODIFIER_KEYS = ("mass_scale", "payload_kg", "payload_pos_m", "spring_scale", "friction", "actuator_delay_ticks")
_PUSH_KEYS = ("t_s", "force_N", "duration_s", "phase")


class _Where:
    """Names the profile file and the key in an error."""

    def __init__(self, profile: RobotProfile, where: str):
        self.source, self.where = profile.source, where

    def fail(self, message: str) -> Any:
        raise ProfileError(f"{self.source}: {self.where}: {message}")

    def table(self, value: Any, known: tuple[str, ...]) -> Mapping[str, Any]:
        if not isinstance(value, Mapping):
            self.fail(f"must be a table, got {value!r}")
        unknown = [k for k in value if k not in known]
        if unknown:
            self.fail(f"unknown key {unknown[0]!r} (known: {', '.join(known)})")
        return value

    def number(self, key: str, value: Any) -> float:
        if isinstance(value, bool) or not isinstance(value, (int, float)) or math.isnan(value):
            self.fail(f"{key} must be a number, got {value!r}")
        return float(value)

    def numbers(self, key: str, value: Any, size: int | None = None) -> tuple[float, ...]:
        if not isinstance(value, list) or (size is not None and len(value) != size):
            self.fail(f"{key} must be a list of {size if size is not None else 'some'} numbers, got {value!r}")
        return tuple(self.number(key, v) for v in value)


def _speed(w: _Where, t: Mapping[str, Any]) -> SpeedProfile:
    if "ramp" in t and "speed_profile" in t:
        w.fail("give either ramp or speed_profile")
    if "ramp" in t:
        v_end, t_ramp = w.numbers("ramp", t["ramp"], 2)
        return SpeedProfile((0.0, RAMP_START_S, RAMP_START_S + t_ramp), (0.0, 0.0, v_end))
    if "speed_profile" in t:
        knots = t["speed_profile"]
        if not isinstance(knots, list) or not knots:
            w.fail(f"speed_profile must be a list of [t_s, v_mps] pairs, got {knots!r}")
        pairs = [w.numbers("speed_profile", k, 2) for k in knots]
        return SpeedProfile(tuple(p[0] for p in pairs), tuple(p[1] for p in pairs))
    return SpeedProfile.constant(0.0)


def _pushes(w: _Where, value: Any) -> tuple[Push, ...]:
    if not isinstance(value, list):
        w.fail(f"pushes must be a list of tables, got {value!r}")
    out = []
    for p in value:
        p = w.table(p, _PUSH_KEYS)
        fx, fy, fz = w.numbers("force_N", p.get("force_N"), 3)
        phase = p.get("phase")
        out.append(
            Push(
                w.number("t_s", p.get("t_s")),
                (fx, fy, fz),
                w.number("duration_s", p.get("duration_s")),
                None if phase is None else w.number("phase", phase),
            )
        )
    return tuple(out)


def _scenario(profile: RobotProfile, key: str, value: Any):
    w = _Where(profile, f"scenarios.{key}")
    t = w.table(value, _SCENARIO_KEYS)
    if "duration_s" not in t:
        w.fail("duration_s is required")
    gait = None
    if "gait" in t:
        g = w.table(t["gait"], ("step_time_s", "com_height_m", "clearance_m", "step_width_m"))
        gait = GaitSettings(**{k: w.number(k, v) for k, v in g.items()})
    aware = t.get("terrain_aware", False)
    if not isinstance(aware, bool):
        w.fail(f"terrain_aware must be true or false, got {aware!r}")
    clearance = t.get("clearance_m")
    setting = PlantSetting(
        terrain=str(t.get("terrain", "flat")),
        terrain_aware=aware,
        clearance_m=None if clearance is None else w.number("clearance_m", clearance),
    )
    try:
        return Scenario(
            f"{profile.name}-{key}",
            profile.name,
            w.number("duration_s", t["duration_s"]),
            vx=_speed(w, t),
            vy_mps=w.number("vy_mps", t.get("vy_mps", 0.0)),
            turn_rate_radps=math.radians(w.number("turn_rate_degps", t.get("turn_rate_degps", 0.0))),
            turn_start_s=w.number("turn_start_s", t.get("turn_start_s", 0.0)),
            turn_angle_rad=math.radians(w.number("turn_angle_deg", t.get("turn_angle_deg", math.inf))),
            pushes=_pushes(w, t.get("pushes", [])),
            gait=gait,
            setting=setting,
            description=str(t.get("description", "")),
        )
    except InputError as exc:
        return w.fail(str(exc))


def _setting(profile: RobotProfile, name: str, value: Any) -> tuple[PlantSetting, str, tuple[str, ...] | None]:
    w = _Where(profile, f"settings.{name}")
    t = w.table(value, _SETTING_KEYS)
    keys = t.get("scenarios")
    if keys is not None and (not isinstance(keys, list) or any(k not in profile.scenarios for k in keys)):
        w.fail(f"scenarios must be a list of the robot's scenario keys, got {keys!r}")
    imu = None if "imu" not in t else read_imu_table(profile.source, f"settings.{name}.imu", t["imu"])
    try:
        setting = PlantSetting(
            plant=t.get("plant"), sensors=t.get("sensors", "ideal"), estimator=t.get("estimator", "truth"), imu=imu
        )
    except InputError as exc:
        return w.fail(str(exc))
    return setting, str(t.get("description", name)), None if keys is None else tuple(keys)


def _modifiers(profile: RobotProfile, name: str, value: Any) -> tuple[PlantModifiers, str]:
    if not isinstance(value, Mapping):
        known = ", ".join(("scenario", *_MODIFIER_KEYS, "description"))
        _Where(profile, "mismatches").fail(f"{name} must be a table of plant modifiers (known: {known})")
    w = _Where(profile, f"mismatches.{name}")
    t = w.table(value, (*_MODIFIER_KEYS, "description"))
    kwargs: dict[str, Any] = {}
    for k, v in t.items():
        if k == "description":
            continue
        if k == "payload_pos_m":
            kwargs[k] = w.numbers(k, v, 3)
        elif k == "actuator_delay_ticks":
            if isinstance(v, bool) or not isinstance(v, int):
                w.fail(f"actuator_delay_ticks must be a whole number, got {v!r}")
            kwargs[k] = v
        else:
            kwargs[k] = w.number(k, v)
    try:
        return PlantModifiers(**kwargs), str(t.get("description", name))
    except InputError as exc:
        return w.fail(str(exc))


def profile_scenarios(profile: RobotProfile) -> list:
    """The named :class:`~amlip_qp.sim.scenarios.scenarios.Scenario` objects of ``profile`` (module doc), in order.

    Raises:
        ProfileError: A key that is unknown or of the wrong type (naming the file and the key).
    """
    plain: list[Scenario] = []
    terrain: list[Scenario] = []
    own: dict[str, str] = {}  # scenario name -> the setting it runs on
    for key, value in profile.scenarios.items():
        sc = _scenario(profile, key, value)
        if value.get("setting") is not None:
            own[sc.name] = value["setting"]
            terrain.append(sc)
        else:
            (plain if sc.setting == PlantSetting() else terrain).append(sc)
    settings = {name: _setting(profile, name, value) for name, value in profile.settings.items()}
    for i, sc in enumerate(terrain):
        if sc.name not in own:
            continue
        if own[sc.name] not in settings:
            where = _Where(profile, f"scenarios.{sc.name.removeprefix(profile.name + '-')}")
            known = ", ".join(settings) or "none"
            where.fail(f"setting must name one of the [settings] ({known}), got {own[sc.name]!r}")
        setting, text, _ = settings[own[sc.name]]
        on = replace(
            sc.setting, plant=setting.plant, sensors=setting.sensors, estimator=setting.estimator, imu=setting.imu
        )
        terrain[i] = sc.with_(setting=on, description=f"{sc.description}; {text}")
    out = list(plain)
    by_name = {s.name: s for s in plain}
    for name in profile.settings:
        setting, text, keys = settings[name]
        chosen = {f"{profile.name}-{k}" for k in keys} if keys is not None else None
        for s in plain:
            if chosen is not None and s.name not in chosen:
                continue
            copy = s.with_(name=f"{s.name}-{name}", setting=setting, description=f"{s.description}; {text}")
            out.append(copy)
            by_name[copy.name] = copy
    if profile.mismatches:
        w = _Where(profile, "mismatches")
        table = dict(profile.mismatches)
        base_key = table.pop("scenario", None)
        base = by_name.get(f"{profile.name}-{base_key}") if isinstance(base_key, str) else None
        if base is None:
            w.fail(f"scenario must name one of the robot's scenarios, got {base_key!r}")
        assert base is not None
        for name, value in table.items():
            mods, text = _modifiers(profile, name, value)
            out.append(
                base.with_(
                    name=f"{base.name}-{name}",
                    setting=replace(base.setting, modifiers=mods),
                    description=f"{base.description}; {text}",
                )
            )
    return out + terrain
