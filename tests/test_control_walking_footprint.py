"""Terrain-aware foothold selection: the footprint moved off stair edges, a no-op on smooth ground."""

from __future__ import annotations

import math

import pytest

from amlip_qp.control.walking.footprint import FootholdSelector
from amlip_qp.exceptions import InputError

#: A blade foot, from its contact point along the heading: 0.12 m ahead, 0.08 m behind, m (Cassie's).
BLADE_M = (0.12, 0.08)


def stairs(x_m: float, y_m: float) -> float:
    """The stairs of cassie-stairs-10cm: up 4 of 0.1 m / 0.3 m from x = 1 m, a landing to 3.2 m, down 3."""
    if x_m < 1.0:
        return 0.0
    if x_m < 2.2:
        return 0.1 * (1 + math.floor((x_m - 1.0) / 0.3))
    if x_m < 3.2:
        return 0.4
    if x_m < 4.1:
        return 0.3 - 0.1 * math.floor((x_m - 3.2) / 0.3)
    return 0.0


def test_edges_are_found_with_their_rise_along_the_heading():
    sel = FootholdSelector(stairs, *BLADE_M)
    edges = sel.edges(1.2, 0.0, 0.0, -0.3, 0.3)
    assert [e for e, _ in edges] == pytest.approx([-0.2, 0.1])  # the risers at x = 1.0 and 1.3 (+-5 mm)
    assert [r for _, r in edges] == pytest.approx([0.1, 0.1])
    # walking the other way the same risers are drops
    back = sel.edges(1.2, 0.0, math.pi, -0.3, 0.3)
    assert [r for _, r in back] == pytest.approx([-0.1, -0.1])


def test_a_target_across_an_edge_moves_to_the_nearest_tread_spot():
    sel = FootholdSelector(stairs, *BLADE_M)
    # On the floor before the first riser the toe (0.12 m ahead) keeps 0.03 m from it: x <= 0.85.
    assert sel.place(0.80, 0.1, 0.0) == (0.80, 0.1)  # fits: the same floats
    sel.new_step()
    assert sel.place(0.95, 0.1, 0.0) == pytest.approx((0.85, 0.1))
    sel.new_step()
    # Just short of the edge (the failing run's 0.998): onto the first tread, heel (0.08 m behind) on it.
    assert sel.place(0.998, 0.1, 0.0) == pytest.approx((1.08, 0.1))
    sel.new_step()
    assert sel.place(1.2, -0.2, 0.0) == pytest.approx((1.15, -0.2))  # toe 0.03 m short of the next riser
    sel.new_step()
    # Down the stairs: a drop ahead needs the blade on the tread only, a riser behind 0.03 m for the heel.
    assert sel.place(3.12, 0.0, 0.0) == pytest.approx((3.08, 0.0))
    sel.new_step()
    assert sel.place(3.25, 0.0, 0.0) == pytest.approx((3.31, 0.0))


def test_the_choice_has_hysteresis_and_is_kept_late_in_the_swing():
    sel = FootholdSelector(stairs, *BLADE_M)
    sel.new_step()
    # Between the spots 1.15 and 1.38 the nearer wins, except that the last one wins by 0.05 m.
    placed = [sel.place(x, 0.0, 0.0, 0.2)[0] for x in (1.15, 1.2, 1.25, 1.28, 1.30)]
    assert placed == pytest.approx([1.15, 1.15, 1.15, 1.15, 1.38])
    # From phase 0.5 on the stretch is kept whatever the raw target does ...
    assert sel.place(1.2, 0.0, 0.0, 0.6)[0] == pytest.approx(1.38)
    # ... and a new step chooses afresh.
    sel.new_step()
    assert sel.place(1.2, 0.0, 0.0, 0.6)[0] == pytest.approx(1.15)


def test_a_one_sample_glitch_of_the_height_function_is_no_edge():
    # a ray cast between two boxes of terrain can miss both and hit the floor below
    holey = FootholdSelector(lambda x, y: -1.0 if abs(x - 1.305) < 0.004 else stairs(x, y), *BLADE_M)
    edges = holey.edges(1.2, 0.0, 0.0, -0.3, 0.3)
    assert [e for e, _ in edges] == pytest.approx([-0.2, 0.11])  # the riser at 1.3 m, read one sample late
    assert [r for _, r in edges] == pytest.approx([0.1, 0.1])


def test_smooth_ground_is_a_no_op():
    for height in (lambda x, y: math.tan(math.radians(15.0)) * x, lambda x, y: 0.15 * math.sin(2 * math.pi * x / 4.0)):
        sel = FootholdSelector(height, *BLADE_M)
        for x, y, heading in ((1.234, 0.5, 0.3), (-3.0, 2.0, 2.0), (7.77, -0.1, -1.0)):
            placed = sel.place(x, y, heading, 0.3)
            assert placed[0] is x and placed[1] is y  # the very floats


def test_bad_arguments_are_refused():
    with pytest.raises(InputError, match="callable"):
        FootholdSelector(3.0)  # type: ignore[arg-type]
    with pytest.raises(InputError, match="margin_m"):
        FootholdSelector(stairs, margin_m=-0.01)


def test_reset_forgets_the_samples_and_the_last_choice():
    """After reset a selector chooses as a new one, even where its height function changed meanwhile."""
    heights = {"z": 0.0}

    def moving(x_m: float, y_m: float) -> float:
        return stairs(x_m, y_m) + (heights["z"] if x_m > 1.5 else 0.0)

    sel = FootholdSelector(moving, *BLADE_M)
    first = sel.place(0.98, 0.0, 0.0)
    heights["z"] = 0.05  # a new run on other ground: another edge at x = 1.5
    sel.reset()
    assert sel.place(1.45, 0.0, 0.0) == FootholdSelector(moving, *BLADE_M).place(1.45, 0.0, 0.0)
    assert sel.place(1.45, 0.0, 0.0) != (1.45, 0.0)  # the new edge moved it
    assert first != (0.98, 0.0)
