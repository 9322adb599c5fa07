"""Tests of amlip_qp.alip.heading: heading frames, next heading and the hip-yaw split."""

import numpy as np
import pytest

from amlip_qp.alip import heading
from amlip_qp.exceptions import InputError


def test_rotations_round_trip_and_axes():
    rng = np.random.default_rng(0)
    for _ in range(10):
        D = rng.uniform(-7, 7)
        v = rng.normal(size=2)
        w = heading.heading_to_world(v, D)
        np.testing.assert_allclose(heading.world_to_heading(w, D), v, atol=1e-12)
        np.testing.assert_allclose(heading.rotation(D) @ v, w, atol=1e-12)
        assert np.linalg.norm(w) == pytest.approx(np.linalg.norm(v))
    # The heading frame's x axis at D = 90 deg is world +y.
    np.testing.assert_allclose(heading.heading_to_world([1.0, 0.0], np.pi / 2), [0.0, 1.0], atol=1e-15)
    np.testing.assert_allclose(heading.world_to_heading([0.0, 1.0], np.pi / 2), [1.0, 0.0], atol=1e-15)
    assert heading.yaw_of([0.0, 2.0]) == pytest.approx(np.pi / 2)


def test_next_heading_and_split():
    assert heading.next_heading(0.2, 0.5, 0.4) == pytest.approx(0.4)
    assert heading.next_heading(0.2, -1.0, 0.3) == pytest.approx(-0.1)
    st, sw = heading.hip_yaw_targets(0.3)
    assert (st, sw) == (pytest.approx(-0.15), pytest.approx(0.15))
    assert sw - st == pytest.approx(0.3)


@pytest.mark.parametrize(
    "call, match",
    [
        (lambda: heading.next_heading(0.0, 1.0, 0.0), "T_s.*must be > 0"),
        (lambda: heading.next_heading(0.0, np.nan, 0.3), "turn_rate_radps must be finite"),
        (lambda: heading.heading_to_world([1.0, 2.0, 3.0], 0.0), r"shape \(2,\)"),
        (lambda: heading.world_to_heading([1.0, np.inf], 0.0), "xy_world must be finite"),
        (lambda: heading.rotation(np.inf), "heading_rad must be finite"),
        (lambda: heading.hip_yaw_targets(np.nan), "turn_rad must be finite"),
        (lambda: heading.yaw_of([0.0, 0.0]), "nonzero"),
    ],
)
def test_bad_input_raises_input_error(call, match):
    with pytest.raises(InputError, match=match):
        call()
