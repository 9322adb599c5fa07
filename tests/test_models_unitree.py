"""amlip_qp/models/unitree_h1/ and unitree_g1/: MuJoCo Menagerie's Unitree H1 and G1, as shipped.

The folders are built by ``models/tools/build_unitree.py`` (MJCF and LICENSE
verbatim, meshes simplified). These tests read only the package data: each
file loads in MuJoCo and in Pinocchio, and the two agree on masses, frames and
the mass matrix.
"""

from __future__ import annotations

import mujoco
import numpy as np
import pinocchio as pin
import pytest

from amlip_qp.paths import MODELS_DIR
from amlip_qp.robots.state import build_state_map, qpos_to_q, velocity_map

#: folder -> (MJCF file, nq, nv, nu, total mass in kg as measured on the shipped file).
ROBOTS = {
    "unitree_h1": ("h1.xml", 26, 25, 19, 51.437),
    "unitree_g1": ("g1.xml", 36, 35, 29, 33.341142),
}
#: The shipped folders together stay well below the ~30 MB a wheel may have (Menagerie's meshes are 34 MB).
MAX_BYTES = 15_000_000
SEEDS = (0, 1, 2)


@pytest.fixture(scope="module", params=sorted(ROBOTS))
def robot(request):
    """(folder name, MuJoCo model, Pinocchio model, state map) of one shipped robot."""
    folder = request.param
    path = MODELS_DIR / folder / ROBOTS[folder][0]
    mj_model = mujoco.MjModel.from_xml_path(str(path))
    pin_model = pin.buildModelFromMJCF(str(path))
    return folder, mj_model, pin_model, build_state_map(mj_model, pin_model, source=str(path))


def random_qpos(m, seed: int) -> np.ndarray:
    """A configuration with every hinge uniform in its range and a random base pose."""
    rng = np.random.default_rng(seed)
    qpos = m.qpos0.copy()
    for j in range(m.njnt):
        a = int(m.jnt_qposadr[j])
        if m.jnt_type[j] == mujoco.mjtJoint.mjJNT_HINGE:
            qpos[a] = rng.uniform(*m.jnt_range[j])
        elif m.jnt_type[j] == mujoco.mjtJoint.mjJNT_FREE:
            qpos[a : a + 3] = rng.uniform(-1.0, 1.0, 3)
            quat = rng.normal(size=4)
            qpos[a + 3 : a + 7] = quat / np.linalg.norm(quat)
    return qpos


def test_counts_are_menageries(robot):
    folder, m, pm, _ = robot
    _, nq, nv, nu, _ = ROBOTS[folder]
    assert (m.nq, m.nv, m.nu) == (nq, nv, nu)
    assert (pm.nq, pm.nv) == (nq, nv)
    assert m.jnt_type[0] == mujoco.mjtJoint.mjJNT_FREE and m.nu == m.njnt - 1  # one motor on every hinge


def test_each_actuator_drives_the_joint_of_its_name(robot):
    _, m, _, _ = robot
    for a in range(m.nu):
        joint = mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_JOINT, int(m.actuator_trnid[a, 0]))
        assert mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_ACTUATOR, a) == joint


def test_total_mass_is_the_measured_one_in_both_libraries(robot):
    folder, m, pm, _ = robot
    mass_kg = ROBOTS[folder][4]
    assert abs(float(m.body_mass.sum()) - mass_kg) < 1e-9
    assert abs(pin.computeTotalMass(pm) - mass_kg) < 1e-9


@pytest.mark.parametrize("seed", SEEDS)
def test_bodies_sites_and_com_agree_at_a_random_configuration(robot, seed):
    _, m, pm, smap = robot
    qpos = random_qpos(m, seed)
    d = mujoco.MjData(m)
    d.qpos[:] = qpos
    mujoco.mj_forward(m, d)
    q = qpos_to_q(smap, qpos)
    pd = pm.createData()
    pin.framesForwardKinematics(pm, pd, q)
    for b in range(1, m.nbody):
        frame = pd.oMf[pm.getFrameId(mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_BODY, b), pin.BODY)]
        assert np.linalg.norm(frame.translation - d.xpos[b]) < 1e-9
        assert np.abs(frame.rotation - d.xmat[b].reshape(3, 3)).max() < 1e-9
    assert m.nsite > 0
    for s in range(m.nsite):
        frame = pd.oMf[pm.getFrameId(mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_SITE, s), pin.OP_FRAME)]
        assert np.linalg.norm(frame.translation - d.site_xpos[s]) < 1e-9
    assert np.linalg.norm(pin.centerOfMass(pm, pd, q) - d.subtree_com[0]) < 1e-9


@pytest.mark.parametrize("seed", SEEDS)
def test_mass_matrices_agree_with_the_armature(robot, seed):
    _, m, pm, smap = robot
    qpos = random_qpos(m, seed)
    d = mujoco.MjData(m)
    d.qpos[:] = qpos
    mujoco.mj_forward(m, d)
    M_mj = np.zeros((m.nv, m.nv))
    mujoco.mj_fullM(m, d, M_mj)
    q = qpos_to_q(smap, qpos)
    M_pin = pin.crba(pm, pm.createData(), q)
    M_pin = np.triu(M_pin) + np.triu(M_pin, 1).T
    T = velocity_map(smap, q)
    assert np.abs(T.T @ M_mj @ T - M_pin).max() < 1e-9
    assert np.array_equal(pm.armature, m.dof_armature) and m.dof_armature[6:].min() > 0


def _foot_geoms(m, body_name: str, geom_type) -> list[int]:
    body = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, body_name)
    return [int(g) for g in np.flatnonzero(m.geom_bodyid == body) if m.geom_type[g] == geom_type]


@pytest.mark.parametrize("side", ["left", "right"])
def test_h1_foot_is_three_capsules_of_radius_14_mm(side):
    """The capsules' end points in the ankle frame (m): heel, arch, toe bar; the sole is 0.014 m below them."""
    m = mujoco.MjModel.from_xml_path(str(MODELS_DIR / "unitree_h1" / "h1.xml"))
    ends = set()
    for g in _foot_geoms(m, f"{side}_ankle_link", mujoco.mjtGeom.mjGEOM_CAPSULE):
        assert m.geom_size[g, 0] == pytest.approx(0.014, abs=1e-12)
        rot = np.zeros(9)
        mujoco.mju_quat2Mat(rot, m.geom_quat[g])
        half = rot.reshape(3, 3)[:, 2] * m.geom_size[g, 1]
        ends |= {tuple(float(round(x, 9)) + 0.0 for x in m.geom_pos[g] + sign * half) for sign in (-1, 1)}
    assert sorted(ends) == [(-0.035, 0.0, -0.056), (0.02, 0.0, -0.045), (0.115, 0.0, -0.056),
                            (0.14, -0.03, -0.056), (0.14, 0.03, -0.056)]  # fmt: skip


@pytest.mark.parametrize("side", ["left", "right"])
def test_g1_foot_is_four_spheres_of_radius_5_mm(side):
    """The sphere centres in the ankle-roll frame (m); the sole is 0.005 m below them."""
    m = mujoco.MjModel.from_xml_path(str(MODELS_DIR / "unitree_g1" / "g1.xml"))
    spheres = _foot_geoms(m, f"{side}_ankle_roll_link", mujoco.mjtGeom.mjGEOM_SPHERE)
    assert [m.geom_size[g, 0] for g in spheres] == pytest.approx([0.005] * 4, abs=1e-12)
    centres = sorted(tuple(float(x) for x in m.geom_pos[g]) for g in spheres)
    expected = [(-0.05, -0.025, -0.03), (-0.05, 0.025, -0.03), (0.12, -0.03, -0.03), (0.12, 0.03, -0.03)]
    assert np.allclose(centres, expected, rtol=0, atol=1e-12)


def test_licence_and_credits_are_shipped(robot):
    folder = robot[0]
    licence = (MODELS_DIR / folder / "LICENSE").read_text()
    assert "Unitree Robotics" in licence
    for clause in (
        "Redistributions of source code must retain the above copyright notice",
        "Redistributions in binary form must reproduce the above copyright notice",
        "Neither the name of the copyright holder nor the names of its",
    ):
        assert clause in licence  # the three clauses of the BSD 3-Clause licence
    credits = (MODELS_DIR / folder / "README.md").read_text()
    assert "BSD-3-Clause" in credits and "Unitree Robotics" in credits and "MuJoCo Menagerie" in credits


def test_the_folders_fit_in_a_wheel():
    sizes = [f.stat().st_size for folder in ROBOTS for f in (MODELS_DIR / folder).rglob("*") if f.is_file()]
    assert 0 < sum(sizes) < MAX_BYTES
