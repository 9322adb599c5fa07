"""``amlip_qp.MujocoLoop``: the controller on a MuJoCo model and data the user steps.

On the robot's own model it walks the harness's walk bit for bit; on a model
compiled from the same file with its actuators in another order, the same walk;
bad models, data and calls are refused in one line; the controls are always finite.
"""

from __future__ import annotations

import warnings

import mujoco
import numpy as np
import pytest

import amlip_qp
from amlip_qp.control import registry
from amlip_qp.control.tracker import Tracker
from amlip_qp.exceptions import InputError, PlantMismatchError
from amlip_qp.messages import TrackerResult
from amlip_qp.paths import MODELS_DIR
from amlip_qp.robots import RobotKinematics
from amlip_qp.sim.scenarios import factory
from amlip_qp.sim.scenarios.scenarios import Scenario
from amlip_qp.sim.scenarios.speed_profile import SpeedProfile


@pytest.fixture(scope="module")
def cassie():
    return factory.load("cassie")


@pytest.fixture(scope="module")
def rabbit():
    return factory.load("rabbit")


class NaNTracker(Tracker):
    """Returns NaN torques: the controller must fall back."""

    name = "nan"

    def __init__(self, robot):
        self.robot = robot

    def compute(self, kin, target):
        return TrackerResult(tau_Nm=np.full(self.robot.nu, np.nan))


def _walk(loop, command, ticks):
    """``ticks`` control ticks of ``loop`` (one MuJoCo step each); the base positions after each step."""
    base = []
    for _ in range(ticks):
        loop.step(command)
        mujoco.mj_step(loop.model, loop.data)
        base.append(loop.data.qpos[:3].copy())
    return np.array(base)


@pytest.mark.parametrize(("robot_name", "tracker"), [("cassie", "qp"), ("rabbit", "pbc")])
def test_on_the_robots_own_model_the_loop_walks_the_harness_walk_bit_for_bit(robot_name, tracker):
    scenario = Scenario("walk", robot_name, 0.5, vx=SpeedProfile.constant(0.5))
    sim = factory.build_simulation(scenario, tracker)
    result = sim.run(scenario.duration_s, log="summary")
    robot = sim.robot
    data = robot.new_mj_data("stand")
    loop = amlip_qp.MujocoLoop(robot, registry.make_tracker(tracker, robot), robot.mj_model, data)
    command = loop.command(vx_mps=0.5)
    assert command == scenario.command(0.0)  # the profile's gait
    taus = []
    for _ in range(1000):
        taus.append(loop.step(command).tau_Nm.copy())
        mujoco.mj_step(robot.mj_model, data)
    assert len(loop.controller.steps) == len(result.steps) >= 1  # a touchdown in 0.5 s
    assert np.array_equal(np.array(taus), result.log["tau"])
    assert np.array_equal(data.qpos, sim.data.qpos) and np.array_equal(data.qvel, sim.data.qvel)


def test_a_model_with_its_actuators_in_another_order_walks_the_same(cassie):
    spec = mujoco.MjSpec.from_file(str(cassie.path))
    kept = [(a.name, list(a.gear), list(a.ctrlrange), a.ctrllimited) for a in spec.actuators]
    for a in list(spec.actuators):
        spec.delete(a)
    for name, gear, ctrlrange, limited in reversed(kept):
        spec.add_actuator(
            name=name, target=name, trntype=mujoco.mjtTrn.mjTRN_JOINT, gear=gear, ctrlrange=ctrlrange,
            ctrllimited=limited,
        )  # fmt: skip
    model = spec.compile()
    assert [mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_ACTUATOR, 0)] == [cassie.actuated.names[-1]]
    runs, ctrls = [], []
    for m in (cassie.mj_model, model):
        data = mujoco.MjData(m)
        mujoco.mj_resetDataKeyframe(m, data, mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_KEY, "stand"))
        mujoco.mj_forward(m, data)
        loop = amlip_qp.MujocoLoop(cassie, registry.make_tracker("qp", cassie), m, data)
        runs.append(_walk(loop, loop.command(vx_mps=0.5), 700))
        assert len(loop.controller.steps) == 1  # a touchdown at about 0.3 s
        lo, hi = cassie.actuated.ctrl_range.T
        assert np.all(loop.ctrl >= lo) and np.all(loop.ctrl <= hi) and np.isfinite(data.ctrl).all()
        ctrls.append(data.ctrl.copy())
    assert np.array_equal(runs[1], runs[0])
    assert np.array_equal(ctrls[1], ctrls[0][::-1]) and not np.array_equal(ctrls[1], ctrls[0])  # by name


def test_a_model_without_an_actuator_or_a_joint_is_named_in_one_line(cassie):
    spec = mujoco.MjSpec.from_file(str(cassie.path))
    spec.delete(spec.actuator("left-knee"))
    spec.joint("right-shin").name = "right-shin-spring"
    model = spec.compile()
    with pytest.raises(PlantMismatchError) as err:
        amlip_qp.MujocoLoop(cassie, NaNTracker(cassie), model, mujoco.MjData(model))
    msg = str(err.value)
    assert "\n" not in msg and isinstance(err.value, InputError)
    assert msg.startswith("plant MjModel 'cassie' does not fit the cassie controller")
    assert "actuator 'left-knee'" in msg and "joint 'right-shin'" in msg


def test_bad_data_timesteps_and_controllers_are_refused_in_one_line(cassie, rabbit):
    model = cassie.mj_model
    tracker = NaNTracker(cassie)
    controller = amlip_qp.WalkingController(cassie, tracker, RobotKinematics(cassie))
    cases = [
        ((cassie, tracker, model, rabbit.new_mj_data()), "data was not made for model"),
        ((cassie, tracker, model, mujoco.MjData(mujoco.MjModel.from_xml_path(str(cassie.path)))), "not made for"),
        ((cassie, tracker, "cassie.xml", cassie.new_mj_data()), "needs a mujoco.MjModel and its mujoco.MjData"),
        ((cassie, NaNTracker(rabbit), model, cassie.new_mj_data()), "tracker 'nan' was built for another robot"),
        ((cassie, "qp", model, cassie.new_mj_data()), "controller must be a tracker"),
        ((rabbit, tracker, model, cassie.new_mj_data()), "tracker 'nan' was built for another robot"),
        ((rabbit, controller, rabbit.mj_model, rabbit.new_mj_data()), "controller was built for another robot"),
    ]
    for args, message in cases:
        with pytest.raises(InputError, match=message) as err:
            amlip_qp.MujocoLoop(*args)
        assert "\n" not in str(err.value)
    slow = mujoco.MjModel.from_xml_path(str(cassie.path))
    slow.opt.timestep = 0.0002  # 2.5 steps per 0.5 ms control tick
    with pytest.raises(InputError, match=r"control period \(0.0005 s\) must be a whole multiple of the plant step"):
        amlip_qp.MujocoLoop(cassie, tracker, slow, mujoco.MjData(slow))
    with pytest.raises(InputError, match="contact_threshold_N must be a finite force"):
        amlip_qp.MujocoLoop(cassie, tracker, model, cassie.new_mj_data(), contact_threshold_N=float("nan"))


def test_a_coarser_timestep_takes_whole_steps_per_tick(rabbit):
    model = mujoco.MjModel.from_xml_path(str(rabbit.path))
    model.opt.timestep = 0.00025
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_KEY, "stand"))
    loop = amlip_qp.MujocoLoop(rabbit, registry.make_tracker("pbc", rabbit), model, data)
    assert loop.substeps == 2
    loop.step(loop.command())
    mujoco.mj_step(model, data)  # one step of two: half a control period
    with pytest.raises(InputError, match=r"one control tick per 0.0005 s .*\(2 mj_step between calls\)"):
        loop.step(loop.command())
    mujoco.mj_step(model, data)
    loop.step(loop.command())  # now on time


def test_each_call_is_one_tick_later_and_reset_starts_over(rabbit):
    data = rabbit.new_mj_data("stand")
    loop = amlip_qp.MujocoLoop(rabbit, registry.make_tracker("pbc", rabbit), rabbit.mj_model, data)
    command = loop.command(vx_mps=0.3)
    _walk(loop, command, 800)
    assert len(loop.controller.steps) >= 1
    loop.step(command)
    with pytest.raises(InputError, match=r"data.time moved by 0 s since the last call .*call loop.reset\(\)"):
        loop.step(command)  # twice at the same time
    mujoco.mj_resetDataKeyframe(
        rabbit.mj_model, data, mujoco.mj_name2id(rabbit.mj_model, mujoco.mjtObj.mjOBJ_KEY, "stand")
    )
    with pytest.raises(InputError, match=r"data.time moved by -0.4 s"):
        loop.step(command)
    loop.reset()
    tick = loop.step(command)
    assert loop.controller.steps == [] and tick.t_s == 0.0


def test_controls_are_finite_when_the_tracker_returns_nan_and_zero_for_a_nan_state(cassie):
    data = cassie.new_mj_data("stand")
    loop = amlip_qp.MujocoLoop(cassie, NaNTracker(cassie), cassie.mj_model, data)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        _walk(loop, loop.command(), 20)
    assert loop.controller.fallback_ticks == 20  # the controller's damped fallback, every tick
    assert any("non-finite torques" in str(w.message) for w in caught)
    assert np.isfinite(data.ctrl).all()
    lo, hi = cassie.actuated.ctrl_range.T
    assert np.all(loop.ctrl >= lo) and np.all(loop.ctrl <= hi)
    assert np.any(data.ctrl != 0.0)  # damping the joints' velocities
    data.qvel[7] = np.nan  # a diverged simulation
    with pytest.raises(InputError, match=r"MujocoLoop.step: qvel contains NaN or inf at indices \[7\]") as err:
        loop.step(loop.command())
    assert "ctrl set to 0" in str(err.value) and np.array_equal(data.ctrl, np.zeros(cassie.nu))


def test_a_robot_without_a_profile_needs_its_own_command(rabbit, tmp_path):
    copy = tmp_path / "rabbit.xml"
    copy.write_text((MODELS_DIR / "rabbit.xml").read_text())
    bare = amlip_qp.load_robot(copy)
    assert bare.profile is None
    loop = amlip_qp.MujocoLoop(bare, registry.make_tracker("pbc", bare), bare.mj_model, bare.new_mj_data("stand"))
    with pytest.raises(InputError, match="rabbit has no profile and so no gait: make the Command yourself"):
        loop.command(vx_mps=0.5)
    gait = rabbit.profile.gait
    command = amlip_qp.Command(
        step_time_s=gait.step_time_s, com_height_m=gait.com_height_m, clearance_m=gait.clearance_m, vx_mps=0.5
    )
    assert np.isfinite(loop.step(command).tau_Nm).all()
    with pytest.raises(InputError, match="Command.vx_mps must be a finite number"):
        amlip_qp.MujocoLoop(rabbit, NaNTracker(rabbit), rabbit.mj_model, rabbit.new_mj_data()).command(float("inf"))
