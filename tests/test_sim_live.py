"""Tests of amlip_qp.sim.loop.live and live_keys: the keys' command, the live loop without a window."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from amlip_qp.exceptions import InputError
from amlip_qp.profiles import get_profile
from amlip_qp.sim.loop.live import LiveCommand, LiveLoop
from amlip_qp.sim.loop.live_keys import ACTIONS, BINDINGS, CODE_OF_NAME, VX_STEP_MPS, keys_help, parse_key_script
from amlip_qp.sim.loop.run_types import FallCriteria
from amlip_qp.sim.scenarios import factory
from amlip_qp.sim.scenarios.scenarios import Scenario

UP, DOWN, LEFT, RIGHT = (CODE_OF_NAME[k] for k in ("up", "down", "left", "right"))
HOME, END, ENTER, SPACE, BACKSPACE = (CODE_OF_NAME[k] for k in ("home", "end", "enter", "space", "backspace"))


def _command(robot: str = "cassie", **start) -> LiveCommand:
    scenario = Scenario("live", robot, 10.0)
    return LiveCommand(scenario.command(0.0), get_profile(robot).bounds, **start)


def _press(cmd: LiveCommand, action: str, times: int) -> None:
    for _ in range(times):
        cmd.apply(action)


# ----------------------------------------------------------------------------- keys


def test_the_key_codes_are_glfws_the_codes_mujocos_viewer_hands_on():
    import glfw

    for b in BINDINGS:
        assert getattr(glfw, f"KEY_{b.name.upper()}") == b.code, b.name
        assert b.action in ACTIONS
    assert len({b.code for b in BINDINGS}) == len(BINDINGS)
    assert {b.action for b in BINDINGS} == set(ACTIONS)


def test_the_keys_help_names_every_key_and_its_step():
    text = keys_help()
    for b in BINDINGS:
        assert b.name.capitalize() in text and b.help in text
    assert f"+{VX_STEP_MPS:g} m/s" in text


def test_mujocos_viewer_binds_none_of_the_keys_to_a_flag():
    """Its visualisation and rendering flags' shortcuts are single characters, none of them a key of view's."""
    shortcuts = {row[2] for row in (*mujoco.mjVISSTRING, *mujoco.mjRNDSTRING) if row[2]}
    assert {"R", ",", "D"} <= shortcuts and all(len(s) == 1 for s in shortcuts)
    for b in BINDINGS:
        assert b.code > 255 or chr(b.code) not in shortcuts, b.name


# -------------------------------------------------------------------------- command


def test_a_key_press_steps_the_command_by_its_step():
    cmd = _command()
    assert cmd.apply("vx+") and cmd.values == (0.1, 0.0, 0.0)
    _press(cmd, "vx+", 2)
    _press(cmd, "vy-", 3)
    _press(cmd, "turn+", 2)
    assert cmd.values == (0.3, -0.15, 20.0)  # sums of steps, exact to 1e-9 and kept so
    c = cmd.command()
    assert (c.vx_mps, c.vy_mps) == (0.3, -0.15) and c.turn_rate_radps == pytest.approx(math.radians(20.0), abs=1e-15)
    _press(cmd, "vx-", 3)
    _press(cmd, "vy+", 3)
    _press(cmd, "turn-", 2)
    assert cmd.values == (0.0, 0.0, 0.0)


def test_the_command_stops_at_the_robots_bounds():
    cmd = _command()
    bounds = get_profile("cassie").bounds
    _press(cmd, "vx+", 100)
    _press(cmd, "vy+", 100)
    _press(cmd, "turn-", 100)
    assert cmd.values == (bounds.vx_mps[1], bounds.vy_max_mps, -round(math.degrees(bounds.turn_rate_max_radps), 9))
    assert not cmd.apply("vx+") and not cmd.apply("vy+") and not cmd.apply("turn-")  # at the bound: no change
    _press(cmd, "vx-", 200)
    assert cmd.vx_mps == bounds.vx_mps[0]
    assert cmd.command().turn_rate_radps == pytest.approx(-bounds.turn_rate_max_radps, rel=1e-12)


def test_a_planar_robot_gets_no_lateral_speed_or_turn_rate():
    cmd = _command("rabbit")
    assert get_profile("rabbit").bounds.vy_max_mps == 0.0
    for action in ("vy+", "vy-", "turn+", "turn-"):
        assert not cmd.apply(action)
    assert cmd.apply("vx+") and cmd.values == (0.1, 0.0, 0.0)


def test_stop_zeroes_and_reset_returns_to_the_starting_command():
    cmd = _command(vx_mps=0.5, vy_mps=-0.1, turn_rate_degps=15.0)
    assert cmd.values == (0.5, -0.1, 15.0)
    _press(cmd, "vx+", 3)
    assert cmd.apply("stop") and cmd.values == (0.0, 0.0, 0.0)
    cmd.reset()
    assert cmd.values == (0.5, -0.1, 15.0)
    assert _command(vx_mps=9.0).vx_mps == get_profile("cassie").bounds.vx_mps[1]  # a start outside: clipped


def test_the_command_object_is_kept_while_the_values_hold_and_keeps_the_gait():
    cmd = _command()
    first = cmd.command()
    assert cmd.command() is first
    assert not cmd.apply("pause") and not cmd.apply("reset") and cmd.command() is first  # the loop's actions
    cmd.apply("vx+")
    second = cmd.command()
    assert second is not first and second.vx_mps == 0.1
    assert (second.step_time_s, second.com_height_m, second.clearance_m, second.step_width_m) == (
        first.step_time_s,
        first.com_height_m,
        first.clearance_m,
        first.step_width_m,
    )
    with pytest.raises(InputError, match="unknown key action"):
        cmd.apply("jump")


def test_a_key_script_is_read_in_time_order():
    text = "# warm up\n2.5 Left\n0.5 up   # faster\n\n1 UP\n3 backspace\n"
    assert parse_key_script(text) == ((0.5, UP), (1.0, UP), (2.5, LEFT), (3.0, BACKSPACE))
    for bad, why in (
        ("1 up down", "line 1: expected 'T KEY'"),
        ("up", "line 1: expected 'T KEY'"),
        ("0 up\n-1 up", "line 2: the time must be a number of seconds >= 0"),
        ("nan up", "the time must be"),
        ("1 jump", "unknown key 'jump'; known: up, down"),
    ):
        with pytest.raises(InputError, match=why):
            parse_key_script(bad, "keys.txt")


# ------------------------------------------------------------------------ live loop


@pytest.fixture(scope="module")
def sim():
    return factory.build_simulation(Scenario("live", "cassie", 10.0), "qp")


def _loop(sim, **kwargs) -> LiveLoop:
    sim.reset_to_keyframe()
    return LiveLoop(sim, _command(), **kwargs)


def _keyframe_qpos(sim) -> np.ndarray:
    key = mujoco.mj_name2id(sim.model, mujoco.mjtObj.mjOBJ_KEY, "stand")
    return sim.model.key_qpos[key].copy()


@pytest.mark.slow
def test_the_live_loop_walks_at_the_keyed_command(sim):
    live = _loop(sim)
    for _ in range(5):
        live.key(UP)  # as the viewer's key_callback does
    n = 0
    while n < 8000:  # 4 s: the ramp to 0.5 m/s (1 s at Cassie's 0.5 m/s^2), then 3 s at it
        n += live.step_ticks(200)
        assert not live.fell
    assert live.command.values == (0.5, 0.0, 0.0) and live.keys_handled == 5
    assert sim.controller.shaper.value == pytest.approx((0.5, 0.0, 0.0), abs=1e-12)
    vx, vy = live.measured_velocity()  # the base's mean over the last second
    assert vx == pytest.approx(0.5, abs=0.1) and abs(vy) < 0.1
    assert live.t_s == pytest.approx(4.0, abs=1e-9) and len(sim.controller.steps) >= 10
    assert 1.2 < live.distance_m() < 2.0
    summary = live.summary()
    assert summary["command"] == {"vx_mps": 0.5, "vy_mps": 0.0, "turn_rate_degps": 0.0}
    assert summary["steps"] == len(sim.controller.steps) and summary["distance_m"] == live.distance_m()
    line = live.overlay()
    assert line.startswith(f"v fwd {vx:+.2f} lat {vy:+.2f} m/s | cmd fwd +0.50 lat +0.00 m/s turn +0 deg/s | step ")
    assert "FELL" not in line and "PAUSED" not in line


def test_each_key_reaches_the_command_through_the_loop(sim):
    live = _loop(sim)
    expected = (
        (UP, (0.1, 0.0, 0.0)), (UP, (0.2, 0.0, 0.0)), (DOWN, (0.1, 0.0, 0.0)), (LEFT, (0.1, 0.0, 10.0)),
        (RIGHT, (0.1, 0.0, 0.0)), (RIGHT, (0.1, 0.0, -10.0)), (HOME, (0.1, 0.05, -10.0)), (END, (0.1, 0.0, -10.0)),
        (END, (0.1, -0.05, -10.0)), (ENTER, (0.0, 0.0, 0.0)), (32000, (0.0, 0.0, 0.0)),  # a key of the viewer's own
    )  # fmt: skip
    for code, values in expected:
        live.key(code)
        live.step_ticks(0)  # the keys are carried out before any tick
        assert live.command.values == values
    assert live.keys_handled == len(expected) - 1 and live.ticks == 0


def test_space_pauses_and_resumes_the_loop(sim):
    live = _loop(sim)
    assert live.step_ticks(10) == 10
    live.key(SPACE)
    assert live.step_ticks(10) == 0 and live.paused and "PAUSED" in live.overlay()
    assert live.frame(live.clock() + 1.0) == 0  # a frame steps nothing while paused
    live.key(SPACE)
    assert live.step_ticks(10) == 10 and not live.paused and live.t_s == pytest.approx(20 * live.dt_s)


def test_backspace_resets_to_the_stand_keyframe_and_the_starting_command(sim):
    live = _loop(sim)
    live.key(UP)
    live.step_ticks(400)
    assert live.command.vx_mps == 0.1 and not np.array_equal(sim.data.qpos, _keyframe_qpos(sim))
    live.key(BACKSPACE)
    assert live.step_ticks(0) == 0  # the keys are carried out first
    assert live.resets == 1 and live.command.values == (0.0, 0.0, 0.0)
    np.testing.assert_array_equal(sim.data.qpos, _keyframe_qpos(sim))
    assert float(sim.data.time) == 0.0 and live.t_s == 0.0 and sim.controller.steps == []
    assert live.distance_m() == 0.0
    assert live.step_ticks(10) == 10


def test_a_reset_of_the_viewers_own_is_turned_into_the_keyframe(sim):
    live = _loop(sim)
    live.step_ticks(50)
    live.notice_plant()  # the plant as the loop left it: nothing to do
    assert live.step_ticks(0) == 0 and live.resets == 0
    mujoco.mj_resetData(sim.model, sim.data)  # the viewer's "Reset": MuJoCo's default state, time 0
    mujoco.mj_forward(sim.model, sim.data)
    live.notice_plant()
    live.step_ticks(0)
    assert live.resets == 1
    np.testing.assert_array_equal(sim.data.qpos, _keyframe_qpos(sim))


def _viewers_reset(sim) -> None:
    """What the viewer's sync does after its Backspace: MuJoCo's default state, forwarded."""
    mujoco.mj_resetData(sim.model, sim.data)
    mujoco.mj_forward(sim.model, sim.data)


@pytest.mark.parametrize("order", ["viewer first", "loop first", "loop first, paused"])
def test_backspace_and_the_viewers_own_reset_make_one_reset_in_either_order(sim, order):
    live = _loop(sim)
    live.step_ticks(50)
    if order.endswith("paused"):
        live.key(SPACE)
    live.key(BACKSPACE)  # the key reaches the loop's queue and the viewer at once
    if order == "viewer first":  # the viewer's sync comes before the loop reads its keys
        _viewers_reset(sim)
        live.notice_plant()
        live.step_ticks(10)
    else:  # the loop reads the key first, then the viewer's sync resets (even with the same time, paused)
        live.step_ticks(0 if order.endswith("paused") else 10)
        _viewers_reset(sim)
        live.notice_plant()
        live.step_ticks(0)
    assert live.resets == 1
    key = _keyframe_qpos(sim)
    assert np.abs(sim.model.qpos0 - key).max() > 0.1  # MuJoCo's default state is far from the keyframe
    assert np.abs(sim.data.qpos - key).max() < 0.01  # at the keyframe, or 10 ticks (5 ms) from it
    live.notice_plant()  # the next syncs change nothing
    live.step_ticks(0)
    assert live.resets == 1


def test_script_keys_come_at_their_simulated_times(sim):
    live = _loop(sim, script=parse_key_script("0.05 up\n0.05 up\n0.1 left\n"))
    live.step_ticks(100)  # ticks 0..99: before 0.05 s
    assert live.command.values == (0.0, 0.0, 0.0)
    live.step_ticks(1)  # the keys at 0.05 s come before the tick at 0.05 s
    assert live.command.values == (0.2, 0.0, 0.0)
    live.step_ticks(100)
    assert live.command.values == (0.2, 0.0, 10.0) and live.keys_handled == 3


def test_a_frame_steps_no_more_simulated_time_than_wall_time(sim):
    now = [100.0]
    live = _loop(sim, clock=lambda: now[0], max_lag_s=0.1)
    assert live.frame() == 0  # the first frame: no wall time has passed
    for wall_s in (0.01, 0.0205, 0.003, 0.0171, 0.0004):
        now[0] += wall_s
        live.frame()
        elapsed = now[0] - 100.0
        assert elapsed - live.dt_s < live.t_s <= elapsed + 1e-12  # behind the wall clock by less than a tick
    before = live.ticks
    now[0] += 5.0  # a stall: at most max_lag_s is caught up, the rest dropped
    assert live.frame() == pytest.approx(0.1 / live.dt_s, abs=1) and live.ticks - before <= 200
    assert live.summary()["realtime_factor"] == pytest.approx(live.ticks * live.dt_s / (now[0] - 100.0))
    assert 0.0 < live.realtime_factor() < 0.05  # the last frame stepped 0.1 s in 5 s


def test_the_viewers_push_in_xfrc_applied_acts_on_the_robot_and_is_counted(sim):
    """MuJoCo's viewer writes the mouse's push into xfrc_applied at each sync; the loop's ticks keep it."""
    base = sim.plant.base_body_id
    ys = []
    for force_N in (0.0, 60.0):
        live = _loop(sim)
        sim.data.xfrc_applied[base, :3] = (0.0, force_N, 0.0)  # to the left, as a sync would leave it
        live.notice_plant()
        live.step_ticks(400)  # 0.2 s
        ys.append(float(sim.data.xpos[base, 1]))
        assert (live.push_frames, live.max_push_N) == ((0, 0.0) if force_N == 0.0 else (1, force_N))
        sim.data.xfrc_applied[:] = 0.0
    assert ys[1] - ys[0] > 0.02  # 60 N for 0.2 s on the 33-kg robot: 0.5 F t^2 / m = 3.6 cm (4.2 cm measured)


def test_the_session_ends_after_its_duration_over_every_start(sim):
    live = _loop(sim, duration_s=0.1)
    assert live.step_ticks(150) == 150 and not live.finished
    live.key(BACKSPACE)  # a reset does not start the session's clock over
    assert live.step_ticks(150) == 50 and live.finished and live.resets == 1
    assert live.step_ticks(10) == 0 and live.summary()["total_sim_time_s"] == pytest.approx(0.1, abs=1e-15)


def test_a_fall_stops_the_loop_until_a_reset(sim):
    fall = sim.fall
    sim.fall = FallCriteria(max_tilt_rad=0.02)  # the base's tilt at the first steps counts as a fall
    try:
        live = _loop(sim)
        done = live.step_ticks(2000)
        assert live.fell and done < 2000 and live.falls == 1
        assert live.step_ticks(10) == 0 and "FELL at" in live.overlay()
        live.notice_plant()  # after a fall the viewer's state is left alone
        assert live.resets == 0
        live.key(BACKSPACE)
        live.step_ticks(0)
        assert not live.fell and live.resets == 1 and live.summary()["falls"] == 1
    finally:
        sim.fall = fall
