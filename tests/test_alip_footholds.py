"""Tests of amlip_qp.alip.footholds: the ground plane from the last footholds (blind mode)."""

import math

import numpy as np
import pytest

from amlip_qp.alip.footholds import FootholdPlane
from amlip_qp.exceptions import InputError


def _walk(plane, n, heading, grade_along, grade_left=0.0, step=0.3, width=0.2, start=(1.0, -2.0, 0.5)):
    """Add n footholds of a straight walk along ``heading`` on the plane z = start_z + grades . (u, w)."""
    c, s = math.cos(heading), math.sin(heading)
    pts = []
    for k in range(n):
        u, w = k * step, (0.5 if k % 2 == 0 else -0.5) * width
        p = np.array([start[0] + c * u - s * w, start[1] + s * u + c * w, start[2] + grade_along * u + grade_left * w])
        plane.add(p, heading)
        pts.append(p)
    return pts


@pytest.mark.parametrize("heading", [0.0, 0.7, -2.5])
@pytest.mark.parametrize("deg_along, deg_left", [(0.0, 0.0), (10.0, 0.0), (-15.0, 5.0), (22.0, -8.0)])
def test_plane_recovers_pitch_roll_and_heights(heading, deg_along, deg_left):
    ga, gl = math.tan(math.radians(deg_along)), math.tan(math.radians(deg_left))
    plane = FootholdPlane()
    pts = _walk(plane, 6, heading, ga, gl)
    g = plane.plane(heading)
    assert g.n_footholds == 4  # capacity
    assert g.grade_along == pytest.approx(ga, abs=1e-12) and g.grade_left == pytest.approx(gl, abs=1e-12)
    assert g.pitch_rad == pytest.approx(-math.radians(deg_along), abs=1e-12)  # uphill: negative pitch
    assert g.roll_rad == pytest.approx(math.radians(deg_left), abs=1e-12)
    # Height difference to a target 0.35 m ahead and 0.1 m to the left of the stance foot.
    st = pts[-1]
    c, s = math.cos(heading), math.sin(heading)
    target = st[:2] + np.array([c * 0.35 - s * 0.1, s * 0.35 + c * 0.1])
    assert g.rise_m(*(target - st[:2]), heading) == pytest.approx(ga * 0.35 + gl * 0.1, abs=1e-12)


def test_two_footholds_give_only_the_pitch_along_the_heading():
    plane = FootholdPlane()
    plane.add([0.0, 0.1, 0.0], 0.0)
    assert plane.plane(0.0).pitch_rad == 0.0  # one foothold: flat
    plane.add([0.3, -0.1, 0.3 * math.tan(math.radians(12.0))], 0.0)
    g = plane.plane(0.0)
    assert g.grade_along == pytest.approx(math.tan(math.radians(12.0)), abs=1e-12) and g.grade_left == 0.0


def test_guards_walk_in_place_slope_cap_and_reset():
    # Walking in place: no spread along the heading, so no pitch, however the feet differ in height.
    plane = FootholdPlane()
    for k in range(4):
        plane.add([0.0, 0.1 if k % 2 == 0 else -0.1, 0.02 * (k % 2)], 0.0)
    g = plane.plane(0.0)
    assert g.grade_along == 0.0 and g.roll_rad == pytest.approx(-math.atan(0.1), abs=1e-12)
    # A 50 degree staircase is capped at 30 degrees.
    steep = FootholdPlane()
    _walk(steep, 4, 0.0, math.tan(math.radians(50.0)), width=0.0)
    assert steep.plane(0.0).pitch_rad == pytest.approx(-math.radians(30.0), abs=1e-12)
    # A turn of more than 45 degrees forgets the footholds behind the corner.
    _walk(plane, 3, 0.0, 0.2)
    plane.add([5.0, 5.0, 1.0], math.radians(60.0))
    assert plane.plane(math.radians(60.0)).n_footholds == 1
    assert len(plane.footholds_world_m) == 1
    plane.reset()
    assert plane.plane(0.0) == FootholdPlane().plane(0.0)


@pytest.mark.parametrize(
    "kw, match",
    [
        (dict(capacity=1), "capacity must be an integer >= 2"),
        (dict(max_slope_rad=2.0), "max_slope_rad must be < pi/2"),
        (dict(reset_turn_rad=0.0), "reset_turn_rad must be > 0"),
        (dict(min_spread_m=-1.0), "min_spread_m must be > 0"),
    ],
)
def test_bad_settings_raise_input_error(kw, match):
    with pytest.raises(InputError, match=match):
        FootholdPlane(**kw)


def test_bad_footholds_raise_input_error():
    plane = FootholdPlane()
    with pytest.raises(InputError, match=r"foothold_world_m must have shape \(3,\)"):
        plane.add([0.0, 1.0], 0.0)
    with pytest.raises(InputError, match="foothold_world_m must be finite"):
        plane.add([0.0, np.nan, 0.0], 0.0)
    with pytest.raises(InputError, match="heading_rad must be finite"):
        plane.add([0.0, 0.0, 0.0], np.inf)
