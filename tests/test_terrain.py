"""Terrain in the plant (sim.world.terrain, terrain_grids, terrain_lift, terrain_rays): surface, keyframes, height maps.

The terrain specs' parsing is in ``tests/test_terrain_parsing.py``.
"""

from __future__ import annotations

import math

import imageio.v3 as iio
import mujoco
import numpy as np
import pytest

from amlip_qp.exceptions import InputError, MJCFError
from amlip_qp.sim.loop.run_types import PlantSetting
from amlip_qp.sim.scenarios import factory
from amlip_qp.sim.world.plant_loader import load_plant
from amlip_qp.sim.world.terrain import (
    START_X_M,
    TERRAIN_GEOM_GROUP,
    parse_terrain,
    terrain_edit,
)
from amlip_qp.sim.world.terrain_grids import HALF_WIDTH_M
from amlip_qp.sim.world.terrain_rays import ground_height_function

KINDS = ["slope:10", "slope:-15", "stairs:0.1:0.3", "rough:0.04:3", "waves:0.3:4"]


def _plant(robot: str, text: str):
    spec = parse_terrain(text)
    return load_plant(robot, factory.load(robot), edits=[terrain_edit(spec)]), spec


def _ramp_png(path, size=(41, 101), dtype=np.uint8):
    """A gray ramp along x (columns): black at the left edge, white at the right."""
    top = np.iinfo(dtype).max
    img = np.tile(np.round(np.linspace(0, top, size[1])).astype(dtype), (size[0], 1))
    iio.imwrite(path, img)
    return img


# --------------------------------------------------------- analytic heights
def test_analytic_profiles():
    k = math.tan(math.radians(10.0))
    slope = parse_terrain("slope:10")
    assert slope.height_m(START_X_M - 0.01, 0.0) == 0.0
    assert slope.height_m(START_X_M + 2.0, 1.0) == pytest.approx(2.0 * k)
    down = parse_terrain("slope:-15")
    assert down.height_m(START_X_M + 3.0, 0.0) == pytest.approx(-3.0 * math.tan(math.radians(15.0)))
    stairs = parse_terrain("stairs:0.1:0.3:2")  # up at 1.0 and 1.3, landing 1.6-2.6, down at 2.6-2.9, floor after
    expected = {0.9: 0.0, 1.1: 0.1, 1.4: 0.2, 2.0: 0.2, 2.7: 0.1, 3.0: 0.0}
    assert {x: round(stairs.height_m(x, 0.5), 9) for x in expected} == expected
    waves = parse_terrain("waves:0.3:4")
    assert waves.height_m(START_X_M, 0.0) == pytest.approx(0.0, abs=1e-9)
    assert waves.height_m(START_X_M + 2.0, 0.0) == pytest.approx(0.3, abs=1e-6)  # crest
    assert waves.height_m(START_X_M + 4.0, 2.0) == pytest.approx(0.0, abs=1e-6)  # trough
    rough = parse_terrain("rough:0.04:3")
    xs, ys = np.meshgrid(np.linspace(-3.0, 25.0, 200), np.linspace(-3.5, 3.5, 30))
    h = np.array([rough.height_m(x, y) for x, y in zip(xs.ravel(), ys.ravel())])
    assert np.max(np.abs(h)) <= 0.04 + 1e-9 and np.max(np.abs(h)) > 0.03
    assert abs(rough.height_m(0.3, -0.2)) < 1e-7  # the flat start patch
    assert rough.height_m(5.0, 0.0) != parse_terrain("rough:0.04:4").height_m(5.0, 0.0)  # the seed matters


def test_the_0_deg_waves_grid_is_the_ridges_across_the_path_array_for_array():
    from amlip_qp.sim.world import terrain_grids as G

    for h, lam in ((0.3, 4.0), (0.6, 2.25), (0.05, 0.2)):
        # the ridges across the path as they were built before a heading could be given
        n_waves = max(int(math.ceil((G.FRONT_M - START_X_M) / lam)), 1)
        n = max(int(math.ceil(n_waves * lam / G.GRID_SPACING_M)), 1)
        xs = START_X_M + (n_waves * lam / n) * np.arange(n + 1)
        profile = 0.5 * h * (1.0 - np.cos(2.0 * math.pi * (xs - START_X_M) / lam))
        profile[0] = profile[-1] = 0.0
        rows = np.tile(profile, (17, 1))  # y every 0.5 m over |y| <= 4 m
        lo, span = float(rows.min()), float(rows.max() - rows.min())
        for grid in (G.waves_grid(h, lam, START_X_M), G.waves_grid(h, lam, START_X_M, 0.0)):
            assert np.array_equal(grid.data, ((rows - lo) / span).astype(np.float32))
            assert (grid.x0_m, grid.y0_m, grid.dy_m, grid.z0_m, grid.elevation_m) == (START_X_M, -4.0, 0.5, lo, span)
        a, b = parse_terrain(f"waves:{h}:{lam}"), parse_terrain(f"waves:{h}:{lam}:0")
        assert a.text == b.text and np.array_equal(a.grid.data, b.grid.data)


@pytest.mark.parametrize("heading", [0.0, 30.0, -45.0, 90.0])
def test_the_waves_height_field_samples_the_analytic_field(heading):
    """The surface MuJoCo collides with is the smooth field to within its linear interpolation:
    half the field's curvature (2 pi / wavelength)^2 h / 2 times the squared half-diagonal of a cell."""
    from amlip_qp.sim.world.terrain_grids import GRID_SPACING_M, waves_height_m

    h, lam = 0.6, 2.25
    spec = parse_terrain(f"waves:{h}:{lam}:{heading:g}")
    rng = np.random.default_rng(0)
    x0 = START_X_M if heading == 0.0 else -3.9
    xs, ys = rng.uniform(x0, 29.0, 4000), rng.uniform(-HALF_WIDTH_M, HALF_WIDTH_M, 4000)
    smooth = waves_height_m(xs, ys, h, lam, heading, START_X_M)
    surface = np.array([spec.height_m(x, y) for x, y in zip(xs, ys)])
    bound = 0.5 * (2.0 * math.pi / lam) ** 2 * (0.5 * h) * 0.5 * GRID_SPACING_M**2 + 1e-6
    err = np.abs(surface - smooth)
    assert np.max(err) < bound  # about 1.2 mm for these 60 cm waves
    assert np.max(err) > 0.1 * bound  # the grid is a grid, not the function itself
    assert np.max(smooth) == pytest.approx(h, abs=1e-3) and np.min(smooth) == pytest.approx(0.0, abs=1e-3)


def test_waves_at_90_deg_run_along_the_path_with_the_robot_in_a_valley():
    h, lam = 0.6, 2.25
    spec = parse_terrain(f"waves:{h}:{lam}:90")
    for x in (-3.0, 0.0, 0.4, 5.0, 20.0):
        assert spec.height_m(x, 0.0) == pytest.approx(0.0, abs=1e-6)  # the valley floor under the path
        assert spec.height_m(x, lam / 2) == pytest.approx(h, abs=1e-3)  # the ridges beside it
        assert spec.height_m(x, -lam / 2) == pytest.approx(h, abs=1e-3)
        assert spec.height_m(x, lam) == pytest.approx(0.0, abs=1e-3)  # the next valley
    # the feet of a robot standing 0.25 m wide at the start are 2 cm up the valley's sides
    assert spec.height_m(0.0, 0.125) == pytest.approx(0.5 * h * (1 - math.cos(2 * math.pi * 0.125 / lam)), abs=1e-3)
    # 30 deg: the line through the start along the ridges is a valley floor too
    oblique = parse_terrain(f"waves:{h}:{lam}:30")
    for t in (-4.0, -2.0, 0.0, 3.0, 4.0):  # |y| <= 3.5 m, on the terrain
        x, y = -t * math.sin(math.radians(30.0)), t * math.cos(math.radians(30.0))
        assert oblique.height_m(x + 4.0, y) == pytest.approx(oblique.height_m(4.0, 0.0), abs=2e-3)
    assert oblique.height_m(0.0, 0.0) == pytest.approx(0.0, abs=1e-6)


def test_the_robot_starts_standing_in_the_valley_of_90_deg_waves():
    plant, spec = _plant("cassie", "waves:0.6:2.25:90")
    ground = ground_height_function(plant, spec)
    assert ground(0.0, 0.0) == pytest.approx(0.0, abs=1e-6)
    assert ground(3.0, 1.125) == pytest.approx(0.6, abs=2e-3)
    data = mujoco.MjData(plant.model)
    mujoco.mj_resetDataKeyframe(plant.model, data, 0)
    mujoco.mj_forward(plant.model, data)
    # the stand keyframe is lifted onto the valley's sides under the feet: 2 cm at most
    assert 0.0 <= data.qpos[2] - factory.load("cassie").qpos_stand[2] < 0.03


@pytest.mark.parametrize("text", [*KINDS, "waves:0.6:2.25:90", "waves:0.3:4:35"])
def test_analytic_height_matches_mujoco_ray_casts(text):
    plant, spec = _plant("cassie", text)
    ground = ground_height_function(plant, spec)
    grid = spec.grid
    xs = np.linspace(-3.0, 24.0, 271)
    ys = list(np.linspace(-HALF_WIDTH_M + 0.3, HALF_WIDTH_M - 0.3, 7))
    if grid is not None:  # also exactly on a row of the height field (MuJoCo's ray misses some of those)
        ys.append(grid.y0_m + 9 * grid.dy_m)
    err = max(abs(ground(x, y) - spec.height_m(x, y)) for x in xs for y in ys)
    assert err < 1e-3
    # the robot's own geoms are not terrain: the ray under the pelvis finds the ground
    assert ground(0.0, 0.0) == pytest.approx(spec.height_m(0.0, 0.0), abs=1e-6)


def test_rabbit_walks_in_the_xz_plane_of_every_terrain():
    for text in KINDS:
        plant, spec = _plant("rabbit", text)
        ground = ground_height_function(plant, spec)
        for x in np.linspace(-1.0, 12.0, 53):
            assert ground(x, 0.0) == pytest.approx(spec.height_m(x, 0.0), abs=1e-3)


def test_terrain_geoms_are_in_their_group_with_the_floor_contact():
    plant, _ = _plant("cassie", "stairs:0.1:0.3")
    m = plant.model
    static = np.flatnonzero(m.body_weldid[m.geom_bodyid] == 0)
    floor = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, "floor")
    assert len(static) == 1 + 4 + 1 + 3  # the floor, 4 steps up, the landing, 3 steps down
    assert np.all(m.geom_group[static] == TERRAIN_GEOM_GROUP)
    for g in static:
        assert (m.geom_contype[g], m.geom_conaffinity[g]) == (m.geom_contype[floor], m.geom_conaffinity[floor])
        assert np.array_equal(m.geom_friction[g], m.geom_friction[floor])
        assert np.array_equal(m.geom_solref[g], m.geom_solref[floor])


def test_ground_function_of_a_flat_plant_and_a_mismatched_spec():
    robot = factory.load("cassie")
    plant = load_plant("cassie", robot)
    flat = ground_height_function(plant, parse_terrain("flat"))
    assert flat(0.0, 0.0) == 0.0 and flat(3.0, -1.0) == 0.0  # the floor, not the robot above it
    with pytest.raises(InputError, match="has no terrain geoms"):
        ground_height_function(plant, parse_terrain("slope:10"))


# ---------------------------------------------------------------- keyframes
def _foot_clearances_m(plant, spec):
    """(min, max) over the foot contact geoms of their distance to the terrain below, m, at the keyframe."""
    data = plant.new_data()
    m = plant.model
    out = []
    for body in plant.foot_body_ids.values():
        for g in np.flatnonzero(m.geom_bodyid == body):
            if m.geom_conaffinity[g] or m.geom_contype[g]:
                x, y, z = data.geom_xpos[g]
                out.append(z - m.geom_size[g, 0] - spec.height_m(x, y))
    return min(out), max(out), data


@pytest.mark.parametrize("robot", ["cassie", "rabbit"])
def test_keyframe_lifted_onto_a_ramp_under_the_feet(robot, tmp_path):
    """A 2 m high, 10 m long gray ramp (11 deg) starting 1 m behind the robot: it stands on it at the start."""
    _ramp_png(tmp_path / "ramp.png")
    spec = parse_terrain(f"hfield:{tmp_path / 'ramp.png'}:10:4:2")
    plant = load_plant(robot, factory.load(robot), edits=[terrain_edit(spec)])
    flat_plant = load_plant(robot, factory.load(robot))
    lo, hi, data = _foot_clearances_m(plant, spec)
    assert -3e-3 < lo < 1e-3  # touching, not penetrating by more than a few mm
    assert hi < 0.05  # the other foot hangs at most a few cm above the slope
    penetration = [data.contact[i].dist for i in range(data.ncon)]
    assert penetration and min(penetration) > -3e-3  # the first mj_forward has feet in contact
    lift = plant.new_data().qpos - flat_plant.new_data().qpos
    ground_under_start = spec.height_m(0.0, 0.0)
    assert ground_under_start == pytest.approx(0.2, abs=0.01)  # 1 m into the ramp
    assert np.count_nonzero(lift) == 1 and 0.15 < lift.max() < 0.3


@pytest.mark.parametrize("text", KINDS)
def test_terrains_starting_ahead_leave_the_keyframe_on_the_flat(text):
    plant, spec = _plant("cassie", text)
    flat_plant = load_plant("cassie", factory.load("cassie"))
    assert np.allclose(plant.new_data().qpos, flat_plant.new_data().qpos, atol=1e-6)
    lo, _, _ = _foot_clearances_m(plant, spec)
    assert abs(lo) < 1e-6


def test_a_plant_without_floor_or_liftable_root_is_an_mjcf_error():
    no_floor = mujoco.MjSpec.from_string(
        '<mujoco><worldbody><body pos="0 0 1"><freejoint/><geom size="0.1"/></body></worldbody></mujoco>'
    )
    with pytest.raises(MJCFError, match="no floor"):
        terrain_edit(parse_terrain("slope:10"))(no_floor)
    hinged = mujoco.MjSpec.from_string(
        '<mujoco><worldbody><geom type="plane" size="0 0 1"/><body pos="0 0 1"><joint axis="0 1 0"/>'
        '<geom size="0.1"/></body></worldbody><keyframe><key qpos="0"/></keyframe></mujoco>'
    )
    with pytest.raises(MJCFError, match="neither a free joint nor a slide joint along z"):
        terrain_edit(parse_terrain("waves:0.3:4"))(hinged)


# ------------------------------------------------------------- flat = today
def test_flat_changes_nothing():
    robot = factory.load("cassie")
    assert factory.setting_edits(PlantSetting(), robot) == []
    assert factory.setting_edits(PlantSetting(terrain="flat"), robot) == []
    today = load_plant("cassie", robot)
    flat = load_plant("cassie", robot, edits=[terrain_edit(parse_terrain("flat"))])
    a, b = today.model, flat.model
    assert (a.nbody, a.ngeom, a.nhfield) == (b.nbody, b.ngeom, b.nhfield)
    assert np.array_equal(a.geom_group, b.geom_group) and np.array_equal(a.geom_pos, b.geom_pos)
    da, db = today.new_data(), flat.new_data()
    for _ in range(200):  # a passive drop: the same trajectory, bit for bit
        mujoco.mj_step(a, da)
        mujoco.mj_step(b, db)
    assert np.array_equal(da.qpos, db.qpos)
    assert PlantSetting().describe()["terrain"] == "flat"


# ------------------------------------------------------------------ the PNG
@pytest.mark.parametrize("dtype", [np.uint8, np.uint16])
def test_png_round_trip(tmp_path, dtype):
    rng = np.random.default_rng(1)
    top = np.iinfo(dtype).max
    img = rng.integers(0, top + 1, size=(6, 9)).astype(dtype)
    img[0, 0], img[-1, -1] = 0, top  # the full gray range: heights 0 .. HEIGHT_M
    path = tmp_path / "map.png"
    iio.imwrite(path, img)
    spec = parse_terrain(f"hfield:{path}:8:5:0.4")
    assert spec.text == f"hfield:{path}:8:5:0.4"
    # pixel (row i, col j) is the grid point x = -1 + j, y = 2.5 - i (top row at +y)
    for i in range(6):
        for j in range(9):
            assert spec.height_m(-1.0 + j, 2.5 - i) == pytest.approx(0.4 * img[i, j] / top, abs=1e-6)
    plant = load_plant("cassie", factory.load("cassie"), edits=[terrain_edit(spec)])
    ground = ground_height_function(plant, spec)
    for x, y in rng.uniform([-1.0, -2.5], [7.0, 2.5], size=(300, 2)):
        assert ground(x, y) == pytest.approx(spec.height_m(x, y), abs=1e-3)


@pytest.mark.slow
def test_the_qp_controller_stands_on_a_ramp_it_starts_on(tmp_path):
    """Started on an 11 deg ramp (keyframe lifted), 0.5 s of the controller stepping in place: feet on the ground."""
    from amlip_qp.sim.scenarios.scenarios import Scenario

    _ramp_png(tmp_path / "ramp.png")
    setting = PlantSetting(terrain=f"hfield:{tmp_path / 'ramp.png'}:10:4:2")
    sim = factory.build_simulation(Scenario("ramp", "cassie", 0.5, setting=setting), "qp")
    res = sim.run(0.5)
    assert not res.fell
    spec = parse_terrain(setting.terrain)
    m, d = sim.model, sim.data
    clearance = []
    for body in sim.plant.foot_body_ids.values():
        for g in np.flatnonzero((m.geom_bodyid == body) & (m.geom_conaffinity > 0)):
            x, y, z = d.geom_xpos[g]
            clearance.append(z - m.geom_size[g, 0] - spec.height_m(x, y))
    assert min(clearance) > -5e-3  # no foot sank into the ramp
    stance = [min(clearance[:2]), min(clearance[2:])]
    assert min(stance) < 5e-3  # a foot stands on it
    base = res.log["base_pos"]
    base_above_ground = base[:, 2] - np.array([spec.height_m(x, y) for x, y in base[:, :2]])
    assert base_above_ground.min() > 0.8


def test_a_gray_and_alpha_png_reads_its_gray_level_not_the_alpha(tmp_path):
    from amlip_qp.sim.world.terrain_grids import read_gray_png

    gray = np.array([[0, 64], [128, 255]], dtype=np.uint8)
    path = tmp_path / "la.png"
    iio.imwrite(path, np.stack([gray, np.full_like(gray, 255)], axis=-1))  # opaque gray + alpha
    assert np.allclose(read_gray_png(str(path)), gray / 255.0)


def test_ray_casts_skip_robot_geoms_that_share_the_terrain_group():
    from amlip_qp.sim.world.terrain import TERRAIN_GEOM_GROUP

    spec = parse_terrain("waves:0.3:4")

    def robot_in_terrain_group(s: mujoco.MjSpec) -> None:  # as a model with its visuals in group 2 would be
        for geom in s.geoms:
            if not geom.name.startswith("amlip-terrain") and geom.parent.name != "world":
                geom.group = TERRAIN_GEOM_GROUP

    plant = load_plant("cassie", factory.load("cassie"), edits=[terrain_edit(spec), robot_in_terrain_group])
    moving = plant.model.body_weldid[plant.model.geom_bodyid] != 0
    assert np.any(moving & (plant.model.geom_group == TERRAIN_GEOM_GROUP))
    ground = ground_height_function(plant, spec)
    for x in (0.0, 0.05, 1.7, 3.2):  # under the standing robot, and ahead on the waves
        assert ground(x, 0.0) == pytest.approx(spec.height_m(x, 0.0), abs=1e-6)
