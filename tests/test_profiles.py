"""amlip_qp.profiles: the robot profile registry, its command bounds, shaping and tracker configurations."""

import math

import pytest

from amlip_qp.exceptions import InputError, UnknownRobotError
from amlip_qp.profiles import (
    NO_SHAPING,
    PROFILES,
    ROBOT_NAMES,
    CommandBounds,
    CommandShaping,
    get_profile,
)
from amlip_qp.robots import OutputMap, load_robot
from amlip_qp.sim.scenarios.named import SCENARIOS


def test_registry_names_match_their_profiles_and_model_files_exist():
    from amlip_qp.paths import MODELS_DIR

    assert ROBOT_NAMES == ("cassie", "g1", "h1", "rabbit")
    for name, profile in PROFILES.items():
        assert profile.name == name and get_profile(name) is profile
        assert profile.source == MODELS_DIR / f"{name}.toml" and profile.model.path.is_file()
        assert profile.outputs == OutputMap(load_robot(name)).names
        assert profile.planar == (name == "rabbit")
        assert profile.planar == (profile.gait.step_width_m == 0.0)


def test_unknown_robot_names_the_known_ones():
    with pytest.raises(UnknownRobotError, match="known robots: cassie, g1, h1, rabbit"):
        get_profile("atlas")


@pytest.mark.parametrize("name", ROBOT_NAMES)
def test_tracker_configurations_import_and_have_one_gain_per_output(name):
    from amlip_qp.control.pbc.gains import PBCGains
    from amlip_qp.control.wbc.config import QPConfig

    profile = get_profile(name)
    qp = profile.tracker_config("qp")
    trackers = "pbc, qp"
    assert isinstance(qp, QPConfig) and ", ".join(sorted(profile.trackers)) == trackers
    if "pbc" in profile.trackers:
        assert isinstance(profile.tracker_config("pbc"), PBCGains)
    n_outputs = {"rabbit": 4, "g1": 10}.get(name, 9)
    assert len(qp.output_kp) == len(qp.output_kd) == len(qp.output_weight) == n_outputs
    with pytest.raises(InputError, match=f"no 'mpc' tracker configuration; known: {trackers}"):
        profile.tracker_config("mpc")


def test_every_named_scenario_is_inside_its_robot_bounds():
    for sc in SCENARIOS.values():
        profile = get_profile(sc.robot)
        profile.bounds.check(
            sc.robot,
            vx_mps=sc.vx.speeds_mps,
            vy_mps=sc.vy_mps,
            turn_rate_radps=sc.turn_rate_radps,
            duration_s=sc.duration_s,
            pushes=[(p.t_s, p.force_N, p.duration_s) for p in sc.pushes],
        )


def test_compare_ranges_are_inside_the_bounds():
    compared = [p for p in PROFILES.values() if p.compare is not None]
    assert [p.name for p in compared] == ["cassie", "g1", "h1", "rabbit"]
    for profile in compared:
        assert profile.compare.nominal_scenario in SCENARIOS
        assert profile.compare.ramp_end_mps <= profile.bounds.vx_mps[1]
        assert profile.compare.push_max_impulse_Ns <= profile.bounds.push_impulse_max_Ns


def test_bounds_name_the_bound_they_reject():
    b = get_profile("cassie").bounds
    b.check("cassie", vx_mps=(-4.14, 4.14))  # the ends are inside
    with pytest.raises(InputError, match=r"forward speed 4.2 m/s is outside cassie's bounds \[-4.14, 4.14\] m/s"):
        b.check("cassie", vx_mps=(0.0, 4.2))
    with pytest.raises(InputError, match="lateral speed"):
        b.check("cassie", vy_mps=-2.08)
    with pytest.raises(InputError, match="turn rate"):
        b.check("cassie", turn_rate_radps=math.radians(181.0))
    with pytest.raises(InputError, match="duration"):
        b.check("cassie", duration_s=601.0)
    with pytest.raises(InputError, match="impulse"):
        b.check("cassie", duration_s=10.0, pushes=[(1.0, (600.0, 0.0, 0.0), 0.2)])  # 120 N s


@pytest.mark.parametrize(
    "kwargs",
    [
        {"vx_mps": (0.5, 2.0)},  # must contain 0
        {"vx_mps": (-1.0, math.inf)},
        {"vx_mps": (-1.0, 1.0), "vy_max_mps": -0.1},
        {"vx_mps": (-1.0, 1.0), "duration_max_s": math.nan},
    ],
)
def test_bad_bounds_are_refused(kwargs):
    kwargs.setdefault("vy_max_mps", 0.5)
    kwargs.setdefault("turn_rate_max_radps", 1.0)
    with pytest.raises(InputError, match="CommandBounds"):
        CommandBounds(**kwargs)


@pytest.mark.parametrize("value", [0.0, -1.0, math.nan])
def test_shaping_rates_must_be_positive(value):
    with pytest.raises(InputError, match="CommandShaping.vx_accel_mps2"):
        CommandShaping(vx_accel_mps2=value, vy_accel_mps2=1.0, turn_accel_radps2=1.0)


def test_no_shaping_limits_nothing():
    assert NO_SHAPING.vx_accel_mps2 == NO_SHAPING.vy_accel_mps2 == NO_SHAPING.turn_accel_radps2 == math.inf
    assert NO_SHAPING.max_step_length_m == math.inf


def test_shaping_passes_every_named_ramp_unchanged():
    """The forward rate limit is at or above every named scenario's steepest ramp (so they are not shaped)."""
    for sc in SCENARIOS.values():
        t, v = sc.vx.times_s, sc.vx.speeds_mps
        steepest = max((abs(v[i + 1] - v[i]) / (t[i + 1] - t[i]) for i in range(len(t) - 1)), default=0.0)
        assert steepest <= get_profile(sc.robot).shaping.vx_accel_mps2, sc.name
