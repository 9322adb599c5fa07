"""The MuJoCo harness: pushes, contact switches, noise determinism, the per-tick hook.

Stand-in trackers only (zero torque, or a joint PD holding the stand
keyframe); the trackers' own tests cover walking.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from amlip_qp.control.tracker import Tracker
from amlip_qp.exceptions import InputError
from amlip_qp.messages import TrackerResult
from amlip_qp.sim.loop.run_types import Push, SensorNoise
from amlip_qp.sim.scenarios import factory
from amlip_qp.sim.scenarios.scenarios import Scenario
from stand_ins import ZeroTracker


class HoldTracker(Tracker):
    """Joint PD to the stand keyframe (a robot that just stands)."""

    name = "hold"

    def __init__(self, robot, kp=400.0, kd=10.0):
        self.q_idx = robot.actuated.pin_q_idx
        self.v_idx = robot.actuated.pin_v_idx
        self.q_ref = robot.q_stand[self.q_idx].copy()
        self.kp, self.kd = kp, kd

    def compute(self, kin, target):
        return TrackerResult(tau_Nm=self.kp * (self.q_ref - kin.q[self.q_idx]) - self.kd * kin.v[self.v_idx])


def _sim(robot, tracker_cls=ZeroTracker, duration=0.05, pushes=(), noise=None, seed=0):
    sc = Scenario("test", robot, duration, pushes=tuple(pushes))
    return factory.build_simulation(sc, tracker_cls(factory.load(robot)), seed=seed, noise=noise)


def test_push_force_only_inside_its_window():
    push = Push(0.010, (50.0, -20.0, 5.0), 0.020)
    sim = _sim("rabbit", pushes=[push])
    assert np.allclose(sim.push_force(0.0099), 0.0)
    assert np.allclose(sim.push_force(0.010), [50.0, -20.0, 5.0])
    assert np.allclose(sim.push_force(0.0299), [50.0, -20.0, 5.0])
    assert np.allclose(sim.push_force(0.030), 0.0)
    res = sim.run(0.05)
    t, f = res.log["t"], res.log["push"]
    inside = (t >= 0.010 - 1e-9) & (t < 0.030 - 1e-9)
    assert inside.sum() == 40  # 20 ms at 2 kHz
    assert np.allclose(f[inside], [50.0, -20.0, 5.0])
    assert np.allclose(f[~inside], 0.0)
    # the force acts on the base body only, and is cleared after the window
    assert np.allclose(sim.data.xfrc_applied, 0.0)


def test_push_changes_base_motion_on_the_base():
    quiet = _sim("cassie", duration=0.03).run(0.03)
    pushed = _sim("cassie", duration=0.03, pushes=[Push(0.0, (300.0, 0.0, 0.0), 0.03)]).run(0.03)
    dx = pushed.log["base_pos"][-1, 0] - quiet.log["base_pos"][-1, 0]
    assert dx > 1e-4  # pushed forward


def test_pushes_sum_when_overlapping():
    sim = _sim("rabbit", pushes=[Push(0.0, (10.0, 0.0, 0.0), 0.02), Push(0.01, (5.0, 0.0, 1.0), 0.02)])
    assert np.allclose(sim.push_force(0.015), [15.0, 0.0, 1.0])


@pytest.mark.parametrize("robot", ["cassie", "rabbit"])
def test_contact_switches_on_when_standing(robot):
    sim = _sim(robot, tracker_cls=HoldTracker, duration=0.1)
    res = sim.run(0.1)
    assert not res.fell
    assert sim.foot_contact() == {"left": True, "right": True}


def test_noise_is_deterministic_for_a_seed():
    a = _sim("cassie", noise=SensorNoise(), seed=7)
    b = _sim("cassie", noise=SensorNoise(), seed=7)
    c = _sim("cassie", noise=SensorNoise(), seed=8)
    ma, mb, mc = a.measure(), b.measure(), c.measure()
    assert np.array_equal(ma.q, mb.q) and np.array_equal(ma.v, mb.v)
    assert not np.array_equal(ma.q, mc.q)
    exact = _sim("cassie").measure()
    assert 0 < np.max(np.abs(ma.v - exact.v)) < 1.0
    ra = a.run(0.02)
    rb = b.run(0.02)
    for key in ("com", "L", "tau", "h"):
        assert np.array_equal(ra.log[key], rb.log[key])


def test_on_tick_hook_and_log_keys():
    seen = []
    sim = _sim("rabbit", duration=0.01)
    res = sim.run(0.01, on_tick=lambda t, d: seen.append(t))
    assert len(seen) == res.log["t"].size == 20
    assert np.allclose(np.diff(seen), 0.0005)
    assert seen[0] == pytest.approx(res.log["t"][0] + 0.0005)
    for key in ("p_st", "t_remaining", "base_yaw"):
        assert res.log[key].shape[0] == 20
    assert np.all(res.log["p_st"][:, 2] > 0.5)  # CoM well above the stance contact
    assert np.allclose(res.log["t_remaining"], np.maximum(0.35 - res.log["t"], 0.0))
    assert res.info["output_names"] == ("torso_pitch", "com_z_over_stance", "com_x_over_swing", "com_z_over_swing")
    assert len(res.info["actuator_names"]) == 4 and res.info["planar"] is True


def test_run_rejects_bad_duration():
    with pytest.raises(InputError):
        _sim("rabbit").run(float("nan"))


def test_run_rejects_a_duration_below_one_tick_and_a_negative_seed():
    with pytest.raises(InputError, match="shorter than one control tick"):
        _sim("rabbit").run(1e-9)
    with pytest.raises(InputError, match="seed"):
        _sim("rabbit", seed=-1)


def test_a_diverging_simulation_is_a_fall_not_a_restart():
    # MuJoCo resets an unstable state to qpos0 and restarts its clock; the
    # harness must report that as a fall at the tick it happened.
    sim = _sim("cassie", pushes=[Push(0.004, (1e300, 0.0, 0.0), 0.01)])
    res = sim.run(0.02)
    assert res.fell
    assert res.fall_time_s == pytest.approx(0.004, abs=1e-3)
    assert res.sim_time_s <= 0.006
    assert np.all(np.diff(res.log["t"]) > 0)
    # Again on the same data: MuJoCo's warning counter is already 1 from the first run and
    # its reset sets it to 1 again; the second divergence is still a fall, on MuJoCo's clock.
    again = sim.run(0.02)
    assert again.fell
    assert again.fall_time_s == pytest.approx(0.004, abs=1e-3)
    assert again.sim_time_s <= 0.006


def _controller_base_log(sim, duration_s, **run_options):
    """A run and the world base state of the controller's kinematics after each tick (as the log's ``*_est``)."""
    from amlip_qp.sim.loop.run_log import world_base
    from amlip_qp.sim.sensing.sensors import base_indices

    rows, kin, (bq, bv) = [], sim.controller.kin, base_indices(sim.robot)

    def keep(t_s, data):
        q, v = kin.state()
        rows.append(np.concatenate((q[bq], v[bv])))

    res = sim.run(duration_s, on_tick=keep, **run_options)
    return res, world_base(np.array(rows), "est")


def test_the_estimated_base_is_the_controllers_with_and_without_noise():
    """The logged ``*_est`` is what the controller's kinematics held, also where the harness logs it from the truth."""
    for noise in (None, SensorNoise()):
        sim = _sim("cassie", tracker_cls=HoldTracker, duration=0.05, noise=noise)
        res, kept = _controller_base_log(sim, 0.05)
        for key, value in kept.items():
            assert np.array_equal(res.log[key], value), key
        same = np.array_equal(res.log["base_vel_true"], res.log["base_vel_est"])
        assert same == (noise is None)


def test_the_true_and_estimated_base_are_logged_and_equal_with_the_truth():
    sim = _sim("cassie", tracker_cls=HoldTracker, duration=0.2)
    res = sim.run(0.2)
    log = res.log
    for key in ("base_pos", "base_vel", "base_yaw"):
        assert np.array_equal(log[f"{key}_true"], log[f"{key}_est"])
    # the world velocity is the derivative of the position (MuJoCo's semi-implicit Euler: p' = p + dt v')
    dp = np.diff(log["base_pos_true"], axis=0) / 0.0005
    assert np.allclose(dp, log["base_vel_true"][1:], atol=1e-9)
    assert np.max(np.abs(log["base_vel_true"])) > 0.01  # it settles: not a trivial zero
    assert np.allclose(log["base_yaw_true"], log["base_yaw"], atol=1e-3)
    summ_info = (res.info["plant"], res.info["sensors"], res.info["estimator"])
    assert summ_info == ("cassie", "ideal", "truth") and res.safe_mode_ticks == 0
    rabbit = _sim("rabbit", duration=0.01).run(0.01)
    assert "base_vel_true" not in rabbit.log  # planar: no free-flyer base to log


def test_the_control_filter_sees_every_tick_s_controls_before_the_plant():
    seen = []

    def zero(ctrl):
        seen.append(ctrl.copy())
        return np.zeros_like(ctrl)

    robot = factory.load("cassie")
    sim = factory.build_simulation(Scenario("test", "cassie", 0.01), HoldTracker(robot))
    sim.ctrl_filter = zero
    res = sim.run(0.01)
    assert len(seen) == 20 and np.all(sim.data.ctrl == 0.0)
    assert np.allclose(seen[-1] * sim.plant.gear, np.clip(res.log["tau"][-1], *robot.actuated.torque_limit_Nm.T))


def test_robot_sensors_and_a_plant_of_another_layout(tmp_path):
    """A slide+ball-floated plant with the robot sensors: the robot stands, the truth reaches the controller."""
    from amlip_qp.sim.world.plant_loader import load_plant
    from plant_cases import slide_ball_spec, write_plant

    robot = factory.load("cassie")
    plant = load_plant(write_plant(slide_ball_spec(), tmp_path / "slide_ball.xml"), robot)
    sc = Scenario("test", "cassie", 0.2)
    sim = factory.build_simulation(sc, HoldTracker(robot), seed=2, plant=plant, sensors="robot")
    res = sim.run(0.2)
    assert not res.fell and sim.foot_contact() == {"left": True, "right": True}
    assert res.info["sensors"] == "robot" and res.info["plant"].endswith("slide_ball.xml")
    assert np.array_equal(res.log["base_vel_true"], res.log["base_vel_est"])  # truth: the true base
    meas = sim.measure()
    assert meas.base_known and meas.imu is not None and np.all(np.isfinite(meas.q))


def test_without_the_truth_the_measurement_has_no_base():
    from amlip_qp.sim.loop.harness import Simulation

    sim = _sim("cassie")
    blind = Simulation(sim.robot, sim.controller, sim.command_fn, plant=sim.plant, sensors="robot", estimator="ekf")
    meas = blind.measure()
    assert not meas.base_known and np.all(np.isnan(meas.q[:7])) and np.all(np.isnan(meas.v[:6]))
    assert np.all(np.isfinite(meas.q[7:])) and np.all(np.isfinite(meas.imu.accel_mps2))


def test_gaussian_noise_is_for_the_ideal_sensors_only():
    with pytest.raises(InputError, match="robot sensors have their own"):
        factory.build_simulation(Scenario("test", "cassie", 0.01), "qp", noise=SensorNoise(), sensors="robot")


def test_plant_edits_and_the_control_filter_reach_the_plant_through_the_factory():
    def heavy_pelvis(spec):
        spec.body("cassie-pelvis").mass = 20.0

    def halve(ctrl):
        return 0.5 * ctrl

    robot = factory.load("cassie")
    sc = Scenario("test", "cassie", 0.01)
    sim = factory.build_simulation(sc, HoldTracker(robot), plant_edits=[heavy_pelvis], ctrl_filter=halve)
    assert sim.model.body_mass[sim.plant.base_body_id] == 20.0 and sim.ctrl_filter is halve
    with pytest.raises(InputError, match="give the plant by name or path"):
        factory.build_simulation(sc, HoldTracker(robot), plant=sim.plant, plant_edits=[heavy_pelvis])


@pytest.mark.parametrize("robot", ["cassie", "rabbit"])
def test_the_summary_log_walks_the_same_trajectory_and_keeps_what_the_summary_reads(robot):
    from amlip_qp.sim.loop.run_log import SUMMARY_LOG_KEYS
    from amlip_qp.sim.reports.summary import TIMING_FIELDS, summarize, to_jsonable

    runs = {}
    for mode in ("full", "summary"):
        sim = _sim(robot, tracker_cls=HoldTracker, duration=0.1, pushes=[Push(0.02, (40.0, 20.0, 0.0), 0.03)])
        res = sim.run(0.1, log=mode)
        runs[mode] = (res, sim.data.qpos.copy(), sim.data.qvel.copy())
    (full, qpos_f, qvel_f), (short, qpos_s, qvel_s) = runs["full"], runs["summary"]
    assert np.array_equal(qpos_f, qpos_s) and np.array_equal(qvel_f, qvel_s)  # the same final state
    floating = robot == "cassie"
    expected = {k for k in SUMMARY_LOG_KEYS if floating or not k.startswith("base_") or k == "base_yaw"}
    assert set(short.log) == expected and set(full.log) > expected and "push" in full.log
    for key in expected:
        assert np.array_equal(short.log[key], full.log[key]), key
    assert short.info["log"] == "summary" and full.info["log"] == "full"

    def numbers(res):
        return to_jsonable({k: v for k, v in summarize(res).items() if k not in TIMING_FIELDS})

    assert numbers(short) == numbers(full)
    # the summary reads nothing else: a full log cut to those keys summarises the same
    full.log = {k: v for k, v in full.log.items() if k in expected}
    assert numbers(full) == numbers(short)


def test_each_tick_is_timed_in_three_parts_and_an_unknown_log_mode_is_refused():
    res = _sim("rabbit", duration=0.02).run(0.02)
    n = res.log["t"].size
    for times in (res.tick_time_us, res.mujoco_time_us, res.harness_time_us):
        assert times.shape == (n,) and np.all(np.isfinite(times)) and np.all(times > 0.0)
    with pytest.raises(InputError, match="log must be one of full, summary"):
        _sim("rabbit").run(0.01, log="npz")


def test_a_fall_is_found_at_the_same_tick_in_both_log_modes():
    falls = []
    for mode in ("full", "summary"):
        sim = _sim("cassie", duration=0.5, pushes=[Push(0.0, (0.0, 2000.0, 0.0), 0.1)])  # knocked over
        res = sim.run(0.5, log=mode)
        falls.append((res.fell, res.fall_time_s, res.log["t"].size, res.harness_time_us.size))
    assert falls[0] == falls[1] and falls[0][0]


@pytest.mark.slow
def test_a_qp_walk_is_the_same_in_both_log_modes():
    from amlip_qp.sim.loop.run_log import SUMMARY_LOG_KEYS
    from amlip_qp.sim.scenarios.named import get_scenario

    runs = {}
    for mode in ("full", "summary"):
        sim = factory.build_simulation(get_scenario("cassie-1mps").with_(duration_s=1.0), "qp")
        runs[mode] = (sim.run(1.0, log=mode), sim.data.qpos.copy())
    (full, qpos_f), (short, qpos_s) = runs["full"], runs["summary"]
    assert np.array_equal(qpos_f, qpos_s) and not full.fell and len(full.steps) == len(short.steps) > 0
    for key in SUMMARY_LOG_KEYS:
        assert np.array_equal(full.log[key], short.log[key]), key


def test_the_fall_check_measures_the_base_height_above_the_ground_under_it():
    from amlip_qp.sim.loop.harness import Simulation
    from amlip_qp.sim.loop.run_types import PlantSetting

    # a terrain reaches the harness through the factory: its analytic height
    sc = Scenario("test", "cassie", 0.01, setting=PlantSetting(terrain="slope:10"))
    robot = factory.load("cassie")
    sim = factory.build_simulation(sc, HoldTracker(robot))
    assert sim.ground_height_m is not None and sim.ground_height_m(3.0, 0.0) > 0.3
    assert factory.build_simulation(Scenario("test", "cassie", 0.01), HoldTracker(robot)).ground_height_m is None
    # standing still: ground at a constant height is no fall (the height above it is what counts) ...
    level = Simulation(robot, sim.controller, sim.command_fn, plant=sim.plant, ground_height_m=lambda x, y: 0.5)
    assert not level.run(0.02).fell
    # ... ground rising to the base after the start value is taken is a fall at the first tick
    heights = iter([0.0])
    rising = Simulation(
        robot, sim.controller, sim.command_fn, plant=sim.plant, ground_height_m=lambda x, y: next(heights, 0.9)
    )
    res = rising.run(0.02)
    assert res.fell and res.fall_time_s == 0.0


def test_the_tilt_fall_is_the_first_tick_whose_tilt_is_over_the_limit_for_any_limit():
    from amlip_qp.sim.loop.run_types import FallCriteria

    def knocked_over(max_tilt_rad):
        sim = _sim("cassie", duration=0.4, pushes=[Push(0.0, (0.0, 2000.0, 0.0), 0.1)])
        sim.fall = FallCriteria(min_height_fraction=-1e9, max_tilt_rad=max_tilt_rad)  # the tilt alone
        return sim.run(0.4)

    tilt = knocked_over(math.inf).log["base_tilt"]
    assert tilt.size == 800 and tilt[0] < 0.05 < 1.5 < tilt.max()
    limits = (-math.inf, -1.0, 0.0, 0.3, 1.0, float(tilt[400]), math.pi, math.inf, math.nan)
    for limit in limits:
        res = knocked_over(limit)
        over = np.flatnonzero(tilt > limit)
        assert res.fell == (over.size > 0), limit
        assert res.log["t"].size == (over[0] + 1 if over.size else tilt.size), limit


@pytest.mark.parametrize("plant_step_s", [0.0005, 0.00025, 0.0005 / 3])
def test_the_clock_is_mujocos_at_every_tick_with_one_or_more_plant_steps_a_tick(plant_step_s):
    """The harness counts MuJoCo's clock (``time += timestep`` a step) instead of reading it: the same floats."""
    from amlip_qp.sim.world.plant_loader import load_plant

    robot = factory.load("cassie")
    plant = load_plant("cassie", robot, edits=[lambda spec: setattr(spec.option, "timestep", plant_step_s)])
    sim = factory.build_simulation(Scenario("test", "cassie", 0.02), HoldTracker(robot), plant=plant)
    times = []
    res = sim.run(0.02, on_tick=lambda t, d: times.append((t, d.time)))
    assert sim.substeps == round(0.0005 / plant_step_s) and len(times) == 40 and not res.fell
    assert all(t == clock for t, clock in times) and res.sim_time_s == sim.data.time
    assert res.log["t"].tolist() == [0.0] + [t for t, _ in times[:-1]]
