"""WalkingController: the never-NaN torque guarantee, saturation, the step clock, the speed correction."""

import numpy as np
import pytest

from amlip_qp.control.tracker import Tracker
from amlip_qp.control.walking.controller import WalkingController
from amlip_qp.exceptions import InputError
from amlip_qp.messages import Command, Measurement, TrackerResult
from amlip_qp.robots import RobotKinematics, load_robot


class _NaNTracker(Tracker):
    name = "nan"

    def __init__(self, nu):
        self.nu = nu

    def compute(self, kin, target):
        return TrackerResult(tau_Nm=np.full(self.nu, np.nan))


class _HugeTracker(_NaNTracker):
    name = "huge"

    def compute(self, kin, target):
        return TrackerResult(tau_Nm=np.full(self.nu, 1e6))


@pytest.fixture(scope="module")
def rabbit():
    return load_robot("rabbit")


def _tick(robot, tracker, v):
    ctrl = WalkingController(robot, tracker, RobotKinematics(robot), planner_backend="numpy")
    cmd = Command(step_time_s=0.35, com_height_m=0.68, clearance_m=0.06)
    return ctrl, ctrl.step(Measurement(0.0, robot.q_stand.copy(), v), cmd)


def test_nan_torques_become_the_damped_fallback_and_are_counted(rabbit):
    v = np.zeros(rabbit.nv)
    v[rabbit.actuated.pin_v_idx] = [1.0, -2.0, 0.5, 0.0]
    with pytest.warns(RuntimeWarning, match="non-finite torques"):
        ctrl, tick = _tick(rabbit, _NaNTracker(rabbit.nu), v)
    assert ctrl.fallback_ticks == 1 and not tick.tracker_ok
    np.testing.assert_allclose(tick.tau_Nm, -5.0 * np.array([1.0, -2.0, 0.5, 0.0]))


def test_torques_saturate_at_the_motor_limits(rabbit):
    _, tick = _tick(rabbit, _HugeTracker(rabbit.nu), np.zeros(rabbit.nv))
    np.testing.assert_allclose(tick.tau_Nm, rabbit.actuated.torque_limit_Nm[:, 1])


def test_the_planner_is_chosen_by_name_and_bad_names_are_typed_errors(rabbit):
    from amlip_qp.alip.mpc_planner import MPCPlanner, MPCSettings
    from amlip_qp.alip.planner import Planner
    from amlip_qp.cli.subcommands import PLANNERS as CLI_PLANNERS
    from amlip_qp.control.walking.planners import PLANNERS

    assert CLI_PLANNERS == PLANNERS == ("one-step", "mpc")
    kin = RobotKinematics(rabbit)
    one = WalkingController(rabbit, _HugeTracker(4), kin, planner_backend="numpy")
    assert type(one.planner) is Planner
    mpc = WalkingController(rabbit, _HugeTracker(4), kin, planner_backend="numpy", planner="mpc")
    assert isinstance(mpc.planner, MPCPlanner) and mpc.planner.clock is mpc.clock
    cmd = Command(step_time_s=0.35, com_height_m=0.68, clearance_m=0.06)
    tick = mpc.step(Measurement(0.0, rabbit.q_stand.copy(), np.zeros(rabbit.nv)), cmd)
    assert mpc.planner.last_plan.solved and np.isfinite(tick.tau_Nm).all()
    assert mpc.clock.planned_step_time_s == pytest.approx(mpc.planner.last_plan.step_time_s)
    with pytest.raises(InputError, match="planner must be one of"):
        WalkingController(rabbit, _HugeTracker(4), kin, planner="two-step")
    with pytest.raises(InputError, match="pass planner='mpc'"):
        WalkingController(rabbit, _HugeTracker(4), kin, mpc_settings=MPCSettings())


def test_the_mpc_plans_no_step_shorter_than_the_tracker_follows(rabbit):
    """The tracker's ``shortest_step_s`` becomes the MPC's ``step_time_min_s`` (a larger one given stays)."""
    from amlip_qp.alip.mpc_planner import MPCSettings

    class _Slow(_HugeTracker):
        shortest_step_s = 0.21

    kin = RobotKinematics(rabbit)
    plain = WalkingController(rabbit, _HugeTracker(4), kin, planner_backend="numpy", planner="mpc")
    assert plain.planner.settings == MPCSettings()  # a tracker without a bound: the MPC's own settings
    slow = WalkingController(rabbit, _Slow(4), kin, planner_backend="numpy", planner="mpc")
    assert slow.planner.settings == MPCSettings(step_time_min_s=0.21)
    given = MPCSettings(step_time_min_s=0.3, weight_time=8.0)
    kept = WalkingController(rabbit, _Slow(4), kin, planner_backend="numpy", planner="mpc", mpc_settings=given)
    assert kept.planner.settings == given


def test_bad_initial_stance_and_backend_are_typed_errors(rabbit):
    kin = RobotKinematics(rabbit)
    with pytest.raises(InputError, match="initial_stance"):
        WalkingController(rabbit, _NaNTracker(4), kin, initial_stance="middle")
    with pytest.raises(InputError, match="planner_backend"):
        WalkingController(rabbit, _NaNTracker(4), kin, planner_backend="fortran")


def test_finite_but_huge_torques_are_saturated_not_replaced(rabbit):
    """Torques whose sum overflows are still finite: saturated, no fallback."""

    class _Enormous(_NaNTracker):
        def compute(self, kin, target):
            return TrackerResult(tau_Nm=np.full(self.nu, 1e308))

    ctrl, tick = _tick(rabbit, _Enormous(rabbit.nu), np.zeros(rabbit.nv))
    assert ctrl.fallback_ticks == 0 and tick.tracker_ok
    np.testing.assert_allclose(tick.tau_Nm, rabbit.actuated.torque_limit_Nm[:, 1])


def test_the_planner_sees_the_command_plus_the_speed_correction(rabbit):
    ctrl = WalkingController(rabbit, _HugeTracker(rabbit.nu), RobotKinematics(rabbit), planner_backend="numpy")
    cmd = Command(step_time_s=0.35, com_height_m=0.68, clearance_m=0.06, vx_mps=0.5, vy_mps=0.0)
    q, v = rabbit.q_stand.copy(), np.zeros(rabbit.nv)
    first = ctrl.step(Measurement(0.0, q, v, {"left": True, "right": True}), cmd)
    ctrl.reset()
    ctrl.corrector.correction_mps[:] = (0.25, 0.0)
    np.testing.assert_array_equal(ctrl.speed_correction_mps, [0.25, 0.0])
    faster = ctrl.step(Measurement(0.0, q, v, {"left": True, "right": True}), cmd)
    # The forward speed enters the desired momentum and thus the foot placement.
    assert faster.plan.L_des_Nms[1] > first.plan.L_des_Nms[1]
    ctrl.reset()
    assert not ctrl.speed_correction_mps.any()


def test_the_clock_starts_the_steps_the_planner_starts(rabbit):
    """One step clock: the planner holds the controller's clock and starts its steps; it switches at touchdown."""
    ctrl = WalkingController(rabbit, _HugeTracker(rabbit.nu), RobotKinematics(rabbit), planner_backend="numpy")
    cmd = Command(step_time_s=0.35, com_height_m=0.68, clearance_m=0.06)
    q, v = rabbit.q_stand.copy(), np.zeros(rabbit.nv)
    assert ctrl.stance is None
    first = ctrl.step(Measurement(0.1, q, v, {"left": True, "right": True}), cmd)
    assert first.stance == ctrl.clock.stance == ctrl.planner.stance == "left"
    assert ctrl.planner.clock is ctrl.clock and ctrl.clock.t_start_s == 0.1
    # before the minimum phase a contact does not end the step; after it, it does
    early = ctrl.step(Measurement(0.1 + 0.3 * 0.35, q, v, {"left": True, "right": True}), cmd)
    assert not early.touchdown and early.phase == pytest.approx(0.3)
    t_td = 0.1 + 0.8 * 0.35
    td = ctrl.step(Measurement(t_td, q, v, {"left": True, "right": True}), cmd)
    assert td.touchdown and td.stance == ctrl.clock.stance == ctrl.planner.stance == "right"
    assert ctrl.clock.t_start_s == t_td
    assert td.phase == 0.0 and len(ctrl.steps) == 1 and ctrl.steps[0].t_start_s == 0.1
    ctrl.reset()
    assert ctrl.stance is None and ctrl.clock.t_start_s == 0.0


def test_the_planner_sees_the_shaped_command(rabbit):
    from amlip_qp.profiles import NO_SHAPING, PROFILES

    v = np.zeros(rabbit.nv)

    def cmd(vx):
        return Command(step_time_s=0.35, com_height_m=0.68, clearance_m=0.06, vx_mps=vx)

    def first_tick(vx, **kwargs):
        kin = RobotKinematics(rabbit)
        ctrl = WalkingController(rabbit, _HugeTracker(rabbit.nu), kin, planner_backend="numpy", **kwargs)
        return ctrl, ctrl.step(Measurement(0.0, rabbit.q_stand.copy(), v), cmd(vx))

    ctrl, step_cmd = first_tick(1.0)
    assert ctrl.shaper.shaping is PROFILES["rabbit"].shaping
    # From rest, a 1 m/s step is shaped to 0 at the first tick: the plan of a 0 m/s command.
    _, rest = first_tick(0.0)
    np.testing.assert_array_equal(step_cmd.plan.L_des_Nms, rest.plan.L_des_Nms)
    _, unshaped = first_tick(1.0, command_shaping=NO_SHAPING)
    assert unshaped.plan.L_des_Nms[1] > rest.plan.L_des_Nms[1] + 1.0
    assert ctrl.shaper.value[0] == 0.0
    ctrl.step(Measurement(0.0005, rabbit.q_stand.copy(), v), cmd(1.0))
    assert ctrl.shaper.value[0] == pytest.approx(PROFILES["rabbit"].shaping.vx_accel_mps2 * 0.0005)
    ctrl.reset()
    assert ctrl.shaper.value == (0.0, 0.0, 0.0)


class _StubEstimator:
    """Returns the measurement with a NaN base while ``bad`` (or reports ``diverged``)."""

    def __init__(self):
        self.bad = True
        self.diverged = False
        self.resets = 0

    def fill(self, m):
        if not self.bad:
            return m
        q = m.q.copy()
        q[0] = np.nan
        return Measurement(m.t_s, q, m.v, m.foot_contact, m.imu, True)

    def reset(self):
        self.resets += 1


def _safe_ctrl(robot, estimator):
    return WalkingController(
        robot, _NaNTracker(robot.nu), RobotKinematics(robot), planner_backend="numpy", base_estimator=estimator
    )


def test_a_nan_base_estimate_runs_the_damped_safe_mode_and_never_a_nan_torque(rabbit):
    est = _StubEstimator()
    ctrl = _safe_ctrl(rabbit, est)
    cmd = Command(step_time_s=0.35, com_height_m=0.68, clearance_m=0.06)
    v = np.zeros(rabbit.nv)
    v[rabbit.actuated.pin_v_idx] = [1.0, -2.0, 0.5, 0.0]
    with pytest.warns(RuntimeWarning, match="safe mode"):
        tick = ctrl.step(Measurement(0.0, rabbit.q_stand.copy(), v), cmd)
    np.testing.assert_allclose(tick.tau_Nm, -5.0 * np.array([1.0, -2.0, 0.5, 0.0]))
    assert not tick.tracker_ok and ctrl.fallback_ticks == 0  # the tracker was not called
    assert ctrl.safe_mode_ticks == 1 and ctrl.estimator_divergences == 1
    v_nan = v.copy()
    v_nan[rabbit.actuated.pin_v_idx[0]] = np.nan  # non-finite encoders: zero torque
    tick = ctrl.step(Measurement(0.0005, rabbit.q_stand.copy(), v_nan), cmd)
    np.testing.assert_array_equal(tick.tau_Nm, np.zeros(rabbit.nu))
    assert ctrl.safe_mode_ticks == 2 and ctrl.estimator_divergences == 1  # one event, two ticks
    assert np.isnan(tick.plan.h_d).all() and np.isnan(tick.estimate.com_m).all()


def test_each_entry_into_the_safe_mode_counts_and_warns_once(rabbit):
    import warnings

    est = _StubEstimator()
    ctrl = _safe_ctrl(rabbit, est)
    ctrl.tracker = _HugeTracker(rabbit.nu)
    cmd = Command(step_time_s=0.35, com_height_m=0.68, clearance_m=0.06)
    v = np.zeros(rabbit.nv)
    with pytest.warns(RuntimeWarning, match="safe mode"):
        ctrl.step(Measurement(0.0, rabbit.q_stand.copy(), v), cmd)
    est.bad = False
    tick = ctrl.step(Measurement(0.0005, rabbit.q_stand.copy(), v), cmd)
    np.testing.assert_allclose(tick.tau_Nm, rabbit.actuated.torque_limit_Nm[:, 1])  # the tracker ran again
    est.diverged = True  # a diverged estimator with a finite base: safe mode too
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        tick = ctrl.step(Measurement(0.001, rabbit.q_stand.copy(), v), cmd)
    np.testing.assert_array_equal(tick.tau_Nm, np.zeros(rabbit.nu))
    assert ctrl.safe_mode_ticks == 2 and ctrl.estimator_divergences == 2
    ctrl.reset()
    assert ctrl.safe_mode_ticks == 0 and ctrl.estimator_divergences == 0 and est.resets == 1


def test_the_default_base_estimator_is_the_truth(rabbit):
    from amlip_qp.estimation import TruthBaseEstimator

    ctrl, _ = _tick(rabbit, _HugeTracker(rabbit.nu), np.zeros(rabbit.nv))
    assert isinstance(ctrl.base_estimator, TruthBaseEstimator) and ctrl.safe_mode_ticks == 0
