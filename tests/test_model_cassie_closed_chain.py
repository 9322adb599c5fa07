"""amlip_qp/models/cassie-closed-chain.xml: Cassie with the sheet's full tree and its loop closures.

A MuJoCo plant only (the controller keeps Pinocchio's ``cassie.xml``): the achilles and
plantar rods are bodies closed by ``connect`` equalities, with the knee and heel springs.
Reference numbers are Agility Robotics' Cassie parameters (the parameter sheet
``models/reference/cassie_parameters.json``).
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import mujoco
import numpy as np
import pinocchio as pin
import pytest

from amlip_qp.paths import MODELS_DIR
from amlip_qp.robots import load_robot, qpos_to_q

MODEL = MODELS_DIR / "cassie-closed-chain.xml"
LUMPED = MODELS_DIR / "cassie.xml"
REPO = Path(__file__).resolve().parents[1]
GENERATOR = REPO / "models" / "tools" / "build_cassie_closed_chain.py"
#: The parameter sheet vendored in the repository (models/reference/, credits in NOTICE).
SHEET_PATH = REPO / "models" / "reference" / "cassie_parameters.json"

SIDES = ("left", "right")
SHEET_TOTAL_MASS = 33.312
#: The sheet's loop closures: (equality name, body1, body2).
LOOPS = (
    ("left-plantar-loop", "left-plantar-rod", "left-foot"),
    ("left-achilles-loop", "left-achilles-rod", "left-heel-spring"),
    ("right-plantar-loop", "right-plantar-rod", "right-foot"),
    ("right-achilles-loop", "right-achilles-rod", "right-heel-spring"),
)
#: Joints of the sheet's tree that cassie.xml does not have (per side).
EXTRA_JOINTS = ("achilles-rod", "heel-spring", "foot-crank", "plantar-rod")
HEEL_SPRING_STIFFNESS = 1250.0
SHIN_STIFFNESS = 1500.0
#: knee + tarsus with both springs at rest: 13 deg, the sum of the sheet's knee and tarsus refs.
COUPLING_REST = 0.226893
CONTACT_RADIUS = 0.02


@pytest.fixture(scope="module")
def mj():
    m = mujoco.MjModel.from_xml_path(str(MODEL))
    d = mujoco.MjData(m)
    mujoco.mj_resetDataKeyframe(m, d, m.key("stand").id)
    mujoco.mj_forward(m, d)
    return m, d


@pytest.fixture(scope="module")
def lumped():
    m = mujoco.MjModel.from_xml_path(str(LUMPED))
    d = mujoco.MjData(m)
    mujoco.mj_resetDataKeyframe(m, d, m.key("stand").id)
    mujoco.mj_forward(m, d)
    return m, d


def names(m, objtype, n):
    return [mujoco.mj_id2name(m, objtype, i) for i in range(n)]


def loop_residuals_m(m, d):
    """World distance between the two anchor sites of every loop closure (m)."""
    return np.array([np.linalg.norm(d.site_xpos[m.eq_obj1id[e]] - d.site_xpos[m.eq_obj2id[e]]) for e in range(m.neq)])


def qadr(m, joint):
    return int(m.jnt_qposadr[m.joint(joint).id])


def knee_plus_tarsus(m, d, side):
    return d.qpos[qadr(m, f"{side}-knee")] + d.qpos[qadr(m, f"{side}-tarsus")]


# ------------------------------------------------------------------ structure
def test_dimensions_and_loop_closures(mj):
    m, _ = mj
    # free base 7 + per leg: 3 hips, achilles ball 4, knee, shin, tarsus, heel, crank, plantar, foot.
    assert (m.nq, m.nv, m.nu, m.neq) == (35, 32, 10, 4)
    assert m.ntendon == 0
    assert names(m, mujoco.mjtObj.mjOBJ_EQUALITY, m.neq) == [n for n, _, _ in LOOPS]
    for e, (_, body1, body2) in enumerate(LOOPS):
        assert m.eq_type[e] == mujoco.mjtEq.mjEQ_CONNECT
        assert m.eq_objtype[e] == mujoco.mjtObj.mjOBJ_SITE
        assert m.body(m.site_bodyid[m.eq_obj1id[e]]).name == body1
        assert m.body(m.site_bodyid[m.eq_obj2id[e]]).name == body2
        # The sheet's anchor: the rod's far end, on its x axis.
        rod_end = {"plantar-rod": 0.35012, "achilles-rod": 0.5012}[body1.split("-", 1)[1]]
        np.testing.assert_allclose(m.site_pos[m.eq_obj1id[e]], [rod_end, 0, 0], atol=1e-12)


def test_shares_names_and_qpos_meaning_with_cassie_xml(mj, lumped):
    m, d = mj
    mc, dc = lumped
    shared = names(mc, mujoco.mjtObj.mjOBJ_JOINT, mc.njnt)
    own = names(m, mujoco.mjtObj.mjOBJ_JOINT, m.njnt)
    assert set(shared) <= set(own)
    assert sorted(set(own) - set(shared)) == sorted(f"{s}-{j}" for s in SIDES for j in EXTRA_JOINTS)
    assert set(names(mc, mujoco.mjtObj.mjOBJ_BODY, mc.nbody)) <= set(names(m, mujoco.mjtObj.mjOBJ_BODY, m.nbody))
    assert set(names(mc, mujoco.mjtObj.mjOBJ_SITE, mc.nsite)) <= set(names(m, mujoco.mjtObj.mjOBJ_SITE, m.nsite))
    for j in shared:
        a, b = m.joint(j), mc.joint(j)
        assert a.type == b.type
        np.testing.assert_array_equal(a.range, b.range)
        if a.type == mujoco.mjtJoint.mjJNT_HINGE:
            # Same zero: no `ref` (the knee and tarsus refs are baked into the body frames in both).
            assert m.qpos0[qadr(m, j)] == mc.qpos0[qadr(mc, j)] == 0.0
    # The stand keyframes agree on every shared joint (base included).
    for j in shared:
        w = 7 if m.joint(j).type == mujoco.mjtJoint.mjJNT_FREE else 1
        np.testing.assert_allclose(
            d.qpos[qadr(m, j) : qadr(m, j) + w], dc.qpos[qadr(mc, j) : qadr(mc, j) + w], atol=1e-12, err_msg=j
        )


def test_actuators_identical_to_cassie_xml(mj, lumped):
    m, _ = mj
    mc, _ = lumped
    assert names(m, mujoco.mjtObj.mjOBJ_ACTUATOR, m.nu) == names(mc, mujoco.mjtObj.mjOBJ_ACTUATOR, mc.nu)
    for i in range(m.nu):
        a, b = m.actuator(i), mc.actuator(i)
        assert m.joint(a.trnid[0]).name == mc.joint(b.trnid[0]).name == a.name  # the foot motor drives `*-foot`
        np.testing.assert_array_equal(a.gear, b.gear)
        np.testing.assert_array_equal(a.ctrlrange, b.ctrlrange)
        np.testing.assert_array_equal(m.jnt_actfrcrange[a.trnid[0]], mc.jnt_actfrcrange[b.trnid[0]])
    frc = {m.actuator(i).name: m.jnt_actfrcrange[m.actuator(i).trnid[0], 1] for i in range(m.nu)}
    assert frc["left-foot"] == 45.0 and frc["right-knee"] == pytest.approx(195.2)


def test_springs_dampers_and_no_tendon_coupling(mj):
    m, _ = mj
    for s in SIDES:
        assert m.jnt_stiffness[m.joint(f"{s}-shin").id] == SHIN_STIFFNESS
        assert m.jnt_stiffness[m.joint(f"{s}-heel-spring").id] == HEEL_SPRING_STIFFNESS
        assert m.qpos_spring[qadr(m, f"{s}-heel-spring")] == 0.0
        assert m.jnt_type[m.joint(f"{s}-achilles-rod").id] == mujoco.mjtJoint.mjJNT_BALL
        assert m.dof_damping[m.jnt_dofadr[m.joint(f"{s}-achilles-rod").id]] == 0.01
        crank = m.joint(f"{s}-foot-crank")
        assert m.dof_damping[crank.dofadr[0]] == 1.0
        np.testing.assert_allclose(crank.range, [-2.443461, -0.523599])
        assert "knee-spring" not in " ".join(names(m, mujoco.mjtObj.mjOBJ_JOINT, m.njnt))  # welded
    assert m.ntendon == 0


def test_options_and_contact_softness_as_cassie_xml(mj, lumped):
    m, _ = mj
    mc, _ = lumped
    assert m.opt.timestep == mc.opt.timestep == 0.0005
    assert m.opt.integrator == mc.opt.integrator == mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    np.testing.assert_array_equal(m.opt.gravity, mc.opt.gravity)
    floor, floor_c = m.geom("floor"), mc.geom("floor")
    for attr in ("friction", "solref", "solimp", "condim"):
        np.testing.assert_array_equal(getattr(floor, attr), getattr(floor_c, attr))
        for s in SIDES:
            np.testing.assert_array_equal(
                getattr(m.geom(f"{s}-foot-collision0"), attr), getattr(mc.geom(f"{s}-toe-contact"), attr)
            )


def test_collision_geometry_is_the_sheets_and_touches_only_the_floor(mj):
    m, _ = mj
    sheet = json.loads(SHEET_PATH.read_text())
    colliding = {m.geom(g).name for g in range(m.ngeom) if m.geom_contype[g] or m.geom_conaffinity[g]}
    expected = {"floor", "pelvis-collision"}
    for b in sheet["bodies"]:
        if b["name"] == "cassie-pelvis":
            continue
        for k, g in enumerate(b["collision_capsules_etc"]):
            name = f"{b['name']}-collision{k}"
            expected.add(name)
            geom = m.geom(name)
            assert geom.type == mujoco.mjtGeom.mjGEOM_CAPSULE and g["type"] == "capsule"
            np.testing.assert_allclose(geom.size[:2], g["size"][:2], atol=1e-12)
    assert colliding == expected
    for g in range(m.ngeom):
        for h in range(g + 1, m.ngeom):
            pair = (m.geom_contype[g] & m.geom_conaffinity[h]) or (m.geom_contype[h] & m.geom_conaffinity[g])
            if pair:  # every possible contact involves the floor
                assert "floor" in (m.geom(g).name, m.geom(h).name)


# ------------------------------------------------------------------ numbers
def test_total_mass_equals_sheet(mj):
    m, _ = mj
    sheet = json.loads(SHEET_PATH.read_text())
    assert sheet["total_mass"] == SHEET_TOTAL_MASS
    assert m.body_mass.sum() == pytest.approx(SHEET_TOTAL_MASS, abs=1e-9)
    for b in sheet["bodies"]:
        assert m.body(b["name"]).mass[0] == pytest.approx(b["mass"], abs=1e-12), b["name"]
    assert m.nbody - 1 == len(sheet["bodies"]) == 25  # pelvis + 12 per leg


def test_stand_keyframe_closes_the_loops_and_rests_on_the_floor(mj):
    m, d = mj
    # Projected onto the closures by the generator: measured 2.6e-13 m.
    assert loop_residuals_m(m, d).max() < 1e-9
    sheet = json.loads(SHEET_PATH.read_text())
    # The sheet's own standing qpos leaves the plantar loops 1.95 mm open (measured); the keyframe
    # moves only the passive loop joints for that, plus the levelled feet and the base height.
    d2 = mujoco.MjData(m)
    d2.qpos[:] = sheet["standing_qpos"]
    mujoco.mj_kinematics(m, d2)
    assert 1.9e-3 < loop_residuals_m(m, d2).max() < 2.0e-3
    heights = [d.site(f"{s}-{t}").xpos[2] for s in SIDES for t in ("toe", "heel")]
    np.testing.assert_allclose(heights, CONTACT_RADIUS, atol=1e-9)
    for s in SIDES:
        assert knee_plus_tarsus(m, d, s) == pytest.approx(0.22701, abs=1e-5)
        # The achilles loop at the sheet's knee and tarsus angles: heel spring slightly preloaded.
        assert d.qpos[qadr(m, f"{s}-heel-spring")] == pytest.approx(-6.89e-3, abs=5e-5)
    assert np.all(d.qpos[m.jnt_qposadr[1:]][m.jnt_limited[1:]] >= m.jnt_range[1:, 0][m.jnt_limited[1:]])
    assert np.all(d.qpos[m.jnt_qposadr[1:]][m.jnt_limited[1:]] <= m.jnt_range[1:, 1][m.jnt_limited[1:]])


def test_contact_sites_match_the_controllers_pinocchio_model(mj):
    """Given the same base pose and shared joint values, the foot sites coincide with cassie.xml's Pinocchio."""
    m, d = mj
    robot = load_robot("cassie")
    model, data = robot.pin_model, robot.pin_model.createData()
    rng = np.random.default_rng(0)
    configs = [d.qpos.copy()]
    for _ in range(3):  # random shared joints in range, random base pose (loops need not close here)
        q = d.qpos.copy()
        for j in robot.joint_names:
            lo, hi = m.joint(j).range
            q[qadr(m, j)] = rng.uniform(lo, hi)
        q[:3] += rng.normal(0, 0.3, 3)
        quat = rng.normal(size=4)
        q[3:7] = quat / np.linalg.norm(quat)
        configs.append(q)
    sites = [f"{s}-{t}" for s in SIDES for t in ("contact", "toe", "heel")]
    worst = 0.0
    for qpos in configs:
        d2 = mujoco.MjData(m)
        d2.qpos[:] = qpos
        mujoco.mj_kinematics(m, d2)
        qpos21 = np.zeros(robot.mj_model.nq)
        for j in range(robot.mj_model.njnt):
            jm = robot.mj_model.joint(j)
            w = 7 if jm.type == mujoco.mjtJoint.mjJNT_FREE else 1
            qpos21[jm.qposadr[0] : jm.qposadr[0] + w] = qpos[qadr(m, jm.name) : qadr(m, jm.name) + w]
        pin.framesForwardKinematics(model, data, qpos_to_q(robot, qpos21))
        for s in sites:
            diff = data.oMf[model.getFrameId(s)].translation - d2.site(s).xpos
            worst = max(worst, float(np.abs(diff).max()))
    assert worst < 1e-9  # measured 0 to 1e-15 m


# ------------------------------------------------------------------ physics
def test_fixed_base_zero_torque_the_rods_hold_the_tarsus():
    """Pelvis fixed 2 m up, zero torque for 1 s: the legs swing, the rods keep knee + tarsus near 13 deg."""
    spec = mujoco.MjSpec.from_file(str(MODEL))
    key = spec.key("stand")
    qpos = np.array(key.qpos)
    spec.delete(spec.joint("floating-base"))
    spec.delete(key)
    spec.body("cassie-pelvis").pos = [0.0, 0.0, 2.0]
    m = spec.compile()
    d = mujoco.MjData(m)
    d.qpos[:] = qpos[7:]
    mujoco.mj_forward(m, d)
    knee0 = d.qpos[qadr(m, "left-knee")]
    res, kt = [], []
    for _ in range(int(round(1.0 / m.opt.timestep))):
        mujoco.mj_step(m, d)
        res.append(loop_residuals_m(m, d).max())
        kt.append([knee_plus_tarsus(m, d, s) for s in SIDES])
    kt = np.array(kt)
    assert np.all(np.isfinite(d.qpos))
    # The knees swung through their range (-1.20 -> the -0.646 stop): a real motion, not a frozen leg.
    assert d.qpos[qadr(m, "left-knee")] - knee0 > 0.5
    # Measured: residual at most 0.038 mm; knee + tarsus within 12.3..13.1 deg.
    assert max(res) < 1e-4
    assert np.abs(kt - COUPLING_REST).max() < np.radians(1.0)
    # Hanging, both springs are nearly unloaded at the end.
    for s in SIDES:
        assert abs(d.qpos[qadr(m, f"{s}-heel-spring")]) < 2e-3
        assert abs(d.qpos[qadr(m, f"{s}-shin")]) < 5e-3


def test_pd_hold_on_the_floor_stays_finite_with_closed_loops(mj):
    """From ``stand``: a joint PD (Kp 400, Kd 20) on the motors for 2 s; loops stay closed, no blow-up."""
    m, _ = mj
    d = mujoco.MjData(m)
    mujoco.mj_resetDataKeyframe(m, d, m.key("stand").id)
    q0 = d.qpos.copy()
    qa = np.array([m.jnt_qposadr[m.actuator_trnid[i, 0]] for i in range(m.nu)])
    va = np.array([m.jnt_dofadr[m.actuator_trnid[i, 0]] for i in range(m.nu)])
    gear = m.actuator_gear[:, 0]
    res, shin = [], []
    for _ in range(int(round(2.0 / m.opt.timestep))):
        tau = 400.0 * (q0[qa] - d.qpos[qa]) - 20.0 * d.qvel[va]
        d.ctrl[:] = np.clip(tau / gear, m.actuator_ctrlrange[:, 0], m.actuator_ctrlrange[:, 1])
        mujoco.mj_step(m, d)
        res.append(loop_residuals_m(m, d).max())
        shin.append(d.qpos[qadr(m, "left-shin")])
    assert np.all(np.isfinite(d.qpos)) and np.abs(d.qvel).max() < 50.0
    assert max(res) < 1e-3  # measured 0.19 mm
    # The achilles rod loads the knee spring under body weight (cassie.xml's tendon does not):
    # the shin deflects by several hundredths of a radian in the first 0.25 s.
    assert min(shin) < -0.02


def test_regenerates_identically(tmp_path):
    out = tmp_path / "cassie-closed-chain.xml"
    proc = subprocess.run(
        [sys.executable, str(GENERATOR), "--params", str(SHEET_PATH), "--out", str(out)],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert proc.returncode == 0, proc.stderr
    assert out.read_bytes() == MODEL.read_bytes()
