"""amlip_qp.robots.model_edits: a profile's load-time edits of its MJCF file, checked on the compiled model."""

import dataclasses

import mujoco
import numpy as np
import pytest

from amlip_qp.exceptions import MJCFError
from amlip_qp.paths import MODELS_DIR
from amlip_qp.profiles import ModelSpec, get_profile
from amlip_qp.robots import load_robot
from amlip_qp.robots.model_edits import convert_servos, prepared_model_path


@pytest.fixture(autouse=True)
def _own_cache(tmp_path, monkeypatch):
    monkeypatch.setenv("AMLIP_QP_CACHE_DIR", str(tmp_path / "cache"))


def _compiled(profile):
    return mujoco.MjModel.from_xml_path(str(prepared_model_path(profile)))


def test_a_profile_without_edits_loads_its_own_file():
    profile = get_profile("cassie")
    assert prepared_model_path(profile) == MODELS_DIR / "cassie.xml"


def test_h1_edits_name_the_free_joint_set_the_timestep_add_a_floor_and_the_stand_keyframe():
    profile = get_profile("h1")
    m = _compiled(profile)
    assert m.opt.timestep == 0.0005
    free = [j for j in range(m.njnt) if m.jnt_type[j] == mujoco.mjtJoint.mjJNT_FREE]
    assert [mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_JOINT, j) for j in free] == ["floating_base"]
    planes = [g for g in range(m.ngeom) if m.geom_type[g] == mujoco.mjtGeom.mjGEOM_PLANE]
    assert len(planes) == 1 and m.geom_friction[planes[0], 0] == 1.0
    key = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_KEY, "stand")
    qpos = m.key_qpos[key]
    np.testing.assert_array_equal(qpos[:7], [0.0, 0.0, 0.982, 1.0, 0.0, 0.0, 0.0])
    for name, value in profile.model.stand.joints_rad.items():
        j = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, name)
        assert qpos[m.jnt_qposadr[j]] == value
    # The stand pose puts the soles' force points less than 2 mm above the floor.
    d = mujoco.MjData(m)
    mujoco.mj_resetDataKeyframe(m, d, key)
    mujoco.mj_kinematics(m, d)
    for side in ("left", "right"):
        for site in (f"{side}-toe", f"{side}-heel"):
            z = d.site_xpos[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_SITE, site)][2]
            assert 0.0 < z < 0.002, (site, z)


def test_foot_sites_sit_where_the_profile_puts_them_in_the_foot_body():
    profile = get_profile("h1")
    m = _compiled(profile)
    feet = profile.feet
    for side in ("left", "right"):
        body = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, feet.body.format(side=side))
        for site, point in ((f"{side}-contact", feet.contact_point_m),) + tuple(
            zip((f"{side}-toe", f"{side}-heel"), feet.force_points_m)
        ):
            s = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_SITE, site)
            assert m.site_bodyid[s] == body
            np.testing.assert_allclose(m.site_pos[s], point, atol=1e-12)


def test_g1_servos_become_torque_motors_over_the_joints_force_ranges():
    m = _compiled(get_profile("g1"))
    source = mujoco.MjModel.from_xml_path(str(MODELS_DIR / "unitree_g1" / "g1.xml"))
    assert source.nu == m.nu == 29
    for a in range(m.nu):
        j = m.actuator_trnid[a, 0]
        assert source.actuator_biastype[a] == mujoco.mjtBias.mjBIAS_AFFINE  # the file's position servos
        assert m.actuator_biastype[a] == mujoco.mjtBias.mjBIAS_NONE and m.actuator_gainprm[a, 0] == 1.0
        assert not np.any(m.actuator_biasprm[a])
        np.testing.assert_array_equal(m.actuator_ctrlrange[a], source.jnt_actfrcrange[j])
    # A control is a joint torque: 10 units on the left knee give 10 N m there and nothing elsewhere.
    d = mujoco.MjData(m)
    knee = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_ACTUATOR, "left_knee_joint")
    d.ctrl[knee] = 10.0
    mujoco.mj_forward(m, d)
    dof = m.jnt_dofadr[m.actuator_trnid[knee, 0]]
    assert d.qfrc_actuator[dof] == pytest.approx(10.0, abs=1e-12)
    assert np.count_nonzero(d.qfrc_actuator) == 1


def test_servos_are_refused_in_one_line_unless_the_profile_converts_them():
    profile = get_profile("g1")
    refusing = dataclasses.replace(profile, model=dataclasses.replace(profile.model, servos="refuse"))
    with pytest.raises(MJCFError, match=r"actuator 'left_hip_pitch_joint' \(and 28 more\) is a position servo") as e:
        prepared_model_path(refusing)
    assert "\n" not in str(e.value) and 'servos = "convert"' in str(e.value)
    # The bare file, without a profile: the loader refuses it too (never reads a servo as a motor).
    with pytest.raises(MJCFError, match="is a position or velocity servo"):
        load_robot(MODELS_DIR / "unitree_g1" / "g1.xml")


def test_a_servo_without_a_force_range_cannot_be_converted(tmp_path):
    xml = tmp_path / "servo.xml"
    xml.write_text(
        "<mujoco><worldbody><body><joint name='j' type='hinge'/><geom size='0.1'/></body></worldbody>"
        "<actuator><position name='p' joint='j' kp='10'/></actuator></mujoco>"
    )
    spec = mujoco.MjSpec.from_file(str(xml))
    with pytest.raises(MJCFError, match="position servo 'p' has no force range"):
        convert_servos(spec, "convert", xml)


def test_the_edited_model_is_written_once_and_changes_with_the_edits():
    profile = get_profile("h1")
    first = prepared_model_path(profile)
    stamp = first.stat().st_mtime_ns
    assert prepared_model_path(profile) == first and first.stat().st_mtime_ns == stamp
    other = dataclasses.replace(profile, model=dataclasses.replace(profile.model, timestep_s=0.001))
    second = prepared_model_path(other)
    assert second != first and mujoco.MjModel.from_xml_path(str(second)).opt.timestep == 0.001


def test_a_stand_pose_naming_a_missing_joint_is_named(tmp_path):
    profile = get_profile("h1")
    stand = dataclasses.replace(profile.model.stand, joints_rad={"left_tail": 0.1})
    bad = dataclasses.replace(profile, model=dataclasses.replace(profile.model, stand=stand))
    with pytest.raises(MJCFError, match="stand pose names 'left_tail', which is no hinge or slide joint"):
        prepared_model_path(bad)


def test_the_unedited_spec_has_what_the_edits_add():
    """Each edit adds what the file lacks (so the checks above test the edits, not the file)."""
    m = mujoco.MjModel.from_xml_path(str(MODELS_DIR / "unitree_h1" / "h1.xml"))
    assert m.opt.timestep == 0.002 and m.nkey == 0
    assert not any(m.geom_type[g] == mujoco.mjtGeom.mjGEOM_PLANE for g in range(m.ngeom))
    assert mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_SITE, "left-contact") < 0
    assert not mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_JOINT, 0)
    assert not ModelSpec(path=MODELS_DIR / "unitree_h1" / "h1.xml").edits_needed  # no edits by default


def test_a_four_point_foot_gets_its_corners_and_its_sole_line_midpoints(tmp_path):
    from sole_cases import sole_profile

    robot = load_robot(sole_profile("h1", tmp_path))
    m, feet = robot.mj_model, robot.profile.feet
    corners = ((0.14, 0.03, -0.07), (0.14, -0.03, -0.07), (-0.035, 0.03, -0.07), (-0.035, -0.03, -0.07))
    assert feet.force_points_m == corners
    for side in ("left", "right"):
        names = tuple(f"{side}-{s}" for s in ("toe-left", "toe-right", "heel-left", "heel-right"))
        assert robot.force_sites[side] == names and robot.sole_line_sites[side] == (f"{side}-toe", f"{side}-heel")
        body = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, feet.body.format(side=side))
        expected = {
            **dict(zip(names, corners)),
            f"{side}-toe": (0.14, 0.0, -0.07),
            f"{side}-heel": (-0.035, 0.0, -0.07),
        }
        for site, point in expected.items():
            s = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_SITE, site)
            assert m.site_bodyid[s] == body
            np.testing.assert_allclose(m.site_pos[s], point, atol=1e-15)
        # Pinocchio's frames are the same sites, in the same order
        frames = [robot.pin_model.frames[f].name for f in robot.force_frame_ids[side]]
        assert tuple(frames) == names
        lines = [robot.pin_model.frames[f].name for f in robot.sole_line_frame_ids[side]]
        assert tuple(lines) == (f"{side}-toe", f"{side}-heel")


def test_a_two_point_foot_has_its_force_points_as_its_sole_line():
    robot = load_robot("h1")
    for side in ("left", "right"):
        assert robot.force_sites[side] == robot.sole_line_sites[side] == (f"{side}-toe", f"{side}-heel")
        assert robot.force_frame_ids[side] == robot.sole_line_frame_ids[side]
    rabbit = load_robot("rabbit")
    assert rabbit.sole_line_sites == {"left": (), "right": ()}
