"""The variable layout of the whole-body QP: slices, force components, supported feet."""

from types import SimpleNamespace

import numpy as np
import pytest

from amlip_qp.control.wbc.layout import VariableLayout
from amlip_qp.exceptions import InputError
from amlip_qp.robots import load_robot


@pytest.mark.parametrize("name, d, k", [("cassie", 3, 2), ("rabbit", 2, 1)])
def test_layout_of_the_bundled_robots(name, d, k):
    robot = load_robot(name)
    L = VariableLayout.for_robot(robot, 2, 2)
    assert (L.point_dim, L.n_points, L.n_force) == (d, k, d * k)
    assert L.sl_vdot == slice(0, robot.nv)
    assert L.sl_f_st == slice(robot.nv, robot.nv + d * k)
    assert L.sl_f_sw == slice(robot.nv + d * k, robot.nv + 2 * d * k)
    assert L.sl_forces == slice(robot.nv, L.n) and L.n == robot.nv + 2 * d * k
    assert L.n_lambda == 4
    assert L.planar == (name == "rabbit")
    assert list(L.axes) == ([0, 2] if L.planar else [0, 1, 2])
    # The index gives the same rows of a (3, m) array as the axes.
    J = np.arange(12.0).reshape(3, 4)
    assert np.array_equal(J[L.axes_index], J[L.axes])


def test_normal_and_tangential_indices_partition_each_foot():
    cassie = VariableLayout(nv=10, point_dim=3, n_points=2, n_rigid_st=0, n_rigid_sw=0)
    # Stance block 10..15: toe (10, 11, 12), heel (13, 14, 15); z last.
    assert list(cassie.normal_index(cassie.sl_f_st)) == [12, 15]
    assert list(cassie.tangential_index(cassie.sl_f_st)) == [10, 11, 13, 14]
    assert list(cassie.normal_index(cassie.sl_f_sw)) == [18, 21]
    planar = VariableLayout(nv=7, point_dim=2, n_points=1, n_rigid_st=0, n_rigid_sw=0)
    assert list(planar.normal_index(planar.sl_f_sw)) == [10] and list(planar.tangential_index(planar.sl_f_sw)) == [9]
    for L in (cassie, planar):
        for foot in (L.sl_f_st, L.sl_f_sw):
            both = sorted([*L.normal_index(foot), *L.tangential_index(foot)])
            assert both == list(range(foot.start, foot.stop))


def _fake_robot(points_left, points_right, planar=False):
    return SimpleNamespace(
        nv=8, is_planar=planar, foot_sides=("left", "right"),
        force_frame_ids={"left": tuple(range(points_left)), "right": tuple(range(points_right))},
    )  # fmt: skip


@pytest.mark.parametrize(
    "robot, match",
    [
        (_fake_robot(1, 2), "same"),
        (_fake_robot(0, 0), "nonzero"),
        (_fake_robot(3, 3), "supported feet"),
        (_fake_robot(2, 2, planar=True), "supported feet"),
        (_fake_robot(4, 4, planar=True), "supported feet"),
        (_fake_robot(4, 2), "same"),
    ],
)
def test_unsupported_feet_are_a_clear_error(robot, match):
    with pytest.raises(InputError, match=match):
        VariableLayout.for_robot(robot, 0, 0)


def test_a_four_point_sole_gives_twelve_forces_per_foot_normals_every_third():
    layout = VariableLayout.for_robot(_fake_robot(4, 4), 0, 0)
    assert (layout.n_points, layout.n_force, layout.n) == (4, 12, 8 + 24)
    assert list(layout.normal_index(layout.sl_f_st)) == [10, 13, 16, 19]
    assert list(layout.tangential_index(layout.sl_f_sw)) == [20, 21, 23, 24, 26, 27, 29, 30]
