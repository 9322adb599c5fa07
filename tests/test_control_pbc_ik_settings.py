"""Tests of the IK settings (amlip_qp.control.pbc.ik_settings)."""

import pytest

from amlip_qp.control.pbc.ik_settings import IKSettings
from amlip_qp.exceptions import InputError


def test_defaults_warm_start_with_few_iterations_and_cold_with_more():
    s = IKSettings()
    assert 1 <= s.iterations < s.cold_iterations
    assert s.knee_limit_swap and s.swap_threshold > s.tolerance


@pytest.mark.parametrize(
    "bad, match",
    [
        (dict(iterations=0), "iteration counts must be >= 1"),
        (dict(cold_iterations=0), "iteration counts must be >= 1"),
        (dict(damping=-1.0), "damping and tolerance must be >= 0"),
        (dict(max_step_rad=0.0), "max_step_rad and fd_step_s > 0"),
        (dict(fd_step_s=0.0), "max_step_rad and fd_step_s > 0"),
        (dict(tolerance=-1e-6), "damping and tolerance must be >= 0"),
    ],
)
def test_bad_settings_are_typed_errors(bad, match):
    with pytest.raises(InputError, match=match):
        IKSettings(**bad)
