"""Tests of amlip_qp.alip.heading: heading frames and the hip-yaw split."""

import math

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


def test_world_to_heading_is_the_formula_the_planner_and_output_map_use():
    """The validated rotation and the unchecked formula give the same bits."""
    from amlip_qp.alip.formulas import world_to_heading_xy

    D, x, y = 0.7, 1.3, -0.4
    assert tuple(heading.world_to_heading([x, y], D)) == world_to_heading_xy(x, y, math.cos(D), math.sin(D))
    # the heading frame's x axis is (cos D, sin D): a world vector along it has no y component
    hx, hy = world_to_heading_xy(math.cos(D), math.sin(D), math.cos(D), math.sin(D))
    assert hx == pytest.approx(1.0) and hy == pytest.approx(0.0, abs=1e-15)


def test_hip_yaw_split():
    st, sw = heading.hip_yaw_targets(0.3)
    assert (st, sw) == (pytest.approx(-0.15), pytest.approx(0.15))
    assert sw - st == pytest.approx(0.3)


@pytest.mark.parametrize(
    "call, match",
    [
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
