"""Tests of the PBC gains (amlip_qp.control.pbc.gains): validation, schedule, the registry."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from amlip_qp.control.pbc.gains import PBCGains, default_gains
from amlip_qp.exceptions import InputError
from amlip_qp.profiles import get_profile
from amlip_qp.robots import load_robot
from robot_states import tuned_config

CASSIE_ACHILLES = tuned_config("cassie", "pbc").spring_model_linkage
CASSIE_GAINS = tuned_config("cassie", "pbc")
RABBIT_GAINS = tuned_config("rabbit", "pbc")


def test_gains_validation_and_swing_schedule():
    with pytest.raises(InputError):
        PBCGains(kp_stance_ps2=-1.0)
    with pytest.raises(InputError):
        PBCGains(swing_start_fraction=2.0)
    with pytest.raises(InputError, match="hip_yaw_feedback"):
        PBCGains(hip_yaw_feedback=1.5)
    with pytest.raises(InputError):
        PBCGains(hip_yaw_feedback=-0.5)
    with pytest.raises(InputError, match="swing_ankle_gain_scale"):
        PBCGains(swing_ankle_gain_scale=0.0)
    g = PBCGains(swing_start_fraction=0.2, swing_ramp_phase=0.5, touchdown_gain_drop=0.5)
    assert g.swing_scale(0.0, 0.0) == pytest.approx(0.2)
    assert g.swing_scale(0.25, 0.0) == pytest.approx(0.6)
    assert g.swing_scale(1.0, 1.0) == pytest.approx(0.5)
    assert np.isfinite(g.swing_scale(float("nan"), float("nan")))


@pytest.mark.parametrize("name, expected", [("cassie", CASSIE_GAINS), ("rabbit", RABBIT_GAINS)])
def test_bundled_robots_get_their_profiles_gains(name, expected):
    robot = load_robot(name)
    assert robot.profile is get_profile(name)
    assert get_profile(name).tracker_config("pbc") is expected
    assert default_gains(robot) is expected
    # Cassie's legs have springs: stiffer stance gains (they hold the CoM height through the
    # springs, docs/TUNING.md), torso compensation, the spring model
    assert (expected.kp_stance_ps2 > expected.kp_swing_ps2) == (name == "cassie")
    assert expected.spring_model_offset == (name == "cassie")


@pytest.mark.parametrize("name, expected", [("cassie", CASSIE_GAINS), ("rabbit", RABBIT_GAINS)])
def test_a_model_without_profile_gets_the_gains_of_the_robot_it_resembles(name, expected):
    """An MJCF file that is not a bundled robot: Cassie's gains with springs, Rabbit's without."""
    robot = dataclasses.replace(load_robot(name), profile=None)
    assert default_gains(robot) is expected


def test_a_profile_table_with_an_unknown_key_is_a_typed_error_naming_it():
    robot = load_robot("rabbit")
    profile = dataclasses.replace(robot.profile, trackers={"pbc": {"kp_stance": 400.0}})
    with pytest.raises(InputError, match=r"\[trackers.pbc\]: unknown key 'kp_stance' \(known: .*kp_stance_ps2"):
        default_gains(dataclasses.replace(robot, profile=profile))
    profile = dataclasses.replace(robot.profile, trackers={"pbc": {"kp_stance_ps2": "stiff"}})
    with pytest.raises(InputError, match="kp_stance_ps2 must be a number, got 'stiff'"):
        default_gains(dataclasses.replace(robot, profile=profile))


def test_spring_model_settings_are_validated():
    with pytest.raises(InputError, match="spring_model_load"):
        PBCGains(spring_model_load="encoders")
    with pytest.raises(InputError, match="AchillesLinkage"):
        PBCGains(spring_model_linkage=(1.36, 0.81, 1250.0))
    # Cassie's spring model: the robot's achilles linkage under its weight (docs/TUNING.md)
    assert CASSIE_GAINS.spring_model_linkage is CASSIE_ACHILLES and CASSIE_GAINS.spring_model_load == "weight"
    assert RABBIT_GAINS.spring_model_linkage is None
