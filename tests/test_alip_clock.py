"""Tests of amlip_qp.alip.clock: StepClock, the stance side, step start and phase of the current step."""

import pytest

from amlip_qp.alip.clock import StepClock
from amlip_qp.exceptions import InputError


def test_a_step_has_a_stance_a_swing_a_start_and_a_phase():
    clock = StepClock()
    assert clock.stance is None and clock.swing is None and clock.t_start_s == 0.0
    clock.start("left", 1.25)
    assert (clock.stance, clock.swing, clock.t_start_s) == ("left", "right", 1.25)
    assert clock.time_in_step(1.4) == pytest.approx(0.15)
    assert clock.phase_unclipped(1.4, 0.3) == pytest.approx(0.5)
    assert clock.phase_unclipped(1.25 + 0.45, 0.3) == pytest.approx(1.5)  # a late step: above 1
    assert clock.time_in_step(1.0) == 0.0  # before the step started: never negative
    clock.start("right", 1.6)
    assert (clock.stance, clock.swing, clock.t_start_s) == ("right", "left", 1.6)
    clock.reset()
    assert clock.stance is None and clock.t_start_s == 0.0


def test_the_phase_is_the_same_arithmetic_as_before_the_clock():
    """(t - t_start) / T exactly, so the walking loop's numbers do not change."""
    clock = StepClock()
    t0, t, T = 0.1 + 0.2, 0.7000000000000001, 0.35
    clock.start("left", t0)
    assert clock.phase_unclipped(t, T) == (t - t0) / T
    assert clock.time_in_step(t) == max(t - t0, 0.0)


def test_a_bad_side_is_a_typed_error():
    with pytest.raises(InputError, match="stance must be 'left' or 'right'"):
        StepClock().start("middle", 0.0)
