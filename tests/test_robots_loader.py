"""Tests of amlip_qp.robots.loader: loading both models from one MJCF, and bad input."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

from amlip_qp.exceptions import InputError, MJCFError, ModelFileError, UnknownRobotError
from amlip_qp.paths import MODELS_DIR
from amlip_qp.profiles import PROFILES, get_profile
from amlip_qp.robots import load_robot

CASSIE_XML = MODELS_DIR / "cassie.xml"


@pytest.fixture(scope="module")
def rabbit():
    return load_robot("rabbit")


def test_rabbit_description(rabbit):
    assert rabbit.name == "rabbit"
    assert rabbit.path == (MODELS_DIR / "rabbit.xml").resolve()
    assert rabbit.nq == rabbit.nv == 7 and rabbit.mj_model.nq == 7
    assert rabbit.foot_sides == ("left", "right")
    assert rabbit.is_planar and not rabbit.is_floating
    assert rabbit.root_joint_names == ("root-x", "root-z", "root-pitch")
    assert rabbit.base_body == "torso"
    assert rabbit.joint_names == ("left-hip", "left-knee", "right-hip", "right-knee")
    assert rabbit.actuated.joint_names == rabbit.joint_names
    assert rabbit.passive_joint_names == ()
    np.testing.assert_array_equal(rabbit.actuated.pin_v_idx, [3, 4, 5, 6])
    np.testing.assert_array_equal(rabbit.actuated.mj_dof_idx, [3, 4, 5, 6])
    np.testing.assert_array_equal(rabbit.actuated.gear, np.ones(4))
    np.testing.assert_array_equal(rabbit.actuated.torque_limit_Nm, [[-150.0, 150.0]] * 4)
    assert rabbit.mass_kg == pytest.approx(32.0, abs=1e-12)
    assert rabbit.contact_sites == {"left": "left-contact", "right": "right-contact"}
    assert rabbit.force_sites == {"left": ("left-contact",), "right": ("right-contact",)}
    assert rabbit.couplings == ()
    np.testing.assert_array_equal(rabbit.dof_stiffness, np.zeros(7))
    np.testing.assert_allclose(rabbit.q_stand, rabbit.qpos_stand)  # planar: same coordinates
    assert rabbit.q_stand[1] == pytest.approx(0.8046704254145137)


def test_new_data(rabbit):
    d = rabbit.new_mj_data("stand")
    np.testing.assert_allclose(d.qpos, rabbit.qpos_stand)
    assert rabbit.new_mj_data().qpos[1] == 0.0
    assert rabbit.new_pin_data() is not rabbit.new_pin_data()
    with pytest.raises(InputError, match="no keyframe named 'sit'"):
        rabbit.new_mj_data("sit")


def test_path_and_name_are_equivalent(rabbit):
    by_path = load_robot(MODELS_DIR / "rabbit.xml")
    assert by_path.name == "rabbit" and by_path.nv == rabbit.nv
    assert by_path.profile is rabbit.profile is get_profile("rabbit")  # the bundled file: its profile
    assert load_robot(str(MODELS_DIR / "rabbit.xml")).mass_kg == rabbit.mass_kg
    assert load_robot("  Rabbit ").name == "rabbit"


def test_bundled_robots_are_the_profiles_and_a_copy_elsewhere_has_no_profile(rabbit, tmp_path):
    for name, profile in PROFILES.items():
        robot = load_robot(name)
        assert robot.profile is profile
        if not profile.model.edits_needed and profile.feet.body is None:
            assert robot.path == profile.model.path  # no edits: the file itself
        else:
            assert robot.path.parent.name == "models" and robot.path != profile.model.path  # the edited copy
    copy = tmp_path / "rabbit.xml"
    copy.write_text((MODELS_DIR / "rabbit.xml").read_text())
    other = load_robot(copy)
    assert other.name == "rabbit" and other.nv == rabbit.nv
    assert other.profile is None  # not the bundled file: its facts come from the model alone


def test_lazy_top_level_export():
    code = (
        "import sys, amlip_qp; heavy = [m for m in ('mujoco', 'pinocchio') if m in sys.modules]; "
        "assert not heavy, heavy; r = amlip_qp.load_robot('rabbit'); print(r.nv)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "7"


def test_cassie_description():
    cassie = load_robot("cassie")
    assert cassie.is_floating and not cassie.is_planar
    assert cassie.nq == 21 and cassie.nv == 20
    assert cassie.base_body == "cassie-pelvis"
    assert cassie.force_sites["left"] == ("left-toe", "left-heel")
    assert set(cassie.passive_joint_names) == {f"{s}-{j}" for s in ("left", "right") for j in ("shin", "tarsus")}
    assert len(cassie.actuated) == 10
    mj = cassie.mj_model
    # joint-side limits = gear * ctrlrange (and the joints' actuatorfrcrange)
    for a in range(mj.nu):
        expect = mj.actuator_gear[a, 0] * mj.actuator_ctrlrange[a]
        j = mj.actuator_trnid[a, 0]
        if mj.jnt_actfrclimited[j]:
            expect = np.clip(expect, *mj.jnt_actfrcrange[j])
        np.testing.assert_allclose(cassie.actuated.torque_limit_Nm[a], expect)
    assert len(cassie.couplings) == 2
    for side, c in zip(("left", "right"), cassie.couplings):
        assert set(c.joint_names) == {f"{side}-knee", f"{side}-tarsus"}
        np.testing.assert_allclose(c.coefficients, [1.0, 1.0])
        assert c.springlength[0] == pytest.approx(0.2269, abs=1e-4)
        assert c.stiffness == pytest.approx(1250.0)
    shin_v = cassie.state_map.joint_pin_v["left-shin"]
    assert cassie.dof_stiffness[shin_v] == pytest.approx(1500.0)
    assert cassie.mass_kg == pytest.approx(float(np.sum(mj.body_mass)))
    # the stand keyframe in Pinocchio's convention: quaternion xyzw = (0, 0, 0, 1)
    np.testing.assert_allclose(cassie.q_stand[3:7], [0, 0, 0, 1], atol=1e-12)


# ------------------------------------------------------------------ bad input
def test_unknown_robot_name():
    with pytest.raises(
        UnknownRobotError, match=r"unknown robot 'atlas'.*'cassie', 'g1', 'h1', 'rabbit'.*\.toml.*\.xml"
    ):
        load_robot("atlas")


def test_missing_file(tmp_path):
    missing = tmp_path / "nothere.xml"
    with pytest.raises(ModelFileError, match="nothere.xml"):
        load_robot(missing)


def test_xml_syntax_error(tmp_path):
    bad = tmp_path / "broken.xml"
    bad.write_text("<mujoco><worldbody><body name='a'></worldbod></mujoco>")
    with pytest.raises(MJCFError, match=r"broken\.xml.*MuJoCo cannot load.*XML"):
        load_robot(bad)


def test_mujoco_compile_error(tmp_path):
    bad = tmp_path / "badattr.xml"
    bad.write_text(
        "<mujoco><worldbody><body name='a'><freejoint/>"
        "<geom type='sphere' size='0.1' bogus='1'/></body></worldbody></mujoco>"
    )
    with pytest.raises(MJCFError, match=r"badattr\.xml.*unrecognized attribute: 'bogus'"):
        load_robot(bad)


def test_missing_contact_sites(tmp_path):
    bad = tmp_path / "nosites.xml"
    bad.write_text(
        "<mujoco><worldbody><body name='base'><freejoint/>"
        "<geom type='sphere' size='0.1'/><site name='left-contact'/></body></worldbody></mujoco>"
    )
    with pytest.raises(MJCFError, match=r"nosites\.xml.*missing required contact site\(s\) right-contact"):
        load_robot(bad)


def test_half_blade_foot(tmp_path):
    bad = tmp_path / "toeonly.xml"
    bad.write_text(
        "<mujoco><worldbody><body name='base'><freejoint/><geom type='sphere' size='0.1'/>"
        "<site name='left-contact'/><site name='right-contact'/><site name='left-toe'/>"
        "<site name='right-toe'/><site name='right-heel'/></body></worldbody></mujoco>"
    )
    with pytest.raises(MJCFError, match="left-heel is missing"):
        load_robot(bad)


def test_second_body_tree_is_rejected(tmp_path):
    """Pinocchio reads only the first tree: the loader must say so, not mis-map states."""
    bad = tmp_path / "twotrees.xml"
    bad.write_text(
        "<mujoco><worldbody>"
        "<body name='base'><freejoint/><geom type='sphere' size='0.1'/>"
        "<site name='left-contact'/><site name='right-contact'/></body>"
        "<body name='other'><freejoint/><geom type='sphere' size='0.1'/></body>"
        "</worldbody></mujoco>"
    )
    with pytest.raises(MJCFError, match=r"Pinocchio built nv=6 but MuJoCo nv=12"):
        load_robot(bad)


def test_four_point_foot_missing_a_corner_or_its_sole_line(tmp_path):
    corners = "".join(
        f"<site name='{s}-{c}'/>" for s in ("left", "right") for c in ("toe-left", "toe-right", "heel-left")
    )
    line = "".join(f"<site name='{s}-{c}'/>" for s in ("left", "right") for c in ("toe", "heel"))
    head = "<mujoco><worldbody><body name='base'><freejoint/><geom type='sphere' size='0.1'/>"
    head += "<site name='left-contact'/><site name='right-contact'/>"
    bad = tmp_path / "threecorners.xml"
    bad.write_text(f"{head}{corners}{line}</body></worldbody></mujoco>")
    with pytest.raises(MJCFError, match=r"site\(s\) left-heel-right missing: a four-point foot needs its corners"):
        load_robot(bad)
    all_corners = corners + "<site name='left-heel-right'/><site name='right-heel-right'/>"
    bad.write_text(f"{head}{all_corners}</body></worldbody></mujoco>")
    with pytest.raises(MJCFError, match=r"left-toe missing: .* sole line's ends left-toe, left-heel"):
        load_robot(bad)
