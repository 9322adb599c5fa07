"""sim/world/plant_start.py: a plant without a ``stand`` keyframe starts from the controller's stand, loops closed.

The bundled closed-chain Cassie, copied with its keyframe removed, is the
main case: its generator made its keyframe the same way (cassie.xml's stand,
the passive loop joints moved to close the loops), so the inferred pose must
put every body where the bundled keyframe does.
"""

from __future__ import annotations

import re

import mujoco
import numpy as np
import pytest

from amlip_qp import cli
from amlip_qp.exceptions import InputError
from amlip_qp.paths import MODELS_DIR
from amlip_qp.sim.loop.run_types import PlantSetting
from amlip_qp.sim.scenarios import factory
from amlip_qp.sim.scenarios.scenarios import Scenario, SpeedProfile
from amlip_qp.sim.world.plant_loader import load_plant
from amlip_qp.sim.world.plant_start import SETTLED_TOL, STAND_KEYFRAME, equality_residual, stand_qpos
from amlip_qp.sim.world.terrain import parse_terrain, terrain_edit

CLOSED_CHAIN = MODELS_DIR / "cassie-closed-chain.xml"
SIDES = ("left", "right")
RODS = tuple(f"{s}-achilles-rod" for s in SIDES)


def without_keyframe(text: str) -> str:
    stripped = re.sub(r"\s*<keyframe>.*?</keyframe>", "", text, flags=re.S)
    assert "<key" not in stripped
    return stripped


@pytest.fixture(scope="module")
def robot():
    return factory.load("cassie")


@pytest.fixture
def keyless(tmp_path):
    path = tmp_path / "cassie-closed-chain-keyless.xml"
    path.write_text(without_keyframe(CLOSED_CHAIN.read_text()))
    return path


def posed(model: mujoco.MjModel, qpos: np.ndarray) -> mujoco.MjData:
    data = mujoco.MjData(model)
    data.qpos[:] = qpos
    mujoco.mj_kinematics(model, data)
    return data


def test_the_closed_chain_starts_where_its_bundled_keyframe_puts_it_with_the_loops_closed(keyless, robot):
    plant = load_plant(keyless, robot)
    bundled = load_plant("cassie-closed-chain", robot)
    assert plant.model.nkey == 1 and plant.model.key(STAND_KEYFRAME).id == 0
    q, q_ref = plant.model.key_qpos[0], bundled.model.key_qpos[bundled.model.key(STAND_KEYFRAME).id]
    # the loops: every equality row closed (measured 4.8e-16 m)
    residual, _ = equality_residual(plant.model, posed(plant.model, q))
    assert residual.size == 12 and np.max(np.abs(residual)) < SETTLED_TOL
    # every body where the bundled keyframe puts it (a rod may spin about its own axis: its orientation differs)
    data, ref = posed(plant.model, q), posed(bundled.model, q_ref)
    np.testing.assert_allclose(data.xpos, ref.xpos, atol=1e-9)
    rods = [plant.model.body(r).id for r in RODS]
    others = [b for b in range(plant.model.nbody) if b not in rods]
    np.testing.assert_allclose(data.xquat[others], ref.xquat[others], atol=1e-9)
    np.testing.assert_allclose(data.site_xpos, ref.site_xpos, atol=1e-9)  # the rods' loop ends too
    # the controller's joints hold the controller's stand exactly; the heel springs deflect to close the loops
    mapped = plant.qpos_adr >= 0
    np.testing.assert_array_equal(q[plant.qpos_adr[mapped]], robot.qpos_stand[mapped])
    for s in SIDES:
        heel = q[plant.model.joint(f"{s}-heel-spring").qposadr[0]]
        assert heel == pytest.approx(-0.0068953, abs=1e-6)  # the bundled keyframe's -0.00689527 rad


def test_the_contact_points_stand_as_high_as_in_the_controllers_stand(tmp_path, robot):
    """Legs 3 cm longer in the plant (the hips lower in the pelvis): the base starts 3 cm higher."""
    spec = mujoco.MjSpec.from_string(without_keyframe(CLOSED_CHAIN.read_text()))
    for s in SIDES:
        hip = spec.body(f"{s}-hip-roll")
        hip.pos = [hip.pos[0], hip.pos[1], hip.pos[2] - 0.03]
    path = tmp_path / "long-legs.xml"
    path.write_text(spec.to_xml())
    plant = load_plant(path, robot)
    q = plant.model.key_qpos[0]
    assert q[2] == pytest.approx(robot.qpos_stand[2] + 0.03, abs=1e-9)
    data, ctrl = posed(plant.model, q), posed(robot.mj_model, robot.qpos_stand)
    for s in SIDES:
        site = robot.contact_site_ids[s]
        foot = plant.foot_body_ids[s]
        z = data.xpos[foot, 2] + data.xmat[foot].reshape(3, 3)[2] @ robot.mj_model.site_pos[site]
        assert z == pytest.approx(ctrl.site_xpos[site, 2], abs=1e-9)


def test_the_sparse_jacobian_gives_the_same_pose(keyless, robot):
    poses = {}
    for jacobian in (mujoco.mjtJacobian.mjJAC_DENSE, mujoco.mjtJacobian.mjJAC_SPARSE):
        spec = mujoco.MjSpec.from_file(str(keyless))
        spec.option.jacobian = jacobian
        path = keyless.with_name(f"jacobian-{int(jacobian)}.xml")
        path.write_text(spec.to_xml())
        plant = load_plant(path, robot)
        poses[bool(mujoco.mj_isSparse(plant.model))] = plant.model.key_qpos[0]
    np.testing.assert_allclose(poses[True], poses[False], atol=1e-12)


def test_a_terrain_lifts_the_inferred_keyframe_like_a_written_one(keyless, robot, tmp_path):
    import imageio.v3 as iio

    level = tmp_path / "level.png"  # a white map: the ground 0.1 m up everywhere on it, under the robot too
    iio.imwrite(level, np.full((3, 3), 255, dtype=np.uint8))
    edit = terrain_edit(parse_terrain(f"hfield:{level}:4:4:0.1"))
    flat, lifted = load_plant(keyless, robot), load_plant(keyless, robot, edits=[edit])
    dz = lifted.model.key_qpos[0] - flat.model.key_qpos[0]
    assert dz[2] == pytest.approx(0.1, abs=1e-5) and np.max(np.abs(np.delete(dz, 2))) == 0.0


@pytest.mark.slow
def test_a_one_second_qp_walk_from_the_inferred_pose_does_not_fall(keyless):
    scenario = Scenario(
        "keyless", "cassie", 1.0, vx=SpeedProfile.constant(0.5), setting=PlantSetting(plant=str(keyless))
    )
    result = factory.build_simulation(scenario, "qp").run(scenario.duration_s)
    assert not result.fell and result.sim_time_s == pytest.approx(1.0)
    assert len(result.steps) >= 3  # measured: 3 steps, mean vx 0.10 m/s


# ------------------------------------------------------------------ refusals
def _spec_without_key(base: str = "cassie.xml") -> mujoco.MjSpec:
    return mujoco.MjSpec.from_string(without_keyframe((MODELS_DIR / base).read_text()))


def _write(spec: mujoco.MjSpec, path) -> str:
    path.write_text(spec.to_xml())
    return str(path)


def _add_tail(spec: mujoco.MjSpec, **joint) -> None:
    """A 0.1 kg tail hinged to the pelvis: a joint the controller's model does not have."""
    tail = spec.body("cassie-pelvis").add_body(name="tail", pos=[-0.2, 0, 0], mass=0.1, ipos=[0, 0, 0])
    tail.inertia = [1e-4, 1e-4, 1e-4]
    tail.explicitinertial = True
    tail.add_joint(name="tail-hinge", type=mujoco.mjtJoint.mjJNT_HINGE, axis=[0, 1, 0], **joint)


def test_a_joint_that_nothing_determines_is_refused_in_one_line(tmp_path, robot, capsys):
    spec = _spec_without_key()
    _add_tail(spec)
    path = _write(spec, tmp_path / "tail.xml")
    with pytest.raises(InputError) as err:
        load_plant(path, robot)
    assert str(err.value) == (
        f"plant {path} has no 'stand' keyframe, and its joints 'tail-hinge' are not in the cassie controller's "
        "model, carry no spring and close no loop, so their start cannot be inferred: add a 'stand' keyframe "
        "to its MJCF"
    )
    code = cli.main(["walk", "--plant", path, "--duration", "0.1"])
    lines = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(lines) == 1 and "'tail-hinge' are not in the cassie controller's model" in lines[0]


def test_a_joint_with_a_spring_starts_at_its_rest(tmp_path, robot):
    spec = _spec_without_key()
    _add_tail(spec, stiffness=10.0, springref=0.3)
    plant = load_plant(_write(spec, tmp_path / "sprung-tail.xml"), robot)
    assert plant.model.key_qpos[0][plant.model.joint("tail-hinge").qposadr[0]] == pytest.approx(0.3)


def test_a_base_floated_by_other_joints_is_refused(tmp_path, robot):
    spec = _spec_without_key()
    pelvis = spec.body("cassie-pelvis")
    spec.delete(pelvis.joints[0])
    for k, axis in enumerate(np.eye(3)):
        pelvis.add_joint(name=f"slide-{k}", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=axis.tolist())
    pelvis.add_joint(name="swivel", type=mujoco.mjtJoint.mjJNT_BALL)
    with pytest.raises(InputError, match="no free joint on its base body 'cassie-pelvis' to start it from"):
        load_plant(_write(spec, tmp_path / "slides.xml"), robot)


def test_a_loop_that_the_other_joints_cannot_close_is_refused(tmp_path, robot):
    """A tether holds the pelvis where the MJCF puts it (1.01 m up); the controller's stand has it 1.00627 m up."""
    spec = _spec_without_key()
    spec.add_equality(
        type=mujoco.mjtEq.mjEQ_CONNECT, name1="cassie-pelvis", name2="world", objtype=mujoco.mjtObj.mjOBJ_BODY,
        data=[0.0, 0.0, 0.0, 1.0, 0.0, 0.0] + [0.0] * 6,
    )  # fmt: skip
    with pytest.raises(InputError, match=r"its loop closures stay open by 0\.00373 \(m or rad\) in the controller's"):
        load_plant(_write(spec, tmp_path / "tethered.xml"), robot)


def test_a_written_keyframe_is_kept_as_it_is(robot):
    plant = load_plant("cassie-closed-chain", robot)
    text = CLOSED_CHAIN.read_text()
    written = re.search(r'<key name="stand" qpos="([^"]*)"', text).group(1)
    # as written, the quaternions normalised by MuJoCo's compiler (4e-13)
    np.testing.assert_allclose(plant.model.key_qpos[0], [float(x) for x in written.split()], atol=1e-12)
    # and stand_qpos, asked anyway, infers the same bodies' places from the controller's stand
    residual, _ = equality_residual(plant.model, posed(plant.model, stand_qpos(plant)))
    assert np.max(np.abs(residual)) < SETTLED_TOL
