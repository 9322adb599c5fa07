"""The foot's extent along the heading, read from each robot's collision geometry at the stand pose."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from amlip_qp.robots import load_robot
from amlip_qp.robots.foot_extent import foot_extent_m


def test_a_blade_of_two_spheres_reaches_their_outer_surfaces():
    """Cassie's toe and heel spheres (radius 0.02 m) sit 0.10 m ahead of and 0.06 m behind the foot joint."""
    assert foot_extent_m(load_robot("cassie")) == (0.12, 0.08)


def test_a_point_foot_has_no_extent():
    assert foot_extent_m(load_robot("rabbit")) == (0.0, 0.0)


def _ray_extent(model, data, geom: int, x0: float, step_m: float = 0.001) -> tuple[float, float]:
    """How far one geom reaches ahead of and behind ``x0`` along +x: rays cast along -x and +x on a grid
    of ``step_m`` over the geom's bounding sphere (MuJoCo's own ray-geom intersection)."""
    c, rb = data.geom_xpos[geom], model.geom_rbound[geom]
    grid = np.arange(-rb, rb + step_m, step_m)
    front, back = -np.inf, -np.inf
    for dy in grid:
        for dz in grid:
            for sign in (1.0, -1.0):
                start = np.array([c[0] + sign * 2.0 * rb, c[1] + dy, c[2] + dz])
                dist = mujoco.mju_rayGeom(
                    data.geom_xpos[geom],
                    data.geom_xmat[geom],
                    model.geom_size[geom],
                    start,
                    np.array([-sign, 0.0, 0.0]),
                    model.geom_type[geom],
                )
                if dist >= 0.0:
                    x = start[0] - sign * dist - x0
                    front, back = (max(front, x), back) if sign > 0 else (front, max(back, -x))
    return front, back


@pytest.mark.parametrize("name", ["h1", "g1"])
def test_the_extent_is_the_foot_geometry_found_by_ray_casting(name):
    """The sole reaches past its force points, and rays cast at the foot's colliding geoms find the
    same front and back to within the millimetre rounding."""
    robot = load_robot(name)
    front, back = foot_extent_m(robot)
    model, data = robot.mj_model, robot.new_mj_data()
    data.qpos[:] = robot.qpos_stand
    mujoco.mj_forward(model, data)
    for side in robot.foot_sides:
        site = robot.contact_site_ids[side]
        x0 = data.site_xpos[site][0]
        xs = np.array([data.site_xpos[i][0] for i in robot.force_site_ids[side]]) - x0
        assert xs.max() < front and -xs.min() < back
        body = model.site_bodyid[site]
        geoms = [g for g in range(model.ngeom) if model.geom_bodyid[g] == body and model.geom_contype[g]]
        reach = np.array([_ray_extent(model, data, g, x0) for g in geoms])
        assert reach[:, 0].max() == pytest.approx(front, abs=1.5e-3)
        assert reach[:, 1].max() == pytest.approx(back, abs=1.5e-3)
