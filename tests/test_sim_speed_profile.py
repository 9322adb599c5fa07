"""Tests of amlip_qp.sim.scenarios.speed_profile: parsing, and np.interp of the knots bit for bit."""

from __future__ import annotations

import math

import numpy as np
import pytest

from amlip_qp.exceptions import InputError
from amlip_qp.sim.scenarios.speed_profile import SpeedProfile


def test_speed_profile_parse_and_interpolate():
    p = SpeedProfile.parse("0:0,5:2.1")
    assert p.times_s == (0.0, 5.0) and p.speeds_mps == (0.0, 2.1)
    assert p(2.5) == pytest.approx(1.05)
    assert p(100.0) == pytest.approx(2.1) and p.final_mps == 2.1
    assert SpeedProfile.parse(" 1:0.5 ")(0.0) == 0.5  # held before the first knot too
    assert SpeedProfile.constant(0.7)(3.0) == 0.7


@pytest.mark.parametrize("text", ["", "0", "0:0,x:1", "0:0:1", "5:0,1:1", "0:0,0:1", "-1:0", "0:nan", "0:inf,1:0"])
def test_speed_profile_rejects_bad_text(text):
    with pytest.raises(InputError):
        SpeedProfile.parse(text)


def test_a_speed_profile_is_np_interp_of_its_knots_exactly():
    prof = SpeedProfile((0.0, 1.0, 3.0), (0.0, -0.0, 1.1))
    for t in (0.0, 0.5, 1.0, 2.2, 3.0, 3.0 + 1e-12, 7.0, 1e9):
        assert prof(t) == float(np.interp(t, prof.times_s, prof.speeds_mps))
    assert math.copysign(1.0, SpeedProfile((0.0,), (-0.0,))(5.0)) == -1.0  # the held value, sign and all
    assert math.copysign(1.0, prof(1.0)) == -1.0 and math.isnan(prof(math.nan))
    assert math.isnan(np.interp(math.nan, prof.times_s, prof.speeds_mps))
    rng = np.random.default_rng(4)
    for n_knots in (1, 2, 3, 5):
        for _ in range(20):
            times = np.cumsum(rng.uniform(0.01, 3.0, n_knots)) - 0.01
            prof = SpeedProfile(tuple(times.tolist()), tuple(rng.normal(0.0, 1.0, n_knots).tolist()))
            for t in np.r_[rng.uniform(-1.0, times[-1] + 1.0, 300), times].tolist():
                assert prof(t) == float(np.interp(t, prof.times_s, prof.speeds_mps))
