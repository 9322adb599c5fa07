"""Terrain in the plant: slopes, stairs, rough ground, waves and the user's height maps (``--terrain``).

The terrain exists in the MuJoCo plant only. :func:`parse_terrain` reads a
spec (``flat``, ``slope:DEG``, ``stairs:RISE_M:RUN_M[:N]``,
``rough:AMPLITUDE_M[:SEED]``, ``waves:HEIGHT_M:WAVELENGTH_M[:HEADING_DEG]``,
``hfield:PATH.png:SIZE_X_M:SIZE_Y_M:HEIGHT_M``) into a :class:`TerrainSpec`
whose :meth:`~TerrainSpec.height_m` is the analytic ground height;
:func:`terrain_edit` builds it into a plant's ``MjSpec`` (boxes where they
are exact: slopes and stairs; height fields for the rest, with
:mod:`~amlip_qp.sim.world.terrain_grids`) and lifts the plant's keyframes so the
robot starts standing on the ground under its feet;
:func:`~amlip_qp.sim.world.terrain_rays.ground_height_function` casts rays
into a compiled plant's terrain.

The robot starts at x = 0 heading +x; the terrain varies along x (so the
planar Rabbit, in the x-z plane, walks on all of it) and spans
``|y| <=`` :data:`~amlip_qp.sim.world.terrain_grids.HALF_WIDTH_M`. Slopes, stairs
and waves start :data:`START_X_M` ahead of the robot; rough ground is flat
around the start. Waves at a heading other than 0 (their ridges at
``HEADING_DEG`` to the path; 90: along it) cover the whole terrain, the robot
starting on the floor of the valley through x = y = 0
(:func:`~amlip_qp.sim.world.terrain_grids.waves_height_m`).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field

import mujoco
import numpy as np

from amlip_qp.exceptions import InputError, MJCFError
from amlip_qp.sim.world import terrain_grids as G
from amlip_qp.sim.world.plant_modifiers import is_static_body
from amlip_qp.sim.world.terrain_lift import keyframe_lifts

#: Geom group of every terrain geom (the floor included once a terrain is built); rendered by default.
TERRAIN_GEOM_GROUP = 2
#: Slopes, stairs and waves start this far ahead of the robot, m.
START_X_M = 1.0
#: A slope runs this far along x before its plateau (up) or the lowered floor (down), m.
SLOPE_RUN_M = 20.0
#: Length of the plateau at the top of an up slope, and of the flat start before a down slope, m.
SLOPE_FLAT_M = 10.0
#: Slopes must be less steep than this, deg.
MAX_SLOPE_DEG = 45.0
#: Length of the stairs' landing, m.
STAIRS_LANDING_M = 1.0
#: Steps up (and down) of ``stairs:RISE:RUN`` without N.
DEFAULT_STAIRS_STEPS = 4
#: Thickness of the terrain boxes below their top faces, beyond what reaches the floor, m.
BOX_DEPTH_M = 1.0
#: Name (prefix) of the geoms and the height field the terrain adds.
TERRAIN_NAME = "amlip-terrain"
#: A height map's left edge lies this far behind the robot's start, m.
HFIELD_BACK_M = 1.0

KINDS = ("flat", "slope", "stairs", "rough", "waves", "hfield")
_USAGE = (
    "flat, slope:DEG, stairs:RISE_M:RUN_M[:N], rough:AMPLITUDE_M[:SEED], waves:HEIGHT_M:WAVELENGTH_M[:HEADING_DEG] "
    "or hfield:PATH.png:SIZE_X_M:SIZE_Y_M:HEIGHT_M"
)


def _num(x: float) -> str:
    """A number as the canonical spec writes it (``10``, ``0.1``)."""
    f = float(x)
    return str(int(f)) if f.is_integer() and abs(f) < 1e15 else repr(f)


@dataclass(frozen=True)
class _Step:
    """A box's top face: x from ``x0_m`` to ``x1_m``, height ``z0_m`` at ``x0_m`` rising at ``slope`` (dz/dx)."""

    x0_m: float
    x1_m: float
    z0_m: float
    slope: float = 0.0


@dataclass(frozen=True)
class TerrainSpec:
    """A parsed ``--terrain`` spec (build one with :func:`parse_terrain`).

    Attributes:
        kind: One of :data:`KINDS`.
        text: The canonical spec (``"flat"``, ``"slope:10"``, ``"stairs:0.1:0.3:4"``, ...).
        params: Its numbers, in the spec's order (defaults filled in).
        path: The PNG of ``hfield``, else ``""``.
    """

    kind: str
    text: str
    params: tuple[float, ...] = ()
    path: str = ""
    grid: G.HeightGrid | None = field(default=None, compare=False, repr=False)

    @property
    def is_flat(self) -> bool:
        return self.kind == "flat"

    # ------------------------------------------------------------ geometry
    @property
    def steps(self) -> tuple[_Step, ...]:
        """The boxes' top faces of ``slope`` and ``stairs`` (empty for the others)."""
        if self.kind == "slope":
            k = math.tan(math.radians(self.params[0]))
            top = k * SLOPE_RUN_M
            ramp = _Step(START_X_M, START_X_M + SLOPE_RUN_M, 0.0, k)
            if k >= 0.0:
                end = START_X_M + SLOPE_RUN_M
                return ramp, _Step(end, end + SLOPE_FLAT_M, top)
            return _Step(START_X_M - SLOPE_FLAT_M, START_X_M, 0.0), ramp
        if self.kind == "stairs":
            rise, run, n = self.params[0], self.params[1], int(self.params[2])
            out = [_Step(START_X_M + i * run, START_X_M + (i + 1) * run, (i + 1) * rise) for i in range(n)]
            x = START_X_M + n * run
            out.append(_Step(x, x + STAIRS_LANDING_M, n * rise))
            x += STAIRS_LANDING_M
            out += [_Step(x + i * run, x + (i + 1) * run, (n - 1 - i) * rise) for i in range(n - 1)]
            return tuple(out)
        return ()

    @property
    def floor_z_m(self) -> float:
        """Height of the (infinite) floor plane under and around the terrain, m."""
        if self.kind == "slope" and self.params[0] < 0.0:
            return math.tan(math.radians(self.params[0])) * SLOPE_RUN_M
        if self.kind == "rough" and self.grid is not None:
            return self.grid.z0_m
        return 0.0

    def height_m(self, x_m: float, y_m: float) -> float:
        """The ground height at world (x, y), m: what MuJoCo's geometry gives (ray casts agree to 1e-7 m)."""
        if self.kind == "flat":
            return 0.0
        inside = abs(y_m) <= G.HALF_WIDTH_M
        if self.grid is not None:
            if self.grid.covers(x_m, y_m):
                return self.grid.height_m(x_m, y_m)
        elif inside:
            best = -math.inf
            for s in self.steps:
                if s.x0_m <= x_m <= s.x1_m:
                    best = max(best, s.z0_m + s.slope * (x_m - s.x0_m))
            if best > -math.inf:
                return max(best, self.floor_z_m)
        return self.floor_z_m


def _positive(name: str, text: str, spec: str, upper: float) -> float:
    try:
        value = float(text)
    except ValueError:
        raise InputError(f"--terrain {spec!r}: {name} must be a number, got {text!r}; use {_USAGE}") from None
    if not (math.isfinite(value) and 0.0 < value <= upper):
        raise InputError(f"--terrain {spec!r}: {name} must be a number in (0, {upper:g}], got {text}")
    return value


def _heading(text: str, spec: str) -> float:
    """The ridges' heading of ``waves``, deg in [-90, 90] (a ridge at 180 deg is the same ridge)."""
    try:
        value = float(text)
    except ValueError:
        raise InputError(f"--terrain {spec!r}: HEADING_DEG must be a number of degrees, got {text!r}") from None
    if not (math.isfinite(value) and -90.0 <= value <= 90.0):
        raise InputError(
            f"--terrain {spec!r}: HEADING_DEG must be in [-90, 90] (ridges repeat every 180 deg), got {text}"
        )
    return value + 0.0  # -0.0 is heading 0


def _whole(name: str, text: str, spec: str, lo: int, hi: int) -> int:
    try:
        value = int(text)
    except ValueError:
        raise InputError(f"--terrain {spec!r}: {name} must be a whole number, got {text!r}") from None
    if not lo <= value <= hi:
        raise InputError(f"--terrain {spec!r}: {name} must be in [{lo}, {hi}], got {value}")
    return value


@functools.lru_cache(maxsize=16)
def parse_terrain(text: str) -> TerrainSpec:
    """The :class:`TerrainSpec` of a ``--terrain`` spec (cached: a spec is parsed, and a PNG read, once).

    Raises:
        InputError: Anything malformed (one line saying what to give): an
            unknown kind, a wrong number of fields, non-numbers, a slope (or
            waves' flanks) of 45 deg or more, a waves heading outside [-90, 90] deg,
            heights or sizes <= 0, a missing or unreadable PNG,
            or one of more than :data:`~amlip_qp.sim.world.terrain_grids.MAX_HFIELD_PIXELS`
            pixels (read from its header: nothing is decoded).
    """
    spec = str(text).strip()
    kind, _, rest = spec.partition(":")
    kind = kind.lower()
    if kind == "hfield":
        parts = rest.rsplit(":", 3)  # the path may contain ':'
        if len(parts) != 4 or not parts[0]:
            raise InputError(f"--terrain {spec!r}: give hfield:PATH.png:SIZE_X_M:SIZE_Y_M:HEIGHT_M")
        path = parts[0]
        sx = _positive("SIZE_X_M", parts[1], spec, 1000.0)
        sy = _positive("SIZE_Y_M", parts[2], spec, 1000.0)
        h = _positive("HEIGHT_M", parts[3], spec, 100.0)
        try:
            gray = G.read_gray_png(path)
        except InputError as exc:
            raise InputError(f"--terrain {spec!r}: {exc}") from None
        grid = G.png_grid(gray, sx, sy, h, HFIELD_BACK_M)
        canon = f"hfield:{path}:{_num(sx)}:{_num(sy)}:{_num(h)}"
        return TerrainSpec("hfield", canon, (sx, sy, h), path, grid)
    fields = rest.split(":") if rest else []
    n = len(fields)
    if kind == "flat" and n == 0:
        return TerrainSpec("flat", "flat")
    if kind == "slope" and n == 1:
        try:
            deg = float(fields[0])
        except ValueError:
            raise InputError(f"--terrain {spec!r}: the slope must be a number of degrees, e.g. slope:10") from None
        if not (math.isfinite(deg) and abs(deg) < MAX_SLOPE_DEG):
            raise InputError(
                f"--terrain {spec!r}: the slope must be less than {MAX_SLOPE_DEG:g} deg either way, got {fields[0]}"
            )
        return TerrainSpec("slope", f"slope:{_num(deg)}", (deg,))
    if kind == "stairs" and n in (2, 3):
        rise = _positive("RISE_M", fields[0], spec, 1.0)
        run = _positive("RUN_M", fields[1], spec, 10.0)
        steps = _whole("N", fields[2], spec, 1, 50) if n == 3 else DEFAULT_STAIRS_STEPS
        return TerrainSpec("stairs", f"stairs:{_num(rise)}:{_num(run)}:{steps}", (rise, run, float(steps)))
    if kind == "rough" and n in (1, 2):
        amp = _positive("AMPLITUDE_M", fields[0], spec, 1.0)
        seed = _whole("SEED", fields[1], spec, 0, 2**32 - 1) if n == 2 else 0
        return TerrainSpec("rough", f"rough:{_num(amp)}:{seed}", (amp, float(seed)), "", G.rough_grid(amp, seed))
    if kind == "waves" and n in (2, 3):
        h = _positive("HEIGHT_M", fields[0], spec, 5.0)
        lam = _positive("WAVELENGTH_M", fields[1], spec, 100.0)
        heading = _heading(fields[2], spec) if n == 3 else 0.0
        if lam < 4.0 * G.GRID_SPACING_M:
            raise InputError(f"--terrain {spec!r}: the wavelength must be at least {4.0 * G.GRID_SPACING_M:g} m")
        # the flanks' steepest grade, along the ridges' normal: the same at every heading (a foot
        # on a flank stands on that grade whichever way it walks)
        steepest = math.degrees(math.atan(math.pi * h / lam))
        if steepest >= MAX_SLOPE_DEG:
            raise InputError(
                f"--terrain {spec!r}: these waves are {steepest:.0f} deg steep at their flanks; "
                f"keep HEIGHT_M / WAVELENGTH_M below {math.tan(math.radians(MAX_SLOPE_DEG)) / math.pi:.3f}"
            )
        grid = G.waves_grid(h, lam, START_X_M, heading)
        text = f"waves:{_num(h)}:{_num(lam)}" + (f":{_num(heading)}" if heading != 0.0 else "")
        return TerrainSpec("waves", text, (h, lam, heading), "", grid)
    if kind in KINDS:
        raise InputError(f"--terrain {spec!r}: wrong number of fields for {kind}; use {_USAGE}")
    raise InputError(f"--terrain {spec!r}: unknown terrain; use {_USAGE}")


# ------------------------------------------------------------------ the plant
#: The floor's attributes every terrain geom copies (so contacts with the terrain are contacts with the floor).
_CONTACT_ATTRS = tuple("contype conaffinity condim priority friction solmix solref solimp margin gap".split())


@dataclass(frozen=True)
class TerrainEdit:
    """The :data:`~amlip_qp.sim.world.plant.SpecEdit` of a terrain (see :func:`terrain_edit`)."""

    terrain: TerrainSpec

    def __call__(self, spec: mujoco.MjSpec) -> None:
        t = self.terrain
        floors = [g for g in spec.worldbody.geoms if g.type == mujoco.mjtGeom.mjGEOM_PLANE]
        if not floors:
            raise MJCFError("the plant has no floor (a plane geom of the world body) for --terrain to build on")
        floor = floors[0]
        if t.is_flat:
            return
        lift = keyframe_lifts(spec, floor, t.height_m)
        for g in spec.geoms:
            if is_static_body(g.parent):
                g.group = TERRAIN_GEOM_GROUP
        floor.pos = [floor.pos[0], floor.pos[1], t.floor_z_m]
        world = spec.worldbody
        rgba = [1.0, 0.85, 0.6, 1.0]  # a sand tint of the floor's texture
        for i, s in enumerate(t.steps):
            pitch = math.atan(s.slope)
            length = (s.x1_m - s.x0_m) / math.cos(pitch)
            top_mid = np.array([0.5 * (s.x0_m + s.x1_m), 0.0, s.z0_m + 0.5 * s.slope * (s.x1_m - s.x0_m)])
            normal = np.array([-math.sin(pitch), 0.0, math.cos(pitch)])
            z1 = s.z0_m + s.slope * (s.x1_m - s.x0_m)
            depth = BOX_DEPTH_M + max(abs(s.z0_m), abs(z1)) + abs(t.floor_z_m)  # down to the floor
            geom = world.add_geom(
                name=f"{TERRAIN_NAME}-{i}",
                type=mujoco.mjtGeom.mjGEOM_BOX,
                size=[0.5 * length, G.HALF_WIDTH_M, 0.5 * depth],
                pos=list(top_mid - 0.5 * depth * normal),
                quat=[math.cos(-0.5 * pitch), 0.0, math.sin(-0.5 * pitch), 0.0],
                rgba=[c * (0.9 if i % 2 else 1.0) for c in rgba[:3]] + [1.0],
            )
            _copy_contact(floor, geom)
        if t.grid is not None:
            grid = t.grid
            hx, hy = grid.half_size_m
            spec.add_hfield(
                name=TERRAIN_NAME,
                size=[hx, hy, grid.elevation_m, 0.1],
                nrow=grid.nrow,
                ncol=grid.ncol,
                userdata=grid.data.ravel().tolist(),
            )
            cx, cy = grid.centre_m
            geom = world.add_geom(
                name=f"{TERRAIN_NAME}-hfield",
                type=mujoco.mjtGeom.mjGEOM_HFIELD,
                hfieldname=TERRAIN_NAME,
                pos=[cx, cy, grid.z0_m],
                rgba=rgba,
            )
            _copy_contact(floor, geom)
        for key, qpos in zip(spec.keys, lift):
            if qpos is not None:
                key.qpos = qpos


def _copy_contact(floor: mujoco.MjsGeom, geom: mujoco.MjsGeom) -> None:
    """The floor's contact parameters and material (its texture, tinted by the geom's colour) on ``geom``."""
    for attr in _CONTACT_ATTRS:
        setattr(geom, attr, getattr(floor, attr))
    geom.material = floor.material
    geom.group = TERRAIN_GEOM_GROUP


def terrain_edit(terrain: TerrainSpec) -> TerrainEdit:
    """The spec edit that builds ``terrain`` into a plant (a :data:`~amlip_qp.sim.world.plant.SpecEdit`).

    It puts every static geom of the plant (its floor) in
    :data:`TERRAIN_GEOM_GROUP`, moves the floor plane to :attr:`TerrainSpec.floor_z_m`,
    adds the boxes (slopes, stairs) or the height field (rough, waves, PNG) in
    that group with the floor's contact parameters, and lifts every keyframe
    by the ground height under the robot's collision geoms (its feet), so the
    robot starts standing on the ground whatever the terrain there. ``flat``
    changes nothing.

    Raises (when applied):
        MJCFError: The plant has no floor plane, or its keyframes cannot be
            lifted (no free joint nor vertical slide joint at the root).
    """
    return TerrainEdit(terrain)
