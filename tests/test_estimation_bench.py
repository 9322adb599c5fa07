"""estimation.bench: per-tick EKF costs for `amlip-qp bench` (shape and validity; no timing asserted)."""

import numpy as np
import pytest

from amlip_qp.estimation.bench import stand_in_measurements, time_ekf
from amlip_qp.exceptions import InputError
from amlip_qp.robots import load_robot


@pytest.fixture(scope="module")
def cassie():
    return load_robot("cassie")


def test_time_ekf_returns_one_positive_time_per_tick(cassie):
    t = time_ekf(cassie, [0.03, 0.0, 0.09], n_ticks=50, backend="numpy")
    assert t.shape == (50,) and np.isfinite(t).all() and (t > 0).all()
    ms = stand_in_measurements(cassie, 20)
    assert time_ekf(cassie, [0.03, 0.0, 0.09], measurements=ms, backend="c").shape == (20,)
    with pytest.raises(InputError, match="n_ticks"):
        time_ekf(cassie, [0.03, 0.0, 0.09], n_ticks=0)


def test_the_stand_in_sequence_goes_through_single_support(cassie):
    ms = stand_in_measurements(cassie, 1200)
    patterns = {(m.foot_contact["left"], m.foot_contact["right"]) for m in ms}
    assert patterns == {(True, True), (True, False), (False, True)}
