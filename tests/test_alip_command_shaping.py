"""Tests of amlip_qp.alip.command_shaping: the rate limit of the velocity command, the gait schedule, the cap."""

from __future__ import annotations

import math

import numpy as np
import pytest

from amlip_qp.alip.command_shaping import CommandShaper, gait_scales
from amlip_qp.exceptions import InputError
from amlip_qp.messages import Command
from amlip_qp.profiles import PROFILES, CommandShaping

DT = 0.0005


def _cmd(vx=0.0, vy=0.0, turn=0.0, T=0.3) -> Command:
    return Command(step_time_s=T, com_height_m=0.8, clearance_m=0.1, vx_mps=vx, vy_mps=vy, turn_rate_radps=turn)


def _ticks(n: int) -> np.ndarray:
    """Tick times as the harness sees them: MuJoCo's accumulated ``data.time``."""
    t = np.zeros(n)
    for k in range(1, n):
        t[k] = t[k - 1] + DT
    return t


def _shape_all(shaper: CommandShaper, commands, times) -> list[Command]:
    return [shaper.update(c, t) for c, t in zip(commands, times)]


def test_slow_ramp_passes_through_bit_for_bit():
    # The scenarios' ramps, sampled as scenarios.SpeedProfile does (np.interp),
    # some exactly at the limit: every shaped command is the raw object itself.
    shaper = CommandShaper(CommandShaping(vx_accel_mps2=0.5, vy_accel_mps2=0.5, turn_accel_radps2=1.0))
    times = _ticks(8000)
    ramps = (((0.0, 1.0, 3.0), (0.0, 0.0, 1.0)), ((0.0, 10.0), (0.0, 2.1)), ((0.0, 1.0, 3.0), (0.0, 0.0, -1.0)))
    for knots_t, knots_v in ramps:
        shaper.reset()
        raw = [_cmd(vx=float(np.interp(t, knots_t, knots_v))) for t in times]
        shaped = _shape_all(shaper, raw, times)
        assert all(s is r for s, r in zip(shaped, raw))


def test_step_from_rest_becomes_a_ramp_at_the_limit():
    a = 0.5
    shaper = CommandShaper(CommandShaping(vx_accel_mps2=a, vy_accel_mps2=math.inf, turn_accel_radps2=math.inf))
    times = _ticks(6001)  # 3 s
    raw = _cmd(vx=1.0)
    vx = np.array([c.vx_mps for c in _shape_all(shaper, [raw] * len(times), times)])
    # Starts at rest, rises at a m/s^2, reaches 1.0 at 2 s and then is the command itself.
    assert vx[0] == 0.0
    assert np.max(np.diff(vx)) == pytest.approx(a * DT, rel=1e-9)
    np.testing.assert_allclose(vx[:3000], a * times[:3000], rtol=0, atol=1e-12)
    k_reached = int(np.argmax(vx == 1.0))
    assert times[k_reached] == pytest.approx(2.0, abs=DT)
    assert np.all(vx[k_reached:] == 1.0)
    assert shaper.update(raw, times[-1] + DT) is raw


def test_negative_steps_and_step_down_are_limited_too():
    a = 0.4
    shaper = CommandShaper(CommandShaping(vx_accel_mps2=a, vy_accel_mps2=math.inf, turn_accel_radps2=math.inf))
    times = _ticks(5001)  # 2.5 s
    vx = [shaper.update(_cmd(vx=-0.5), t).vx_mps for t in times[:2001]]
    assert vx[-1] == pytest.approx(-a * 1.0, abs=1e-12)
    assert all(np.diff(vx) < 0)
    # Back to 0: rises at the same rate, from -0.4 m/s reaches 0 after 1 s (2000 ticks).
    vx2 = np.array([shaper.update(_cmd(vx=0.0), t).vx_mps for t in times[2001:]])
    assert np.max(np.abs(np.diff(vx2))) == pytest.approx(a * DT, rel=1e-9)
    assert np.all(np.diff(vx2) >= 0.0)
    assert vx2[1990] < 0.0 and np.all(vx2[2000:] == 0.0)


def test_each_axis_has_its_own_rate_and_the_gait_fields_pass():
    shaping = CommandShaping(vx_accel_mps2=1.0, vy_accel_mps2=0.2, turn_accel_radps2=2.0)
    shaper = CommandShaper(shaping)
    raw = _cmd(vx=1.0, vy=-0.3, turn=0.5, T=0.25)
    out = None
    for t in _ticks(201):  # 0.1 s
        out = shaper.update(raw, t)
    assert out.vx_mps == pytest.approx(0.1, abs=1e-12)
    assert out.vy_mps == pytest.approx(-0.02, abs=1e-12)
    assert out.turn_rate_radps == pytest.approx(0.2, abs=1e-12)
    assert (out.step_time_s, out.com_height_m, out.clearance_m) == (0.25, 0.8, 0.1)
    assert shaper.value == (out.vx_mps, out.vy_mps, out.turn_rate_radps)


def test_only_the_out_of_reach_axis_is_replaced():
    # vx is a slow ramp (exact), vy a step (limited): vx keeps the raw bits.
    shaper = CommandShaper(CommandShaping(vx_accel_mps2=0.5, vy_accel_mps2=0.1, turn_accel_radps2=math.inf))
    times = _ticks(2000)
    for t in times:
        raw = _cmd(vx=float(np.interp(t, (0.0, 2.0), (0.0, 0.7))), vy=0.3, turn=0.2)
        out = shaper.update(raw, t)
        assert out.vx_mps == raw.vx_mps
        assert out.turn_rate_radps == raw.turn_rate_radps
    assert out.vy_mps == pytest.approx(0.1 * times[-1], abs=1e-12)


def test_inf_is_no_limit():
    shaper = CommandShaper(CommandShaping(vx_accel_mps2=math.inf, vy_accel_mps2=math.inf, turn_accel_radps2=math.inf))
    raw = _cmd(vx=2.5, vy=0.3, turn=-0.7)
    # Even the first call (dt = 0) and a jump between two ticks pass unchanged.
    assert shaper.update(raw, 0.0) is raw
    raw2 = _cmd(vx=-1.0)
    assert shaper.update(raw2, DT) is raw2


def test_reset_starts_again_from_rest():
    shaper = CommandShaper(CommandShaping(vx_accel_mps2=1.0, vy_accel_mps2=1.0, turn_accel_radps2=1.0))
    raw = _cmd(vx=1.0)
    for t in _ticks(3000):
        shaper.update(raw, t)
    assert shaper.value[0] == 1.0
    shaper.reset()
    assert shaper.value == (0.0, 0.0, 0.0)
    # A new run starts at t = 0 again (no "time went back" error) and from rest.
    assert shaper.update(raw, 0.0).vx_mps == 0.0
    assert shaper.update(raw, DT).vx_mps == pytest.approx(DT)


def test_zero_command_at_rest_is_passed_through():
    shaper = CommandShaper(PROFILES["cassie"].shaping)
    raw = _cmd()
    assert shaper.update(raw, 0.0) is raw
    assert shaper.update(raw, DT) is raw


def test_every_named_scenario_reaches_the_planner_unchanged():
    # The rates of the bundled robots let every acceptance scenario's command
    # through bit for bit (the invariant of the command shaping). Sampled
    # every 10 ticks: a ramp within the limit over 10 ticks is within it over each.
    # The changes a named scenario may see: a gait schedule's above its first speed
    # (Rabbit's ramp to 1.5 m/s: T, H and z_cl scaled, nothing else), then the
    # step-length cap's: a scenario faster than max_step_length_m / T (Cassie's
    # 3 m/s ramp) gets shorter steps, T = max_step_length_m / |vx|, and nothing else.
    from dataclasses import replace

    from amlip_qp.sim.scenarios.named import SCENARIOS

    dt = 10 * DT
    capped, scheduled = set(), set()
    for scenario in SCENARIOS.values():
        shaping = PROFILES[scenario.robot].shaping
        shaper = CommandShaper(shaping)
        t = 0.0
        for _ in range(int(round(scenario.duration_s / dt))):
            raw = scenario.command(t)
            out = shaper.update(raw, t)
            if out is not raw:
                speed, rows, expected = abs(raw.vx_mps), shaping.gait_scale_by_speed, raw
                if rows and speed > rows[0][0]:
                    sT, sH, sz = gait_scales(rows, speed)
                    expected = replace(
                        raw,
                        step_time_s=raw.step_time_s * sT,
                        com_height_m=raw.com_height_m * sH,
                        clearance_m=raw.clearance_m * sz,
                    )
                    scheduled.add(scenario.name)
                L = shaping.max_step_length_m
                if speed * expected.step_time_s > L:
                    expected = replace(expected, step_time_s=L / speed)
                    capped.add(scenario.name)
                assert out == expected, (scenario.name, t)
            t += dt
    assert capped == {"cassie-3mps", "cassie-3mps-cc-ekf"}
    assert scheduled == {"rabbit-ramp-1.5"}


def test_the_gait_schedule_scales_T_H_and_the_clearance_with_the_shaped_speed():
    rows = ((1.0, 1.0, 1.0, 1.0), (1.5, 1.2, 0.8, 2.0), (2.0, 1.2, 0.7, 2.0))
    shaping = CommandShaping(
        vx_accel_mps2=math.inf, vy_accel_mps2=math.inf, turn_accel_radps2=math.inf, gait_scale_by_speed=rows
    )
    shaper = CommandShaper(shaping)
    t = 0.0
    for vx in (0.0, 0.5, 1.0, -1.0):  # at or below the first row's speed: the command itself
        raw = _cmd(vx=vx, T=0.35)
        assert shaper.update(raw, t) is raw
        t += DT
    # (speed, expected scales): linear between the rows, held after the last, the same backwards
    for vx, (sT, sH, sz) in ((1.25, (1.1, 0.9, 1.5)), (-1.25, (1.1, 0.9, 1.5)), (1.5, (1.2, 0.8, 2.0)),
                             (1.75, (1.2, 0.75, 2.0)), (3.0, (1.2, 0.7, 2.0))):  # fmt: skip
        out = shaper.update(_cmd(vx=vx, vy=0.1, T=0.35), t)
        t += DT
        assert out.step_time_s == pytest.approx(0.35 * sT, rel=1e-12)
        assert out.com_height_m == pytest.approx(0.8 * sH, rel=1e-12)
        assert out.clearance_m == pytest.approx(0.1 * sz, rel=1e-12)
        assert (out.vx_mps, out.vy_mps, out.step_width_m) == (vx, 0.1, 0.0)
    assert gait_scales(rows, 0.3) == (1.0, 1.0, 1.0)


def test_the_step_length_cap_applies_to_the_scheduled_step_time():
    # The schedule lengthens T to 0.42 s at 1.5 m/s (0.63 m steps); the cap at 0.6 m shortens it to 0.4 s.
    rows = ((1.0, 1.0, 1.0, 1.0), (1.5, 1.2, 0.8, 1.0))
    shaping = CommandShaping(
        vx_accel_mps2=math.inf,
        vy_accel_mps2=math.inf,
        turn_accel_radps2=math.inf,
        max_step_length_m=0.6,
        gait_scale_by_speed=rows,
    )
    out = CommandShaper(shaping).update(_cmd(vx=1.5, T=0.35), 0.0)
    assert out.step_time_s == pytest.approx(0.4, rel=1e-12)
    assert out.com_height_m == pytest.approx(0.64, rel=1e-12)


@pytest.mark.parametrize(
    "rows, message",
    [
        (((1.0, 1.0, 1.0, 1.0),), "at least two rows"),
        (((1.0, 1.0, 1.0), (2.0, 1.0, 1.0)), "at least two rows"),
        (((1.0, 1.0, 1.0, 1.0), (2.0, 1.0, math.nan, 1.0)), "at least two rows"),
        (((1.0, 1.0, 0.9, 1.0), (2.0, 1.0, 0.8, 1.0)), "first row's scales must be 1"),
        (((1.0, 1.0, 1.0, 1.0), (1.0, 1.0, 0.8, 1.0)), "increasing"),
        (((-1.0, 1.0, 1.0, 1.0), (1.0, 1.0, 0.8, 1.0)), "increasing"),
        (((1.0, 1.0, 1.0, 1.0), (2.0, -1.0, 0.8, 1.0)), "positive"),
        ([(1.0, 1.0, 1.0, 1.0), (2.0, 1.0, 0.8, 1.0)], "must be a tuple"),
    ],
)
def test_bad_gait_schedules_are_input_errors(rows, message):
    with pytest.raises(InputError, match=f"gait_scale_by_speed: .*{message}"):
        CommandShaping(vx_accel_mps2=1.0, vy_accel_mps2=1.0, turn_accel_radps2=1.0, gait_scale_by_speed=rows)


@pytest.mark.parametrize(
    "kwargs",
    [
        dict(vx_accel_mps2=0.0, vy_accel_mps2=1.0, turn_accel_radps2=1.0),
        dict(vx_accel_mps2=1.0, vy_accel_mps2=-1.0, turn_accel_radps2=1.0),
        dict(vx_accel_mps2=1.0, vy_accel_mps2=1.0, turn_accel_radps2=math.nan),
        dict(vx_accel_mps2=-math.inf, vy_accel_mps2=1.0, turn_accel_radps2=1.0),
        dict(vx_accel_mps2="fast", vy_accel_mps2=1.0, turn_accel_radps2=1.0),
        dict(vx_accel_mps2=True, vy_accel_mps2=1.0, turn_accel_radps2=1.0),
        dict(vx_accel_mps2=1.0, vy_accel_mps2=1.0, turn_accel_radps2=1.0, max_step_length_m=0.0),
        dict(vx_accel_mps2=1.0, vy_accel_mps2=1.0, turn_accel_radps2=1.0, max_step_length_m=math.nan),
    ],
)
def test_bad_rates_are_input_errors(kwargs):
    with pytest.raises(InputError, match="CommandShaping"):
        CommandShaping(**kwargs)


def test_bad_arguments_are_input_errors():
    with pytest.raises(InputError, match="CommandShaping"):
        CommandShaper({"vx_accel_mps2": 1.0})
    shaper = CommandShaper(PROFILES["cassie"].shaping)
    with pytest.raises(InputError, match="needs a Command"):
        shaper.update((1.0, 0.0, 0.0), 0.0)
    for bad_t in (math.nan, math.inf, "0", None):
        with pytest.raises(InputError, match="finite time"):
            shaper.update(_cmd(), bad_t)
    shaper.update(_cmd(), 1.0)
    with pytest.raises(InputError, match="call reset"):
        shaper.update(_cmd(), 0.5)


def test_step_time_is_shortened_only_where_steps_would_be_too_long():
    shaping = CommandShaping(
        vx_accel_mps2=math.inf, vy_accel_mps2=math.inf, turn_accel_radps2=math.inf, max_step_length_m=0.63
    )
    shaper = CommandShaper(shaping)
    at_cap = _cmd(vx=2.1, T=0.3)  # 0.63 m: kept, the same object
    assert shaper.update(at_cap, 0.0) is at_cap
    short_steps = _cmd(vx=2.5, T=0.25)  # 0.625 m
    assert shaper.update(short_steps, DT) is short_steps
    for vx in (2.5, -2.5):
        out = shaper.update(_cmd(vx=vx, vy=0.1, T=0.3), 2 * DT)
        assert out.step_time_s == pytest.approx(0.252, rel=1e-12)
        assert (out.vx_mps, out.vy_mps, out.com_height_m, out.clearance_m) == (vx, 0.1, 0.8, 0.1)


def test_the_cap_follows_the_shaped_speed():
    # During the ramp of a step command T stays until |vx| T reaches the cap,
    # then falls as 1 / |vx|.
    shaping = CommandShaping(
        vx_accel_mps2=0.5, vy_accel_mps2=math.inf, turn_accel_radps2=math.inf, max_step_length_m=0.63
    )
    shaper = CommandShaper(shaping)
    raw = _cmd(vx=2.5, T=0.3)
    times = _ticks(12001)  # 6 s
    out = [shaper.update(raw, t) for t in times]
    vx = np.array([c.vx_mps for c in out])
    T = np.array([c.step_time_s for c in out])
    assert np.all(T[vx <= 2.1] == 0.3)
    fast = vx > 2.1 + 1e-9
    np.testing.assert_allclose(T[fast], 0.63 / vx[fast], rtol=1e-12)
    assert T[-1] == pytest.approx(0.252) and vx[-1] == 2.5
