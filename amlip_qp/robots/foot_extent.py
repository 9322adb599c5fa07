"""How far a foot reaches ahead of and behind its contact point: the footprint that must fit on a tread.

The terrain-aware foothold selection
(:class:`~amlip_qp.control.walking.footprint.FootholdSelector`) moves a swing
target until the whole foot lies between two edges of the ground. It needs the
foot's extent along the heading from the contact point, which this module reads
from the robot's own model: the collision geometry of the foot's body, at the
stand pose (the feet then point along the heading, +x), measured exactly for
spheres, capsules and boxes and by the geom's bounding box otherwise, and
rounded to the millimetre.

A robot with one force point per foot (a point foot) has a zero footprint: the
point lies on a tread or it does not.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

from amlip_qp.exceptions import ProfileError

#: The extents are rounded to this many decimals of a metre (a millimetre).
DECIMALS = 3


def _x_half_extent(model: mujoco.MjModel, data: mujoco.MjData, geom: int) -> tuple[float, float]:
    """``(centre x, half extent along x)`` of one geom in the world at ``data``'s pose, m."""
    R = data.geom_xmat[geom].reshape(3, 3)
    size = model.geom_size[geom]
    kind = model.geom_type[geom]
    x = float(data.geom_xpos[geom][0])
    if kind == mujoco.mjtGeom.mjGEOM_SPHERE:
        return x, float(size[0])
    if kind == mujoco.mjtGeom.mjGEOM_CAPSULE:  # a segment along the local z axis, swept by the radius
        return x, float(abs(R[0, 2]) * size[1] + size[0])
    if kind == mujoco.mjtGeom.mjGEOM_BOX:
        return x, float(np.abs(R[0, :]) @ size)
    centre, half = model.geom_aabb[geom][:3], model.geom_aabb[geom][3:]  # the local bounding box
    return x + float(R[0, :] @ centre), float(np.abs(R[0, :]) @ half)


def foot_extent_m(robot) -> tuple[float, float]:
    """``(front_m, back_m)``: how far the foot's collision geometry reaches ahead of and behind
    the contact point along the heading at the stand pose, m (>= 0, rounded to the millimetre;
    ``(0, 0)`` for a point foot). Both feet are measured; the larger reach of the two is taken.

    Args:
        robot: A :class:`~amlip_qp.robots.robot.Robot`.

    Raises:
        ProfileError: A foot with two or more force points whose body has no colliding geom.
    """
    if all(len(robot.force_site_ids[side]) <= 1 for side in robot.foot_sides):
        return 0.0, 0.0
    model = robot.mj_model
    data = robot.new_mj_data()
    data.qpos[:] = robot.qpos_stand
    mujoco.mj_kinematics(model, data)
    front = back = 0.0
    for side in robot.foot_sides:
        site = robot.contact_site_ids[side]
        body = model.site_bodyid[site]
        x0 = float(data.site_xpos[site][0])
        geoms = [
            g
            for g in range(model.ngeom)
            if model.geom_bodyid[g] == body and (model.geom_contype[g] or model.geom_conaffinity[g])
        ]
        if not geoms:
            name = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, body)
            raise ProfileError(f"the {side} foot's body {name!r} has no colliding geom: it cannot touch the ground")
        for g in geoms:
            x, half = _x_half_extent(model, data, g)
            front = max(front, x + half - x0)
            back = max(back, x0 - (x - half))
    extent = (round(front, DECIMALS), round(back, DECIMALS))
    if not all(math.isfinite(e) for e in extent):
        raise ProfileError(f"the feet's extent is not finite: {extent!r}")
    return extent
