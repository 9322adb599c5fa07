"""SpeedIntegrator / SpeedCorrection: the per-step integral on the speed error."""

import numpy as np
import pytest

from amlip_qp.control.walking.speed import CorrectedCommand, SpeedCorrection, SpeedIntegrator
from amlip_qp.exceptions import InputError
from amlip_qp.messages import Command


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


def test_the_corrected_command_adds_the_correction_and_is_made_once_per_pair():
    corrector = CorrectedCommand()
    cmd = Command(step_time_s=0.35, com_height_m=0.68, clearance_m=0.06, vx_mps=0.5)
    assert corrector.apply(cmd) is cmd  # no correction: the command itself
    corrector.correction_mps[:] = (0.1, -0.05)
    c1 = corrector.apply(cmd)
    assert (c1.vx_mps, c1.vy_mps) == (0.5 + 0.1, 0.0 - 0.05) and c1.step_time_s == cmd.step_time_s
    assert corrector.apply(cmd) is c1  # same command and correction: reused
    corrector.correction_mps[0] = 0.2
    assert corrector.apply(cmd).vx_mps == 0.5 + 0.2
    other = Command(step_time_s=0.35, com_height_m=0.68, clearance_m=0.06, vx_mps=0.7)
    assert corrector.apply(other).vx_mps == 0.7 + 0.2
