"""amlip_qp/robots/reach.py: each bundled profile's physical ``[bounds]`` are its legs' (recomputed from the model)."""

from __future__ import annotations

import math

import pytest

from amlip_qp.profiles import bundled_names, get_profile
from amlip_qp.robots import load_robot
from amlip_qp.robots.reach import derive_command_bounds

#: The profile stores the derived numbers rounded to 0.01 (m/s) and 0.1 deg/s; 1 % covers that.
REL_TOL = 0.01


@pytest.fixture(scope="module")
def derived():
    return {name: derive_command_bounds(load_robot(name)) for name in bundled_names()}


@pytest.mark.parametrize("name", ["cassie", "rabbit", "h1", "g1"])
def test_the_stored_bounds_are_the_derivation_from_the_legs(derived, name):
    d, b = derived[name], get_profile(name).bounds
    assert b.vx_mps[0] == pytest.approx(d.vx_mps[0], rel=REL_TOL)
    assert b.vx_mps[1] == pytest.approx(d.vx_mps[1], rel=REL_TOL)
    assert b.vy_max_mps == pytest.approx(d.vy_max_mps, rel=REL_TOL, abs=1e-9)
    assert math.degrees(b.turn_rate_max_radps) == pytest.approx(d.turn_rate_max_degps, rel=REL_TOL, abs=1e-9)


def test_the_numbers_follow_the_formulas(derived):
    for d in derived.values():
        T = d.step_time_s
        assert d.vx_mps[1] == pytest.approx((d.reach_front_m + d.reach_back_m) / T)
        assert d.vx_mps[0] == -d.vx_mps[1]
        assert d.vy_max_mps == pytest.approx(d.spread_max_m / (2.0 * T))
        assert d.turn_rate_max_degps == pytest.approx(2.0 * d.hip_yaw_max_deg / T)
        # a leg reaches as far ahead as behind within 1 mm (the knee's samples; no offset along x)
        assert d.reach_front_m == pytest.approx(d.reach_back_m, abs=1e-3)


def test_cassie_reaches_about_4_mps_and_its_hip_yaw_gives_45_deg_a_step(derived):
    d = derived["cassie"]
    # the paper: about 4 m/s in an ideal simulator; 0.25 s steps of at most 1.035 m
    assert 3.9 < d.vx_mps[1] < 4.4
    assert d.step_time_s == 0.25
    assert d.hip_height_m == pytest.approx(0.8385, abs=1e-3)  # 0.80 m CoM + hip over CoM at the stand pose
    # the leg (hip pitch to toe) is at most about 1 m: 0.518 m ahead at 0.839 m below the hip
    assert math.hypot(d.reach_front_m, d.hip_height_m) == pytest.approx(0.986, abs=0.01)
    assert d.hip_yaw_max_deg == pytest.approx(22.5, abs=1e-3)
    assert d.turn_rate_max_degps == pytest.approx(180.0, abs=1e-3)
    # the paper's hardware: about 1 m/s forward and 1 m/s sideways is physically possible
    assert d.vy_max_mps > 1.0


def test_planar_rabbit_has_no_lateral_or_turning_bound(derived):
    d = derived["rabbit"]
    assert d.vy_max_mps == 0.0 and d.turn_rate_max_degps == 0.0 and d.spread_max_m == 0.0
    assert d.reach_front_m > 0.2


@pytest.mark.parametrize("name", ["cassie", "rabbit", "h1", "g1"])
def test_the_verified_envelope_lies_inside_the_physical_bounds(name):
    p = get_profile(name)
    assert p.verified.within(p.bounds)
    assert p.verified.vx_mps[1] > 0.0  # every bundled robot's acceptance walks forward
