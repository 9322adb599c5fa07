"""WalkingController: the speed integral, the never-NaN torque guarantee, saturation."""

import numpy as np
import pytest

from amlip_qp.alip.planner import Command
from amlip_qp.control.controller import SpeedCorrection, SpeedIntegrator, WalkingController
from amlip_qp.control.estimator import Measurement
from amlip_qp.control.tracker import Tracker, TrackerResult
from amlip_qp.exceptions import InputError
from amlip_qp.robots import RobotKinematics, load_robot


def test_integral_removes_a_constant_bias_geometrically():
    integ = SpeedIntegrator(SpeedCorrection(gain_per_step=0.3, settle_steps=0))
    bias = 0.13  # the robot walks 0.13 m/s slower than what the planner is given
    aimed = np.array([1.0, 0.0])
    for k in range(1, 16):
        v_step = aimed + integ.correction_mps - np.array([bias, 0.0])
        c = integ.update(v_step, aimed)
        assert c[0] == pytest.approx(bias * (1 - 0.7**k), rel=1e-12)
    assert c[1] == 0.0


def test_lateral_uses_the_stride_mean_so_sway_does_not_accumulate():
    integ = SpeedIntegrator(SpeedCorrection(gain_per_step=0.5, settle_steps=0))
    for k in range(20):
        sway = 0.2 if k % 2 else -0.2  # alternating per-step lateral means, zero per stride
        integ.update(np.array([0.0, sway]), np.zeros(2))
    assert integ.correction_mps[1] == pytest.approx(0.0, abs=1e-12)


def test_bounds_disturbances_settling_and_planar():
    integ = SpeedIntegrator(SpeedCorrection(gain_per_step=1.0, max_correction_mps=0.2, settle_steps=2))
    integ.update(np.array([0.0, 0.0]), np.array([0.3, 0.0]))
    integ.update(np.array([0.0, 0.0]), np.array([0.3, 0.0]))
    assert np.all(integ.correction_mps == 0.0)  # still settling
    integ.update(np.array([0.0, 0.0]), np.array([0.3, 0.0]))
    assert integ.correction_mps[0] == pytest.approx(0.2)  # clipped
    integ.update(np.array([-0.5, 0.0]), np.array([0.3, 0.0]))  # error 0.8 > 0.5: a push, ignored
    assert integ.correction_mps[0] == pytest.approx(0.2)
    planar = SpeedIntegrator(SpeedCorrection(settle_steps=0), planar=True)
    planar.update(np.array([0.0, 0.0]), np.array([0.1, 0.1]))
    assert planar.correction_mps[1] == 0.0 and planar.correction_mps[0] > 0
    off = SpeedIntegrator(SpeedCorrection(enabled=False, settle_steps=0))
    off.update(np.zeros(2), np.array([0.3, 0.0]))
    assert np.all(off.correction_mps == 0.0)


def test_bad_speed_correction_is_a_typed_error():
    with pytest.raises(InputError, match="gain_per_step"):
        SpeedCorrection(gain_per_step=1.5)


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


def test_speed_correction_is_added_to_the_command_and_cached(rabbit):
    ctrl = WalkingController(rabbit, _HugeTracker(rabbit.nu), RobotKinematics(rabbit), planner_backend="numpy")
    cmd = Command(step_time_s=0.35, com_height_m=0.68, clearance_m=0.06, vx_mps=0.5)
    assert ctrl._corrected_command(cmd) is cmd  # no correction: the command itself
    ctrl._correction[:] = (0.1, -0.05)
    c1 = ctrl._corrected_command(cmd)
    assert (c1.vx_mps, c1.vy_mps) == (0.5 + 0.1, 0.0 - 0.05) and c1.step_time_s == cmd.step_time_s
    assert ctrl._corrected_command(cmd) is c1  # same command and correction: reused
    ctrl._correction[0] = 0.2
    assert ctrl._corrected_command(cmd).vx_mps == 0.5 + 0.2
    other = Command(step_time_s=0.35, com_height_m=0.68, clearance_m=0.06, vx_mps=0.7)
    assert ctrl._corrected_command(other).vx_mps == 0.7 + 0.2


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
