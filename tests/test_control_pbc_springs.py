"""Tests of the simplified spring model (amlip_qp.control.pbc.springs)."""

from __future__ import annotations

import numpy as np
import pytest

from amlip_qp.control.pbc.gains import AchillesLinkage
from amlip_qp.control.pbc.springs import spring_deflections_rad
from amlip_qp.exceptions import InputError
from amlip_qp.robots import load_robot
from amlip_qp.robots.kinematics import RobotKinematics
from robot_states import tuned_config

CASSIE_ACHILLES = tuned_config("cassie", "pbc").spring_model_linkage


def test_spring_model_cassie_standing_numbers():
    """Full weight on one leg stretches the achilles coupling about twice the measured
    double-support stretch at the stand keyframe (0.031 rad, amlip_qp/models/README.md)."""
    robot = load_robot("cassie")
    kin = RobotKinematics(robot)
    kin.update(robot.q_stand, np.zeros(robot.nv))
    shin, achilles = spring_deflections_rad(kin, "left")
    assert achilles == pytest.approx(2 * 0.031, rel=0.1)
    assert abs(shin) < 0.02


def test_spring_model_rabbit_has_no_springs():
    robot = load_robot("rabbit")
    kin = RobotKinematics(robot)
    kin.update(robot.q_stand, np.zeros(robot.nv))
    assert spring_deflections_rad(kin, "left").size == 0


def test_spring_model_half_weight_matches_the_measured_double_support_stretch():
    """Load share: standing on two feet each leg carries half the weight; the model then gives
    the measured 0.031 rad achilles stretch of the stand keyframe (amlip_qp/models/README.md)."""
    robot = load_robot("cassie")
    kin = RobotKinematics(robot)
    kin.update(robot.q_stand, np.zeros(robot.nv))
    half = np.array([0.0, 0.0, 0.5 * kin.mass_kg * 9.81])
    shin, achilles = spring_deflections_rad(kin, "left", half)
    assert achilles == pytest.approx(0.031, rel=0.1)
    # linear in the load
    np.testing.assert_allclose(2 * np.array([shin, achilles]), spring_deflections_rad(kin, "left"), rtol=1e-9)


def _rod_moment_arms(side: str) -> dict[str, float]:
    """d(rod end-to-end distance)/dq (m/rad) of the closed-chain plant's achilles loop at ``stand``,
    by central differences, for the knee, shin, tarsus and heel-spring joints."""
    import mujoco

    from amlip_qp.paths import MODELS_DIR

    m = mujoco.MjModel.from_xml_path(str(MODELS_DIR / "cassie-closed-chain.xml"))
    d = mujoco.MjData(m)
    mujoco.mj_resetDataKeyframe(m, d, mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_KEY, "stand"))
    q0 = d.qpos.copy()
    rod = m.body(f"{side}-achilles-rod").id
    site = m.site(f"{side}-heel-spring-loop").id

    def dist(q):
        d.qpos[:] = q
        mujoco.mj_kinematics(m, d)
        return float(np.linalg.norm(d.site_xpos[site] - d.xpos[rod]))

    arms = {}
    for joint in ("knee", "shin", "tarsus", "heel-spring"):
        adr = m.jnt_qposadr[m.joint(f"{side}-{joint}").id]
        qp, qm = q0.copy(), q0.copy()
        qp[adr] += 1e-6
        qm[adr] -= 1e-6
        arms[joint] = (dist(qp) - dist(qm)) / 2e-6
    return arms


@pytest.mark.parametrize("side", ["left", "right"])
def test_cassie_achilles_ratios_are_the_closed_chain_linkage(side):
    """CASSIE_ACHILLES is the sheet's rod geometry: the rod's moment arms about the shin and the heel
    spring over its arm about the tarsus, measured on cassie-closed-chain.xml at `stand`. The tendon
    of cassie.xml has 0 and 1 (and acts on knee and tarsus alike, as the rod nearly does)."""
    arms = _rod_moment_arms(side)
    assert arms["shin"] / arms["tarsus"] == pytest.approx(CASSIE_ACHILLES.shin_ratio, abs=1e-3)
    assert arms["heel-spring"] / arms["tarsus"] == pytest.approx(CASSIE_ACHILLES.heel_ratio, abs=1e-3)
    assert arms["knee"] / arms["tarsus"] == pytest.approx(1.0, abs=0.01)


def _closed_chain_standing_deflections() -> dict[str, tuple[float, float]]:
    """``side -> (shin, q_knee + q_tarsus - 0.226893)`` (rad) of the closed-chain plant standing on
    both feet for 2 s from `stand` under a stiff joint PD on the motors (1000 N m/rad, 30 N m s/rad)
    plus the static feed-forward of amlip_qp/models/README.md ("Standing check")."""
    import mujoco

    from amlip_qp.paths import MODELS_DIR

    m = mujoco.MjModel.from_xml_path(str(MODELS_DIR / "cassie-closed-chain.xml"))
    d = mujoco.MjData(m)
    mujoco.mj_resetDataKeyframe(m, d, mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_KEY, "stand"))
    mujoco.mj_forward(m, d)
    act_q = [m.jnt_qposadr[m.actuator_trnid[a, 0]] for a in range(m.nu)]
    act_v = [m.jnt_dofadr[m.actuator_trnid[a, 0]] for a in range(m.nu)]
    q_ref = d.qpos[act_q].copy()
    ff = np.array([0.6, -0.09, -5.5, 39.8, -0.38, -0.6, 0.09, -5.5, 39.8, -0.38])
    gear = m.actuator_gear[:, 0]
    for _ in range(4000):
        tau = 1000.0 * (q_ref - d.qpos[act_q]) - 30.0 * d.qvel[act_v] + ff
        d.ctrl[:] = np.clip(tau / gear, m.actuator_ctrlrange[:, 0], m.actuator_ctrlrange[:, 1])
        mujoco.mj_step(m, d)

    def angle(side, joint):
        return float(d.qpos[m.jnt_qposadr[m.joint(f"{side}-{joint}").id]])

    sides = ("left", "right")
    return {side: (angle(side, "shin"), angle(side, "knee") + angle(side, "tarsus") - 0.226893) for side in sides}


def test_linkage_model_predicts_the_closed_chain_plants_standing_deflections():
    """Standing on two feet (half the weight per leg), the closed-chain plant's rods bend the knee
    spring about -0.045 rad and stretch the achilles about 0.085 rad (measured: left -0.0456 / 0.0864,
    right -0.0435 / 0.0825). The linkage model gives -0.038 / 0.073 (within 20 %); the tendon model
    of cassie.xml gives -0.003 / 0.031: it misses the shin and under-predicts the stretch 2.7 times."""
    measured = _closed_chain_standing_deflections()
    robot = load_robot("cassie")
    kin = RobotKinematics(robot)
    kin.update(robot.q_stand, np.zeros(robot.nv))
    half = np.array([0.0, 0.0, 0.5 * kin.mass_kg * 9.81])
    shin, achilles = spring_deflections_rad(kin, "left", half, CASSIE_ACHILLES)
    t_shin, t_achilles = spring_deflections_rad(kin, "left", half)
    for m_shin, m_achilles in measured.values():
        assert m_shin < -0.03 and m_achilles > 0.07
        assert shin == pytest.approx(m_shin, rel=0.2)
        assert achilles == pytest.approx(m_achilles, rel=0.2)
        assert abs(t_shin) < 0.1 * abs(m_shin) and t_achilles < 0.45 * m_achilles
    # full weight on one leg: twice the half-weight deflections (linear in the load)
    np.testing.assert_allclose(
        spring_deflections_rad(kin, "left", None, CASSIE_ACHILLES), 2 * np.array([shin, achilles]), rtol=1e-9
    )


def test_the_tendon_is_the_linkage_without_shin_arm_and_lever():
    """shin_ratio 0, heel_ratio 1, heel stiffness = the tendon's: the model's own springs, exactly."""
    robot = load_robot("cassie")
    kin = RobotKinematics(robot)
    kin.update(robot.q_stand, np.zeros(robot.nv))
    f = np.array([30.0, -20.0, 300.0])
    tendon = AchillesLinkage(shin_ratio=0.0, heel_ratio=1.0, heel_stiffness_Nmprad=1250.0)
    np.testing.assert_allclose(
        spring_deflections_rad(kin, "left", f, tendon), spring_deflections_rad(kin, "left", f), rtol=1e-12, atol=1e-15
    )


def test_a_linkage_needs_a_shin_and_a_coupling():
    robot = load_robot("rabbit")
    kin = RobotKinematics(robot)
    kin.update(robot.q_stand, np.zeros(robot.nv))
    with pytest.raises(InputError, match="one passive joint and one coupling"):
        spring_deflections_rad(kin, "left", None, CASSIE_ACHILLES)
    with pytest.raises(InputError):
        AchillesLinkage(shin_ratio=1.0, heel_ratio=0.0, heel_stiffness_Nmprad=1250.0)
