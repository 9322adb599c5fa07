"""Lift a plant's keyframes onto a terrain, so the robot starts standing on the ground under its feet.

:func:`keyframe_lifts` is used by :class:`amlip_qp.sim.world.terrain.TerrainEdit`
before it adds the terrain: it compiles a copy of the plant's spec, poses
every keyframe, and raises the robot's root by the ground height under its
collision geoms (its feet), relative to where they stood on the flat floor.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import mujoco
import numpy as np

from amlip_qp.exceptions import MJCFError


def _root_height_address(model: mujoco.MjModel) -> int:
    """qpos address of the robot's height: a root free joint's z, or a root slide joint along z."""
    for j in range(model.njnt):
        if model.body_parentid[model.jnt_bodyid[j]] != 0:
            continue
        if model.jnt_type[j] == mujoco.mjtJoint.mjJNT_FREE:
            return int(model.jnt_qposadr[j]) + 2
        if model.jnt_type[j] == mujoco.mjtJoint.mjJNT_SLIDE and np.allclose(model.jnt_axis[j], (0.0, 0.0, 1.0)):
            return int(model.jnt_qposadr[j])
    raise MJCFError(
        "--terrain lifts the plant's keyframes onto the ground, but the plant's root body has neither a free "
        "joint nor a slide joint along z"
    )


#: Points of a sphere's footprint where :func:`keyframe_lifts` samples the ground: (dx, dy) / radius.
_FOOTPRINT = [(0.0, 0.0)] + [
    (f * math.cos(a), f * math.sin(a)) for f in (0.5, 0.85, 1.0) for a in np.linspace(0.0, 2.0 * math.pi, 12, False)
]


def keyframe_lifts(
    spec: mujoco.MjSpec, floor: mujoco.MjsGeom, height_m: Callable[[float, float], float]
) -> list[np.ndarray | None]:
    """Per keyframe of ``spec``: its qpos lifted onto the ground ``height_m(x, y)`` (``None`` if it needs no lift).

    Every geom of a moving body that can touch the floor is taken as a sphere
    (its own radius for a sphere, its bounding radius otherwise); the
    keyframe is lifted by the largest ``ground under the sphere - ground
    under it on the plant's flat floor``, so the geom that touched the flat
    floor touches the terrain and none penetrates it.
    """
    if not spec.keys:
        return []
    model = spec.copy().compile()
    data = mujoco.MjData(model)
    floor_z = float(floor.pos[2])
    bodies_static = model.body_weldid == 0
    movers = [
        g
        for g in range(model.ngeom)
        if not bodies_static[model.geom_bodyid[g]]
        and ((model.geom_contype[g] & floor.conaffinity) or (floor.contype & model.geom_conaffinity[g]))
    ]
    adr = _root_height_address(model)
    out: list[np.ndarray | None] = []
    for k in range(model.nkey):
        mujoco.mj_resetDataKeyframe(model, data, k)
        mujoco.mj_kinematics(model, data)
        need_terrain, need_flat = -math.inf, -math.inf
        for g in movers:
            sphere = model.geom_type[g] == mujoco.mjtGeom.mjGEOM_SPHERE
            r = float(model.geom_size[g, 0] if sphere else model.geom_rbound[g])
            x, y, z = (float(c) for c in data.geom_xpos[g])
            ground = max(
                height_m(x + r * u, y + r * v) + r * math.sqrt(max(1.0 - u * u - v * v, 0.0)) for u, v in _FOOTPRINT
            )
            need_terrain = max(need_terrain, ground - z)
            need_flat = max(need_flat, floor_z + r - z)
        dz = need_terrain - need_flat if movers else 0.0
        if dz == 0.0:
            out.append(None)
            continue
        qpos = model.key_qpos[k].copy()
        qpos[adr] += dz
        out.append(qpos)
    return out
