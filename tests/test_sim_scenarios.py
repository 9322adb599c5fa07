"""Scenario catalogue and speed-profile parsing."""

from __future__ import annotations

import math

import pytest

from amlip_qp.exceptions import InputError
from amlip_qp.profiles import PROFILES
from amlip_qp.sim.scenarios import SCENARIOS, Scenario, SpeedProfile, get_scenario


def test_speed_profile_parse_and_interpolate():
    p = SpeedProfile.parse("0:0,5:2.1")
    assert p.times_s == (0.0, 5.0) and p.speeds_mps == (0.0, 2.1)
    assert p(2.5) == pytest.approx(1.05)
    assert p(100.0) == pytest.approx(2.1) and p.final_mps == 2.1
    assert SpeedProfile.parse(" 1:0.5 ")(0.0) == 0.5  # held before the first knot too
    assert SpeedProfile.constant(0.7)(3.0) == 0.7


@pytest.mark.parametrize("text", ["", "0", "0:0,x:1", "0:0:1", "5:0,1:1", "0:0,0:1", "-1:0", "0:nan", "0:inf,1:0"])
def test_speed_profile_rejects_bad_text(text):
    with pytest.raises(InputError):
        SpeedProfile.parse(text)


def test_named_scenarios_are_valid_and_known():
    assert {"cassie-in-place", "cassie-1mps", "cassie-ramp-2.1", "cassie-push", "rabbit-0.5mps"} <= set(SCENARIOS)
    for name, sc in SCENARIOS.items():
        assert sc.name == name and sc.robot in PROFILES and sc.duration_s > 0
        cmd = sc.command(sc.duration_s)
        assert cmd.step_time_s == sc.gait_settings.step_time_s
        if sc.gait is None:  # the robot's gait comes from its profile
            assert sc.gait_settings is PROFILES[sc.robot].gait
        if sc.robot == "rabbit":
            assert cmd.vy_mps == 0.0 and cmd.turn_rate_radps == 0.0 and cmd.step_width_m == 0.0
    assert get_scenario("cassie-ramp-2.1").command(15.0).vx_mps == pytest.approx(2.1)
    with pytest.raises(InputError, match="known"):
        get_scenario("nope")


def test_turn_stops_after_its_angle():
    sc = get_scenario("cassie-turn-90")
    assert sc.turn_rate_at(2.9) == 0.0
    assert sc.turn_rate_at(3.0) == pytest.approx(math.radians(18.0))
    assert sc.turn_rate_at(3.0 + 4.99) == pytest.approx(math.radians(18.0))
    assert sc.turn_rate_at(3.0 + 5.01) == 0.0


def test_scenario_validation_and_copy():
    with pytest.raises(InputError):
        Scenario("x", "atlas", 1.0)
    with pytest.raises(InputError):
        Scenario("x", "cassie", -1.0)
    with pytest.raises(InputError):
        Scenario("x", "cassie", 1.0, vy_mps=float("nan"))
    sc = get_scenario("cassie-push").with_(duration_s=7.0)
    assert sc.duration_s == 7.0 and sc.pushes == get_scenario("cassie-push").pushes
