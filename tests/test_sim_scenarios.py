"""Scenario catalogue and speed-profile parsing."""

from __future__ import annotations

import math

import pytest

from amlip_qp.exceptions import InputError
from amlip_qp.profiles import PROFILES
from amlip_qp.sim.scenarios.named import SCENARIOS, get_scenario
from amlip_qp.sim.scenarios.scenarios import Scenario, SpeedProfile


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


def test_every_named_scenario_is_inside_its_robots_bounds():
    from amlip_qp.sim.scenarios.scenarios import check_scenario

    for sc in SCENARIOS.values():
        check_scenario(sc)


@pytest.mark.parametrize(
    "robot, vx",
    [
        ("cassie", 2.5),
        ("cassie", -0.5),
        ("cassie", -1.0),
        ("cassie", 1.0),
        ("rabbit", 0.5),
        ("rabbit", 0.8),
        ("rabbit", 1.0),
    ],
)
def test_the_verified_step_commands_are_inside_the_bounds(robot, vx):
    from amlip_qp.sim.scenarios.scenarios import check_scenario

    check_scenario(Scenario("step", robot, 10.0, vx=SpeedProfile.constant(vx)))


@pytest.mark.parametrize(
    "robot, changes, needle",
    [
        (
            "cassie",
            {"vx": SpeedProfile.constant(4.2)},
            "forward speed 4.2 m/s is outside cassie's bounds [-4.14, 4.14] m/s",
        ),
        ("cassie", {"vx": SpeedProfile((0.0, 4.0, 8.0), (0.0, -4.5, 0.0))}, "forward speed -4.5 m/s"),
        ("rabbit", {"vx": SpeedProfile.constant(1.8)}, "outside rabbit's bounds [-1.73, 1.73] m/s"),
        ("cassie", {"vy_mps": -2.08}, "lateral speed -2.08 m/s is outside cassie's bound |vy| <= 2.07 m/s"),
        (
            "cassie",
            {"turn_rate_radps": math.radians(181.0)},
            "turn rate 181 deg/s is outside cassie's bound |turn rate| <= 180 deg/s",
        ),
        ("cassie", {"duration_s": 601.0}, "duration 601 s is above cassie's bound 600 s"),
        ("rabbit", {"vy_mps": 0.1, "turn_rate_radps": 0.2}, "rabbit is planar: lateral speed (0.1 m/s), turn rate"),
        ("rabbit", {"pushes": [(1.0, (0.0, 10.0, 0.0), 0.1)]}, "rabbit is planar: push FY (10 N at 1 s)"),
        ("cassie", {"pushes": [(1.0, (0.0, 3001.0, 0.0), 0.01)]}, "force 3001 N is above cassie's bound 3000 N"),
        ("cassie", {"pushes": [(1.0, (600.0, 0.0, 800.0), 0.2)]}, "impulse 200 N s (force x duration)"),
        ("cassie", {"pushes": [(9.9, (100.0, 0.0, 0.0), 0.2)]}, "ends after the run's 10 s"),
    ],
)
def test_check_scenario_names_the_bound(robot, changes, needle):
    from amlip_qp.profiles import get_profile
    from amlip_qp.sim.loop.run_types import Push
    from amlip_qp.sim.scenarios.scenarios import check_scenario

    if "pushes" in changes:
        changes = {"pushes": tuple(Push(*p) for p in changes["pushes"])}
    sc = Scenario("x", robot, 10.0).with_(**changes)
    with pytest.raises(InputError) as info:
        check_scenario(sc)
    assert needle in str(info.value) and "\n" not in str(info.value)
    # The bound sits exactly where the message says it does: the same check with it widened passes
    # (except for planar robots and pushes after the run, which no bound widening allows).
    if "planar" not in needle and "after the run" not in needle:
        from dataclasses import replace

        wide = replace(get_profile(robot).bounds, vx_mps=(-99.0, 99.0), vy_max_mps=99.0, turn_rate_max_radps=99.0,
                       duration_max_s=1e4, push_impulse_max_Ns=1e4, push_force_max_N=1e5)  # fmt: skip
        check_scenario(sc, replace(get_profile(robot), bounds=wide))


def test_the_closed_chain_ekf_scenarios_are_the_ideal_ones_on_the_hardware_like_setting():
    from dataclasses import replace

    from amlip_qp.sim.loop.run_types import PlantSetting
    from amlip_qp.sim.scenarios.named import TERRAIN_SCENARIOS, ideal_scenarios
    from amlip_qp.sim.world.plant_modifiers import PlantModifiers

    CLOSED_CHAIN_EKF = PlantSetting("cassie-closed-chain", "robot", "ekf")
    MISMATCHES = {
        "mass-0.8": PlantModifiers(mass_scale=0.8),
        "mass-1.2": PlantModifiers(mass_scale=1.2),
        "payload-5kg": PlantModifiers(payload_kg=5.0, payload_pos_m=(-0.10, 0.0, 0.0)),
        "friction-0.5": PlantModifiers(friction=0.5),
        "delay-1": PlantModifiers(actuator_delay_ticks=1),
    }
    ideal = ideal_scenarios()
    assert ideal == [n for n, s in SCENARIOS.items() if "-ekf" not in n and n not in TERRAIN_SCENARIOS]
    for name in ideal:
        twin = SCENARIOS.get(f"{name}-cc-ekf")
        if SCENARIOS[name].robot != "cassie":
            assert twin is None
            continue
        assert twin is not None and twin.setting == CLOSED_CHAIN_EKF
        # the same commands, pushes, gait and duration: only the setting differs
        assert replace(twin, name=name, setting=PlantSetting(), description="") == replace(
            SCENARIOS[name], description=""
        )
    assert {n for n in SCENARIOS if n.startswith("cassie-1mps-cc-ekf-")} == {
        f"cassie-1mps-cc-ekf-{key}" for key in MISMATCHES
    }
    payload = SCENARIOS["cassie-1mps-cc-ekf-payload-5kg"].setting.modifiers
    assert (payload.payload_kg, payload.payload_pos_m) == (5.0, (-0.10, 0.0, 0.0))  # 10 cm behind the pelvis
    for key, mods in MISMATCHES.items():
        sc = SCENARIOS[f"cassie-1mps-cc-ekf-{key}"]
        assert sc.setting == replace(CLOSED_CHAIN_EKF, modifiers=mods)
        assert sc.duration_s == 10.0 and sc.vx.final_mps == 1.0


def test_the_command_function_of_a_run_gives_the_scenarios_commands():
    sc = get_scenario("cassie-turn-90")
    command = sc.command_function()
    times = [k * 0.0005 for k in range(0, 14000, 7)] + [3.0, 3.0, 1.0]
    made = [command(t) for t in times]
    assert made == [sc.command(t) for t in times]
    assert made[-3] is made[-2]  # unchanged values: the same Command, made once
    assert made[0] is not made[-1]


def test_the_command_function_answers_earlier_times_too():
    # 0.5 m/s held until 1 s, then 1.0 m/s: the cached command answers only for its own values.
    sc = get_scenario("cassie-turn-90").with_(vx=SpeedProfile((0.0, 1.0, 1.0 + 1e-9), (0.5, 0.5, 1.0)))
    command = sc.command_function()
    times = [0.1, 0.2, 2.5, 0.5, 0.15, 2.6, 0.3]
    made = [command(t).vx_mps for t in times]
    assert made == [sc.command(t).vx_mps for t in times] == [0.5, 0.5, 1.0, 0.5, 0.5, 1.0, 0.5]


@pytest.mark.parametrize(
    ("changes", "hold"),
    [
        ({}, 8.0),  # the turn's end: 3 s + 90 deg / 18 deg/s
        ({"turn_angle_rad": math.inf}, 3.0),  # an endless turn: from its start
        ({"turn_rate_radps": 0.0}, 2.5),  # no turn: the last knot
        ({"turn_rate_radps": -0.4, "turn_start_s": 6.0}, 6.0 + math.radians(90.0) / 0.4),
    ],
)
def test_the_command_holds_from_the_last_knot_or_the_turns_end(changes, hold):
    sc = get_scenario("cassie-turn-90").with_(**changes)
    times = [k * 0.0005 for k in range(0, 30000, 5)]
    held = [sc.command(t) for t in times if t >= hold]
    assert held and all(c == held[0] for c in held)
    assert sc.command(hold - 0.01) != held[0]  # it does change just before
    command = sc.command_function()
    made = [command(t) for t in times]
    assert made == [sc.command(t) for t in times]
    assert all(c is made[-1] for c, t in zip(made, times) if t >= hold)


def _bits(c):
    return [math.copysign(1.0, x) * (abs(x) + 1.0) for x in (c.vx_mps, c.turn_rate_radps)]  # a zero's sign too


@pytest.mark.parametrize(
    "knots",
    [
        ((0.0, 1.0, 2.5, 3.0, 4.0), (0.0, 0.0, 0.7, 0.7, -0.3)),
        ((0.5, 1.0, 2.0, 3.0), (-0.0, -0.0, 0.0, 0.0)),  # negative zeros: 0 * dt + (-0.0) is +0.0
        ((1.0,), (-0.5,)),
        ((0.0, 0.001, 1.0), (-0.4, -0.4, -0.4)),
    ],
)
@pytest.mark.parametrize("turn_rate_radps", [math.radians(18.0), 0.0, -0.0])
def test_the_command_is_made_once_while_its_values_hold_bit_for_bit(knots, turn_rate_radps):
    sc = get_scenario("cassie-turn-90").with_(vx=SpeedProfile(*knots), turn_start_s=1.7)
    sc = sc.with_(turn_rate_radps=turn_rate_radps)
    times = [k * 0.0005 for k in range(14000)]
    command = sc.command_function()
    made = [command(t) for t in times]
    assert [_bits(c) for c in made] == [_bits(sc.command(t)) for t in times]
    changes = sum(a is not b for a, b in zip(made, made[1:]))
    assert changes == sum(_bits(sc.command(a)) != _bits(sc.command(b)) for a, b in zip(times, times[1:]))


@pytest.mark.parametrize("turn_rate_radps", [0.3, 0.0])
def test_the_command_function_refuses_a_nan_time_first_or_later(turn_rate_radps):
    """NaN in, a speed of NaN: the constructor's error for the first Command and for the later ones."""
    sc = get_scenario("cassie-1mps").with_(turn_rate_radps=turn_rate_radps)
    for later in (False, True):
        command = sc.command_function()
        if later:
            assert command(2.0) == sc.command(2.0)
        with pytest.raises(InputError, match="vx_mps must be a finite number"):
            command(math.nan)
        assert command(2.5) == sc.command(2.5)  # and it goes on


def test_terrain_scenarios_have_their_speeds_durations_and_modes():
    from amlip_qp.sim.scenarios.named import TERRAIN_SCENARIOS
    from amlip_qp.sim.world.terrain import parse_terrain

    slopes = [n for n in TERRAIN_SCENARIOS if n.startswith("cassie-slope-")]
    # 10 and 15 deg up and down, 22 deg up, each blind and terrain-aware; 26 deg up blind, 30 deg up aware
    assert len(slopes) == 12
    for name, sc in TERRAIN_SCENARIOS.items():
        spec = parse_terrain(sc.setting.terrain)
        assert not spec.is_flat and sc.robot == "cassie"
        assert sc.setting.terrain_aware == name.endswith("-aware") or name == "cassie-stairs-10cm"
        if name in slopes:
            deg = float(spec.text.split(":")[1])
            assert (deg > 0) == ("-up" in name) and abs(deg) == float(name.split("-")[2])
            assert sc.duration_s == 15.0 and sc.vx.final_mps == 0.5
    assert TERRAIN_SCENARIOS["cassie-stairs-10cm"].setting.terrain_aware
    assert TERRAIN_SCENARIOS["cassie-stairs-10cm"].vx.final_mps == 0.4
    rough = TERRAIN_SCENARIOS["cassie-rough-4cm"]
    assert (rough.duration_s, rough.vx.final_mps, rough.setting.terrain_aware) == (20.0, 0.75, False)
    waves = TERRAIN_SCENARIOS["cassie-waves-30cm"]
    assert waves.command(10.0).clearance_m == 0.2 and waves.vx.final_mps == 0.75 and not waves.setting.terrain_aware
