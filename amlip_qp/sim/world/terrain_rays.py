"""Ray casts into a compiled plant's terrain: the ground height under a point, as MuJoCo's geometry has it.

:func:`ground_height_function` answers a terrain-aware controller's question
(world (x, y) -> ground height) from the plant itself, by ``mujoco.mj_ray``
into the terrain geoms that :func:`~amlip_qp.sim.world.terrain.terrain_edit`
built (the analytic height, :meth:`~amlip_qp.sim.world.terrain.TerrainSpec.height_m`,
agrees with it to 1e-7 m).
"""

from __future__ import annotations

import math
from collections.abc import Callable

import mujoco
import numpy as np

from amlip_qp.exceptions import InputError
from amlip_qp.sim.world.plant import Plant
from amlip_qp.sim.world.terrain import TERRAIN_GEOM_GROUP, TerrainSpec

#: Ray casts for the ground start this high, m (above any terrain built here).
_RAY_TOP_M = 1000.0
#: Offset in y of the second ray of :func:`ground_height_function`, m.
_ROW_NUDGE_M = 1e-6


def ground_height_function(plant: Plant, terrain: TerrainSpec) -> Callable[[float, float], float]:
    """World (x, y) m -> ground height m under it, by ``mujoco.mj_ray`` into the plant's terrain geoms only.

    The terrain geoms are the static geoms in :data:`TERRAIN_GEOM_GROUP` (a
    plant built with :func:`terrain_edit`); a plant without them (``flat``:
    no edit) answers with its static geoms (its floor), ray-cast one by one.
    The robot's own geoms are never hit. NaN where no terrain lies under (x, y).
    ``terrain`` is the spec the plant was built with (checked against the plant).

    Raises:
        InputError: ``terrain`` is not flat but the plant has no terrain geoms.
    """
    model = plant.model
    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)  # the static geoms' poses
    static = model.body_weldid[model.geom_bodyid] == 0
    in_group = static & (model.geom_group == TERRAIN_GEOM_GROUP)
    down = np.array([0.0, 0.0, -1.0])
    pnt = np.array([0.0, 0.0, _RAY_TOP_M])
    robot_in_group = np.any(~static & (model.geom_group == TERRAIN_GEOM_GROUP))
    if np.any(in_group) and not robot_in_group:  # one ray into the group: only terrain there
        mask = np.zeros(6, dtype=np.uint8)
        mask[TERRAIN_GEOM_GROUP] = 1
        hit = np.zeros(1, dtype=np.int32)

        def by_group(x_m: float, y_m: float) -> float:
            # MuJoCo 4.0's height-field ray misses some points exactly on a grid row (it then
            # hits something lower); a second ray 1 um beside it cannot be on a row too.
            best = -1.0
            for dy in (0.0, _ROW_NUDGE_M):
                pnt[0], pnt[1] = x_m, y_m + dy
                dist = mujoco.mj_ray(model, data, pnt, down, mask, 1, -1, hit)
                if dist >= 0.0 and (best < 0.0 or dist < best):
                    best = dist
            return _RAY_TOP_M - best if best >= 0.0 else math.nan

        return by_group
    if not terrain.is_flat and not np.any(in_group):
        raise InputError(f"plant {plant.name} has no terrain geoms: load it with the edit of --terrain {terrain.text}")
    # a plant whose own (moving) geoms share the terrain's group: cast into the static geoms one by one
    ids = [int(g) for g in np.flatnonzero(in_group if np.any(in_group) else static)]

    hfield = mujoco.mjtGeom.mjGEOM_HFIELD

    def one(g: int) -> float:
        if model.geom_type[g] == hfield:
            return mujoco.mj_rayHfield(model, data, g, pnt, down)
        pos, mat, size = data.geom_xpos[g], data.geom_xmat[g], model.geom_size[g]
        return mujoco.mju_rayGeom(pos, mat, size, pnt, down, model.geom_type[g])

    def by_geom(x_m: float, y_m: float) -> float:
        hits = []
        for dy in (0.0, _ROW_NUDGE_M):  # the height-field row miss, as in by_group
            pnt[0], pnt[1] = x_m, y_m + dy
            hits += [d for d in (one(g) for g in ids) if d >= 0.0]
        return _RAY_TOP_M - min(hits) if hits else math.nan

    return by_geom
