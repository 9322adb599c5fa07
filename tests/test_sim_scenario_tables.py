"""amlip_qp.sim.scenarios.scenario_tables: a profile's scenarios, settings and mismatches as Scenario objects."""

import dataclasses
import math

import pytest

from amlip_qp.exceptions import ProfileError
from amlip_qp.profiles import ImuMount, get_profile
from amlip_qp.sim.loop.run_types import PlantSetting
from amlip_qp.sim.scenarios.named import SCENARIOS
from amlip_qp.sim.scenarios.scenario_tables import profile_scenarios


def _with(profile, **tables):
    return dataclasses.replace(profile, **tables)


def test_a_table_gives_the_scenario_it_describes():
    profile = _with(
        get_profile("h1"),
        scenarios={
            "walk": {
                "duration_s": 9.0,
                "ramp": [0.8, 2.0],
                "vy_mps": 0.1,
                "turn_rate_degps": 10.0,
                "turn_start_s": 2.0,
                "turn_angle_deg": 45.0,
                "pushes": [{"t_s": 4.0, "force_N": [50.0, 0.0, 0.0], "duration_s": 0.1, "phase": 0.5}],
                "gait": {"step_time_s": 0.3, "com_height_m": 0.8, "clearance_m": 0.1, "step_width_m": 0.2},
                "description": "a walk",
            },
            "hill": {
                "duration_s": 5.0,
                "speed_profile": [[0.0, 0.0], [2.0, 0.5]],
                "terrain": "slope:5",
                "terrain_aware": True,
                "clearance_m": 0.12,
            },
            "hill-ekf": {"duration_s": 5.0, "terrain": "slope:5", "clearance_m": 0.12, "setting": "ekf"},
        },  # fmt: skip
        settings={"ekf": {"sensors": "robot", "estimator": "ekf", "description": "EKF"}},
        mismatches={"scenario": "walk-ekf", "heavy": {"mass_scale": 1.1, "description": "10 % heavier"}},
    )
    out = {s.name: s for s in profile_scenarios(profile)}
    # terrain and own settings last, no copy
    assert list(out) == ["h1-walk", "h1-walk-ekf", "h1-walk-ekf-heavy", "h1-hill", "h1-hill-ekf"]
    assert out["h1-hill-ekf"].setting == PlantSetting(
        sensors="robot", estimator="ekf", terrain="slope:5", clearance_m=0.12
    )
    assert out["h1-hill-ekf"].description == "; EKF"
    walk = out["h1-walk"]
    assert walk.robot == "h1" and walk.duration_s == 9.0 and walk.description == "a walk"
    assert walk.vx.times_s == (0.0, 1.0, 3.0) and walk.vx.speeds_mps == (0.0, 0.0, 0.8)
    assert walk.turn_rate_radps == math.radians(10.0) and walk.turn_angle_rad == math.radians(45.0)
    assert walk.pushes[0].force_N == (50.0, 0.0, 0.0) and walk.pushes[0].phase == 0.5
    assert walk.gait is not None and walk.gait.step_time_s == 0.3
    assert out["h1-walk-ekf"].setting == PlantSetting(sensors="robot", estimator="ekf")
    assert out["h1-walk-ekf"].description == "a walk; EKF"
    heavy = out["h1-walk-ekf-heavy"]
    assert heavy.setting.modifiers.mass_scale == 1.1 and heavy.setting.estimator == "ekf"
    hill = out["h1-hill"]
    assert (hill.setting.terrain, hill.setting.terrain_aware, hill.setting.clearance_m) == ("slope:5", True, 0.12)


def test_a_setting_may_put_the_imu_elsewhere():
    imu = {"body": "torso_link", "pos_m": [0.0, 0.0, 0.3], "quat_wxyz": [0.0, 1.0, 0.0, 0.0]}
    profile = _with(get_profile("h1"), settings={"t": {"sensors": "robot", "estimator": "ekf", "imu": imu}})
    out = {s.name: s for s in profile_scenarios(profile)}
    mount = ImuMount(body="torso_link", pos_m=(0.0, 0.0, 0.3), quat_wxyz=(0.0, 1.0, 0.0, 0.0))
    assert out["h1-1mps-t"].setting == PlantSetting(sensors="robot", estimator="ekf", imu=mount)
    assert SCENARIOS["g1-1mps-ekf-torso-imu"].setting.imu == ImuMount(
        body="torso_link", pos_m=(-0.03959, -0.00224, 0.14792)
    )


def test_a_setting_copies_only_the_scenarios_it_lists():
    names = [n for n in SCENARIOS if n.startswith("h1-") and n.endswith("-ekf")]
    assert names == ["h1-1mps-ekf"]
    assert SCENARIOS["h1-1mps-ekf"].vx == SCENARIOS["h1-1mps"].vx


@pytest.mark.parametrize(
    "tables, message",
    [
        ({"scenarios": {"x": {"duration_s": 1.0, "speed": 1.0}}}, "scenarios.x: unknown key 'speed'"),
        ({"scenarios": {"x": {"ramp": [1.0, 2.0]}}}, "scenarios.x: duration_s is required"),
        ({"scenarios": {"x": {"duration_s": "long"}}}, "scenarios.x: duration_s must be a number, got 'long'"),
        ({"scenarios": {"x": {"duration_s": -1.0}}}, "scenarios.x: scenario duration must be a positive number"),
        ({"scenarios": {"x": {"duration_s": 1.0, "ramp": [1.0]}}}, "ramp must be a list of 2 numbers"),
        (
            {"scenarios": {"x": {"duration_s": 1.0, "ramp": [1.0, 1.0], "speed_profile": [[0.0, 0.0]]}}},
            "give either ramp or speed_profile",
        ),
        ({"settings": {"cc": {"plant": "p", "noise": 1}}}, "settings.cc: unknown key 'noise'"),
        (
            {"scenarios": {"x": {"duration_s": 1.0, "setting": "cc"}}, "settings": {"ekf": {"estimator": "ekf"}}},
            "scenarios.x: setting must name one of the [settings] (ekf), got 'cc'",
        ),
        ({"settings": {"cc": {"scenarios": ["nothing"]}}}, "settings.cc: scenarios must be a list of the robot's"),
        ({"settings": {"t": {"imu": {"quat_wxyz": [1.0, 0.0, 0.2, 0.0]}}}}, "settings.t.imu.quat_wxyz: must be a unit"),
        ({"settings": {"t": {"imu": {"pos_m": [0.1]}}}}, "settings.t.imu.pos_m: must be a list of 3 numbers (m)"),
        ({"settings": {"t": {"imu": {"frame": "x"}}}}, "settings.t.imu: unknown key 'frame' (known here: body"),
        ({"mismatches": {"scenario": "nothing"}}, "mismatches: scenario must name one of the robot's scenarios"),
        ({"mismatches": {"scenario": "1mps", "m": {"mass": 2.0}}}, "mismatches.m: unknown key 'mass'"),
    ],
)
def test_a_bad_table_is_named_with_its_file_and_key(tables, message):
    profile = _with(get_profile("h1"), **tables)
    with pytest.raises(ProfileError) as info:
        profile_scenarios(profile)
    assert str(info.value).startswith(str(profile.source)) and message in str(info.value), str(info.value)
