"""Tests of amlip_qp.alip.phase."""

import numpy as np
import pytest

from amlip_qp.alip import phase
from amlip_qp.exceptions import InputError


def test_phase_values():
    assert phase.step_phase(1.15, 1.0, 0.3) == pytest.approx(0.5)
    assert phase.step_phase(1.0, 1.0, 0.3) == 0.0
    assert phase.step_phase(1.3, 1.0, 0.3) == pytest.approx(1.0)
    assert phase.step_phase(1.0 + 0.3 * (1 + 1e-12), 1.0, 0.3) == 1.0  # round-off is clamped


def test_late_touchdown_is_clipped_only_on_request():
    with pytest.raises(InputError, match=r"outside \[0, 1\].*step_phase_clipped"):
        phase.step_phase(1.4, 1.0, 0.3)
    with pytest.raises(InputError, match=r"outside \[0, 1\]"):
        phase.step_phase(0.9, 1.0, 0.3)
    assert phase.step_phase_clipped(1.4, 1.0, 0.3) == 1.0
    assert phase.step_phase_clipped(0.9, 1.0, 0.3) == 0.0
    assert phase.step_phase_clipped(1.06, 1.0, 0.3) == pytest.approx(0.2)
    assert phase.step_phase(1.4, 1.0, 0.3, clip=True) == 1.0
    assert phase.time_remaining(1.4, 1.0, 0.3) == 0.0
    assert phase.time_remaining(1.1, 1.0, 0.3) == pytest.approx(0.2)


@pytest.mark.parametrize("fn", [phase.step_phase, phase.step_phase_clipped, phase.time_remaining])
def test_bad_input_raises_input_error(fn):
    with pytest.raises(InputError, match="T_s.*must be > 0"):
        fn(0.1, 0.0, 0.0)
    with pytest.raises(InputError, match="T_s.*must be > 0"):
        fn(0.1, 0.0, -0.3)
    with pytest.raises(InputError, match="t_s must be finite"):
        fn(np.nan, 0.0, 0.3)
    with pytest.raises(InputError, match="t_step_start_s must be finite"):
        fn(0.1, np.inf, 0.3)
