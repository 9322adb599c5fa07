"""Tests of amlip_qp/models/rabbit.xml: published parameters, conventions, contacts, keyframe, pinned standing."""

from __future__ import annotations

import mujoco
import numpy as np
import pinocchio as pin
import pytest

from amlip_qp.paths import MODELS_DIR
from amlip_qp.robots import RobotKinematics, load_robot, mj_to_pin

RABBIT_XML = MODELS_DIR / "rabbit.xml"


@pytest.fixture(scope="module")
def model():
    return mujoco.MjModel.from_xml_path(str(RABBIT_XML))


def body(model, name):
    return mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, name)


@pytest.mark.parametrize(
    "name, mass, com_z, iyy",
    [
        ("torso", 12.0, 0.24, 1.33),
        ("left-thigh", 6.8, -0.11, 0.47),
        ("right-thigh", 6.8, -0.11, 0.47),
        ("left-shin", 3.2, -0.24, 0.20),
        ("right-shin", 3.2, -0.24, 0.20),
    ],
)
def test_published_parameters(model, name, mass, com_z, iyy):
    b = body(model, name)
    assert model.body_mass[b] == pytest.approx(mass)
    np.testing.assert_allclose(model.body_ipos[b], [0.0, 0.0, com_z], atol=1e-12)
    np.testing.assert_allclose(model.body_iquat[b], [1, 0, 0, 0], atol=1e-12)  # principal axes = body axes
    assert model.body_inertia[b][1] == pytest.approx(iyy)
    assert np.all(model.body_inertia[b] > 0)


def test_lengths_total_mass_and_options(model):
    assert model.body_subtreemass[0] == pytest.approx(32.0)
    assert model.opt.timestep == 0.0005
    np.testing.assert_allclose(model.opt.gravity, [0, 0, -9.81])
    np.testing.assert_allclose(model.body_pos[body(model, "left-shin")], [0, 0, -0.4])  # thigh 0.4 m
    site = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, "left-contact")
    np.testing.assert_allclose(model.site_pos[site], [0, 0, -0.4])  # shin 0.4 m
    torso_geom = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, "torso")
    assert 2 * model.geom_size[torso_geom][1] == pytest.approx(0.625)  # capsule half length
    cam = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_CAMERA, "track")
    assert model.cam_mode[cam] == mujoco.mjtCamLight.mjCAMLIGHT_TRACKCOM


def test_joints_and_motors(model):
    names = [mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, j) for j in range(model.njnt)]
    assert names == ["root-x", "root-z", "root-pitch", "left-hip", "left-knee", "right-hip", "right-knee"]
    types = list(model.jnt_type)
    assert types == [2, 2, 3, 3, 3, 3, 3]  # slide, slide, then hinges
    np.testing.assert_allclose(model.jnt_axis[2:], [[0, 1, 0]] * 5)
    for a in range(model.nu):
        j = model.actuator_trnid[a, 0]
        assert mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_ACTUATOR, a) == names[j]
        assert model.actuator_gear[a, 0] == 1.0
        np.testing.assert_allclose(model.actuator_ctrlrange[a], [-150, 150])
    assert model.nu == 4


def test_pitch_and_leg_sign_conventions(model):
    d = mujoco.MjData(model)
    d.qpos[2] = 0.3  # root-pitch > 0: torso leans forward
    mujoco.mj_kinematics(model, d)
    assert d.xmat[body(model, "torso")].reshape(3, 3)[0, 2] > 0
    d.qpos[:] = 0
    d.qpos[3] = -0.3  # left hip < 0: thigh swings forward
    mujoco.mj_kinematics(model, d)
    knee = d.xpos[body(model, "left-shin")]
    assert knee[0] > 0
    d.qpos[3], d.qpos[4] = 0, 0.5  # knee > 0: shin folds backwards
    mujoco.mj_kinematics(model, d)
    assert d.site_xpos[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, "left-contact")][0] < 0


def test_only_feet_collide_with_floor(model):
    def collide(g1, g2):
        return bool(model.geom_contype[g1] & model.geom_conaffinity[g2]) or bool(
            model.geom_contype[g2] & model.geom_conaffinity[g1]
        )

    names = [mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_GEOM, g) for g in range(model.ngeom)]
    pairs = {(names[a], names[b]) for a in range(model.ngeom) for b in range(a + 1, model.ngeom) if collide(a, b)}
    assert pairs == {("floor", "left-foot"), ("floor", "right-foot")}
    for side in ("left", "right"):
        g = names.index(f"{side}-foot")
        assert model.geom_size[g][0] == 0.02 and model.geom_friction[g][0] > 0
        site = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, f"{side}-contact")
        np.testing.assert_allclose(model.geom_pos[g], model.site_pos[site])


def test_stand_keyframe(model):
    d = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, d, mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_KEY, "stand"))
    mujoco.mj_forward(model, d)
    for side in ("left", "right"):
        site = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, f"{side}-contact")
        assert d.site_xpos[site][2] == pytest.approx(0.02, abs=1e-9)  # sphere touches the floor
    assert d.qpos[4] > 0.1 and d.qpos[6] > 0.1  # knees slightly bent
    assert d.qpos[2] == 0.0  # torso upright


def test_pinocchio_loads_it():
    pm = pin.buildModelFromMJCF(str(RABBIT_XML))
    assert pm.nq == pm.nv == 7
    assert sum(i.mass for i in pm.inertias) == pytest.approx(32.0)


def test_pinned_rabbit_holds_its_stand_pose_for_two_seconds():
    """Root joints fixed by joint equalities (added with MjSpec); joint PD + gravity feed-forward."""
    robot = load_robot("rabbit")
    spec = mujoco.MjSpec.from_file(str(robot.path))
    for name, value in zip(robot.root_joint_names, robot.qpos_stand[:3]):
        eq = spec.add_equality(type=mujoco.mjtEq.mjEQ_JOINT, name1=name)
        data = np.zeros(len(eq.data))
        data[0] = value  # q = qpos0 (= 0) + data[0]
        eq.data = data
        eq.solref = [0.002, 1.0]  # stiff pin (2 ms time constant)
    m = spec.compile()
    d = mujoco.MjData(m)
    mujoco.mj_resetDataKeyframe(m, d, 0)
    mujoco.mj_forward(m, d)
    act = robot.actuated
    kin = RobotKinematics(robot)
    kin.update(*mj_to_pin(robot, d.qpos, d.qvel))
    tau_ff = kin.nonlinear_effects()[act.pin_v_idx]
    q_ref = d.qpos[act.mj_qpos_idx].copy()
    joint_err = root_err = 0.0
    for _ in range(int(round(2.0 / m.opt.timestep))):
        tau = tau_ff + 400.0 * (q_ref - d.qpos[act.mj_qpos_idx]) - 20.0 * d.qvel[act.mj_dof_idx]
        d.ctrl[:] = np.clip(tau, act.torque_limit_Nm[:, 0], act.torque_limit_Nm[:, 1]) / act.gear
        mujoco.mj_step(m, d)
        joint_err = max(joint_err, np.abs(d.qpos[act.mj_qpos_idx] - q_ref).max())
        root_err = max(root_err, np.abs(d.qpos[:3] - robot.qpos_stand[:3]).max())
    assert joint_err < 0.01  # rad; the feet touch the floor, whose contact forces load the PD
    assert root_err < 1e-4
