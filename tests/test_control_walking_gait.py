"""Gait logic: touchdown detection with early, late and forced switches."""

import pytest

from amlip_qp.control.walking.gait import GaitLogic, GaitParams
from amlip_qp.exceptions import InputError


def test_no_touchdown_before_the_minimum_phase_even_with_contact():
    gait = GaitLogic(GaitParams(min_phase=0.55))
    assert not gait.touchdown(0.3, True, 0.0)
    assert gait.early == gait.late == gait.forced == 0


def test_early_touchdown_from_the_contact_switch():
    gait = GaitLogic()
    assert not gait.touchdown(0.8, False, 0.0)  # the switch wins over the height
    assert gait.touchdown(0.8, True, 0.05)
    assert (gait.early, gait.late) == (1, 0)


def test_late_touchdown_and_forced_switch():
    gait = GaitLogic(GaitParams(max_phase=1.5))
    assert gait.touchdown(1.2, True, 0.0)
    assert gait.late == 1
    assert not gait.touchdown(1.49, False, 0.1)
    assert gait.touchdown(1.5, False, 0.1)
    assert gait.forced == 1


def test_height_detection_without_contact_sensing():
    gait = GaitLogic(GaitParams(touchdown_height_m=0.01))
    assert not gait.touchdown(0.9, None, 0.02)
    assert gait.touchdown(0.9, None, 0.005)


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(min_phase=0.0), "min_phase"),
        (dict(min_phase=0.6, max_phase=0.9), "max_phase"),
        (dict(touchdown_height_m=-0.1), "touchdown_height_m"),
    ],
)
def test_bad_parameters_are_typed_errors(kwargs, match):
    with pytest.raises(InputError, match=match):
        GaitParams(**kwargs)
