"""amlip_qp/models/cassie.xml: the 20-DOF Cassie MJCF shared by MuJoCo and Pinocchio.

Reference numbers (``SHEET_*``, :mod:`cassie_sheet`) are Agility Robotics' Cassie parameters as
given in the project's parameter sheet; ``test_constants_match_sheet`` cross-checks them against
the sheet (``models/reference/cassie_parameters.json``).
"""

from __future__ import annotations

import json

import mujoco
import numpy as np
import pinocchio as pin
import pytest

from cassie_sheet import (
    CONTACT_RADIUS,
    COUPLING_REST,
    JOINTS,
    LEG,
    MODEL,
    MOTORS,
    SHEET_BELOW_KNEE,
    SHEET_GEAR,
    SHEET_LEG_MASSES,
    SHEET_MOTOR_LIMIT,
    SHEET_PATH,
    SHEET_PELVIS_MASS,
    SHEET_STANDING_COM,
    SHEET_STANDING_INERTIA,
    SHEET_STANDING_QPOS,
    SHEET_TOTAL_MASS,
    SIDES,
    SITES,
    mj_composite,
    mj_to_pin,
    pin_composite,
    sheet_qpos21,
    sheet_range,
)


@pytest.fixture(scope="module")
def mj():
    m = mujoco.MjModel.from_xml_path(str(MODEL))
    return m, mujoco.MjData(m)


@pytest.fixture(scope="module")
def pn():
    model = pin.buildModelFromMJCF(str(MODEL))
    return model, model.createData()


# ------------------------------------------------------------------ structure
def test_loads_with_expected_dimensions(mj, pn):
    m, _ = mj
    model, _ = pn
    assert (m.nq, m.nv, m.nu) == (21, 20, 10)
    assert (model.nq, model.nv) == (21, 20)
    # Pinocchio: universe + free flyer + 14 hinges; the floor plane adds nothing.
    assert model.njoints == 16
    assert m.ntendon == 2 and m.neq == 0


def test_joint_names_and_order(mj, pn):
    m, _ = mj
    model, _ = pn
    mj_names = [m.joint(i).name for i in range(m.njnt)]
    assert mj_names == ["floating-base"] + JOINTS
    assert list(model.names) == ["universe", "floating-base"] + JOINTS
    # Same qpos/qvel layout in both.
    for name in JOINTS:
        jid = model.getJointId(name)
        assert model.joints[jid].idx_q == m.jnt_qposadr[m.joint(name).id]
        assert model.joints[jid].idx_v == m.jnt_dofadr[m.joint(name).id]


def test_sites_exist_in_both(mj, pn):
    m, _ = mj
    model, _ = pn
    for s in SITES:
        assert mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_SITE, s) >= 0
        assert model.existFrame(s)
        assert model.frames[model.getFrameId(s)].type == pin.FrameType.OP_FRAME
    # The contact site is the foot joint origin; toe and heel are the contact sphere centres.
    for side in SIDES:
        assert np.allclose(m.site(f"{side}-contact").pos, 0.0)
        foot = m.body(f"{side}-foot").id
        for tag in ("toe", "heel"):
            g = m.geom(f"{side}-{tag}-contact")
            assert g.bodyid[0] == foot and g.type[0] == mujoco.mjtGeom.mjGEOM_SPHERE
            assert g.size[0] == pytest.approx(CONTACT_RADIUS)
            assert np.allclose(g.pos, m.site(f"{side}-{tag}").pos)


def test_camera_light_and_floor(mj):
    m, _ = mj
    cam = m.camera("track")
    assert cam.mode[0] == mujoco.mjtCamLight.mjCAMLIGHT_TRACKCOM
    assert cam.bodyid[0] == m.body("cassie-pelvis").id
    assert m.vis.headlight.active
    assert m.geom("floor").type[0] == mujoco.mjtGeom.mjGEOM_PLANE
    assert m.opt.timestep == 0.0005
    assert m.opt.integrator == mujoco.mjtIntegrator.mjINT_IMPLICITFAST


def test_only_feet_and_pelvis_collide_with_floor(mj):
    m, _ = mj
    floor = m.geom("floor").id
    colliders = set()
    for a in range(m.ngeom):
        for b in range(a + 1, m.ngeom):
            if (m.geom_contype[a] & m.geom_conaffinity[b]) or (m.geom_contype[b] & m.geom_conaffinity[a]):
                assert floor in (a, b), (m.geom(a).name, m.geom(b).name)
                colliders.add(m.geom(b if a == floor else a).name)
    assert colliders == {"pelvis-collision"} | {f"{s}-{t}-contact" for s in SIDES for t in ("toe", "heel")}


# ------------------------------------------------------------------ masses
def test_total_mass_both(mj, pn):
    m, _ = mj
    model, _ = pn
    assert m.body_subtreemass[0] == pytest.approx(SHEET_TOTAL_MASS, abs=1e-6)
    assert sum(Y.mass for Y in model.inertias) == pytest.approx(SHEET_TOTAL_MASS, abs=1e-6)
    assert m.body("cassie-pelvis").mass[0] == pytest.approx(SHEET_PELVIS_MASS, abs=1e-12)


def test_leg_mass_distribution(mj):
    m, _ = mj
    leg_total = sum(SHEET_LEG_MASSES.values())
    below = sum(SHEET_LEG_MASSES[b] for b in SHEET_BELOW_KNEE)
    for side in SIDES:
        assert m.body_subtreemass[m.body(f"{side}-hip-roll").id] == pytest.approx(leg_total, abs=1e-9)
        assert m.body_subtreemass[m.body(f"{side}-knee").id] == pytest.approx(below, abs=1e-9)
        # Lumped hosts: achilles rod -> hip-pitch; knee spring -> knee;
        # heel spring, foot crank, plantar rod -> tarsus.
        s = SHEET_LEG_MASSES
        expect = {
            "hip-roll": s["hip-roll"],
            "hip-yaw": s["hip-yaw"],
            "hip-pitch": s["hip-pitch"] + s["achilles-rod"],
            "knee": s["knee"] + s["knee-spring"],
            "shin": s["shin"],
            "tarsus": s["tarsus"] + s["heel-spring"] + s["foot-crank"] + s["plantar-rod"],
            "foot": s["foot"],
        }
        for body, mass in expect.items():
            assert m.body(f"{side}-{body}").mass[0] == pytest.approx(mass, abs=1e-12)


def test_lumping_preserves_whole_body_inertia_at_sheet_standing(mj, pn):
    """At the sheet's standing pose the lumped model has the full model's CoM and inertia."""
    m, d = mj
    model, data = pn
    qpos = sheet_qpos21()
    d.qpos[:] = qpos
    mujoco.mj_kinematics(m, d)
    M, c, I = mj_composite(m, d)
    assert M == pytest.approx(SHEET_TOTAL_MASS, abs=1e-9)
    np.testing.assert_allclose(c, SHEET_STANDING_COM, atol=1e-9)
    np.testing.assert_allclose(I, SHEET_STANDING_INERTIA, atol=1e-9)
    pin.forwardKinematics(model, data, mj_to_pin(qpos))
    Mp, cp, Ip = pin_composite(model, data)
    assert Mp == pytest.approx(SHEET_TOTAL_MASS, abs=1e-9)
    np.testing.assert_allclose(cp, SHEET_STANDING_COM, atol=1e-9)
    np.testing.assert_allclose(Ip, SHEET_STANDING_INERTIA, atol=1e-9)


# ------------------------------------------------------------------ joints, actuators
def test_joint_ranges_springs_armature(mj, pn):
    m, _ = mj
    model, _ = pn
    for name in JOINTS:
        j = m.joint(name)
        lo, hi = sheet_range(name)
        assert j.limited[0] and tuple(j.range) == pytest.approx((lo, hi), abs=1e-12)
        idx = model.joints[model.getJointId(name)].idx_q
        assert model.lowerPositionLimit[idx] == pytest.approx(lo, abs=1e-12)
        assert model.upperPositionLimit[idx] == pytest.approx(hi, abs=1e-12)
        dof = m.jnt_dofadr[j.id]
        assert model.armature[dof] == pytest.approx(m.dof_armature[dof], abs=1e-15)
    for side in SIDES:
        shin = m.joint(f"{side}-shin").id
        assert m.jnt_stiffness[shin] == 1500.0 and m.qpos_spring[m.jnt_qposadr[shin]] == 0.0
        t = m.tendon(f"{side}-achilles").id
        assert m.tendon_stiffness[t] == 1250.0
        assert tuple(m.tendon_lengthspring[t]) == pytest.approx((COUPLING_REST, COUPLING_REST), abs=1e-12)
        adr, num = m.tendon_adr[t], m.tendon_num[t]
        wraps = {m.joint(m.wrap_objid[k]).name: m.wrap_prm[k] for k in range(adr, adr + num)}
        assert wraps == {f"{side}-knee": 1.0, f"{side}-tarsus": 1.0}
        assert m.dof_armature[m.jnt_dofadr[m.joint(f"{side}-knee").id]] == pytest.approx(0.09344)
        assert m.dof_armature[m.jnt_dofadr[m.joint(f"{side}-hip-roll").id]] == pytest.approx(0.038125)
        assert m.dof_armature[m.jnt_dofadr[m.joint(f"{side}-foot").id]] == pytest.approx(0.01225)


def test_coupling_torque_formula(mj):
    """qfrc_passive on knee and tarsus is -k (q_k + q_t - 0.226893) (plus joint damping)."""
    m, d = mj
    mujoco.mj_resetDataKeyframe(m, d, m.key("stand").id)
    d.qpos[m.jnt_qposadr[m.joint("left-tarsus").id]] += 0.02
    d.qvel[:] = 0
    mujoco.mj_forward(m, d)
    qk = d.qpos[m.jnt_qposadr[m.joint("left-knee").id]]
    qt = d.qpos[m.jnt_qposadr[m.joint("left-tarsus").id]]
    expect = -1250.0 * (qk + qt - COUPLING_REST)
    for name in ("left-knee", "left-tarsus"):
        assert d.qfrc_passive[m.jnt_dofadr[m.joint(name).id]] == pytest.approx(expect, abs=1e-9)


def test_actuators_match_sheet(mj, pn):
    m, _ = mj
    model, _ = pn
    assert [m.actuator(i).name for i in range(m.nu)] == MOTORS
    for i, name in enumerate(MOTORS):
        short = name.split("-", 1)[1]
        assert m.joint(m.actuator_trnid[i, 0]).name == name
        assert m.actuator_gear[i, 0] == SHEET_GEAR[short]
        assert m.actuator_ctrllimited[i]
        lim = SHEET_MOTOR_LIMIT[short]
        assert tuple(m.actuator_ctrlrange[i]) == (-lim, lim)
        joint_lim = SHEET_GEAR[short] * lim
        assert tuple(m.jnt_actfrcrange[m.joint(name).id]) == pytest.approx((-joint_lim, joint_lim))
        v = model.joints[model.getJointId(name)].idx_v
        assert model.effortLimit[v] == pytest.approx(joint_lim)


# ------------------------------------------------------------------ keyframe
def test_stand_keyframe(mj):
    m, d = mj
    key = m.key("stand")
    mujoco.mj_resetDataKeyframe(m, d, key.id)
    mujoco.mj_kinematics(m, d)
    heights = [d.site(f"{s}-{t}").xpos[2] for s in SIDES for t in ("toe", "heel")]
    np.testing.assert_allclose(heights, CONTACT_RADIUS, atol=1e-3)
    np.testing.assert_allclose(heights, CONTACT_RADIUS, atol=1e-9)  # computed, so exact
    for side in SIDES:
        toe, heel = d.site(f"{side}-toe").xpos, d.site(f"{side}-heel").xpos
        assert toe[0] > heel[0]  # toe points forward
        qk = d.qpos[m.jnt_qposadr[m.joint(f"{side}-knee").id]]
        qt = d.qpos[m.jnt_qposadr[m.joint(f"{side}-tarsus").id]]
        assert qk + qt == pytest.approx(0.2269, abs=2e-4)
    for name in JOINTS:
        j = m.joint(name)
        q = d.qpos[m.jnt_qposadr[j.id]]
        assert j.range[0] <= q <= j.range[1]
    # Joint angles are the sheet's (the foot is re-levelled by < 1e-3 rad).
    ref = sheet_qpos21()
    np.testing.assert_allclose(key.qpos[3:], ref[3:], atol=1e-3)
    assert key.qpos[2] == pytest.approx(1.00627, abs=1e-5)


# ------------------------------------------------------------------ MuJoCo vs Pinocchio
def test_frames_agree_mujoco_pinocchio(mj, pn):
    m, d = mj
    model, data = pn
    rng = np.random.default_rng(7)
    for _ in range(5):
        qpos = np.zeros(m.nq)
        qpos[:3] = rng.uniform(-1, 1, 3)
        quat = rng.normal(size=4)
        qpos[3:7] = quat / np.linalg.norm(quat)
        for name in JOINTS:
            j = m.joint(name)
            qpos[m.jnt_qposadr[j.id]] = rng.uniform(*j.range)
        d.qpos[:] = qpos
        mujoco.mj_kinematics(m, d)
        q = mj_to_pin(qpos)
        pin.framesForwardKinematics(model, data, q)
        for s in SITES:
            oMf = data.oMf[model.getFrameId(s)]
            np.testing.assert_allclose(oMf.translation, d.site(s).xpos, atol=1e-9)
            np.testing.assert_allclose(oMf.rotation, d.site(s).xmat.reshape(3, 3), atol=1e-9)
        for name in ["cassie-pelvis"] + JOINTS:
            b = m.body(name).id
            jid = model.getJointId("floating-base" if name == "cassie-pelvis" else name)
            np.testing.assert_allclose(data.oMi[jid].translation, d.xpos[b], atol=1e-9)
            np.testing.assert_allclose(data.oMi[jid].rotation, d.xmat[b].reshape(3, 3), atol=1e-9)
            Y = model.inertias[jid]
            assert Y.mass == pytest.approx(m.body_mass[b], abs=1e-12)
            np.testing.assert_allclose(data.oMi[jid].act(Y.lever), d.xipos[b], atol=1e-9)
            R = d.ximat[b].reshape(3, 3)
            Rp = data.oMi[jid].rotation
            np.testing.assert_allclose(Rp @ Y.inertia @ Rp.T, R @ np.diag(m.body_inertia[b]) @ R.T, atol=1e-9)


def test_mass_matrix_agrees(mj, pn):
    """Joint-space mass matrices agree (including armature) at the keyframe."""
    m, d = mj
    model, data = pn
    mujoco.mj_resetDataKeyframe(m, d, m.key("stand").id)
    mujoco.mj_forward(m, d)
    Mmj = np.zeros((m.nv, m.nv))
    mujoco.mj_fullM(m, d, Mmj)
    Mp = pin.crba(model, data, mj_to_pin(d.qpos))
    Mp = np.triu(Mp) + np.triu(Mp, 1).T
    # Leg block: joint coordinates are identical in both (base velocity conventions differ).
    np.testing.assert_allclose(Mp[6:, 6:], Mmj[6:, 6:], atol=1e-9)


# ------------------------------------------------------------------ sheet cross-check
def test_constants_match_sheet():
    sheet = json.loads(SHEET_PATH.read_text())
    bodies = {b["name"]: b for b in sheet["bodies"]}
    assert sheet["total_mass"] == SHEET_TOTAL_MASS
    assert sum(b["mass"] for b in sheet["bodies"]) == pytest.approx(SHEET_TOTAL_MASS, abs=1e-9)
    assert sheet["standing_qpos"] == SHEET_STANDING_QPOS
    for side in SIDES:
        for short, mass in SHEET_LEG_MASSES.items():
            assert bodies[f"{side}-{short}"]["mass"] == mass
        for short in LEG:
            j = bodies[f"{side}-{short}"]["joints"][0]
            assert tuple(j["range_rad"]) == sheet_range(f"{side}-{short}")
    for a in sheet["actuators"]:
        short = a["name"].split("-", 1)[1]
        assert a["gear"] == SHEET_GEAR[short]
        assert a["motor_torque_limit"] == [-SHEET_MOTOR_LIMIT[short], SHEET_MOTOR_LIMIT[short]]
    knee = bodies["left-knee"]["joints"][0]["ref_rad"][0]
    tarsus = bodies["left-tarsus"]["joints"][0]["ref_rad"][0]
    assert knee + tarsus == pytest.approx(COUPLING_REST, abs=1e-12)
