"""Tests of amlip_qp.robots.kinematics (and passive): the robot's contacts, root body, momentum about a contact,
passive forces, couplings and output cache, against MuJoCo and finite differences (the model's part:
test_robots_model_kinematics.py)."""

from __future__ import annotations

import mujoco
import numpy as np
import pinocchio as pin
import pytest

from amlip_qp.exceptions import InputError
from amlip_qp.robots import (
    RobotKinematics,
    force_mj_to_pin,
    load_robot,
    mj_to_pin,
    velocity_map,
)
from robot_states import ROBOTS, assert_jacobians_match_fd, fd_along, mujoco_at, random_states

TOL_MJ = 1e-8  # Pinocchio vs MuJoCo (both exact rigid-body algorithms; only round-off differs)
TOL_FD = 1e-6  # central differences with h = 1e-6: truncation ~h^2, round-off ~1e-16/h


@pytest.fixture(scope="module", params=ROBOTS)
def robot(request):
    return load_robot(request.param)


# ------------------------------------------------------- Pinocchio vs MuJoCo
def test_passive_forces_match_mujoco(robot):
    kin = RobotKinematics(robot)
    for qpos, qvel, q, v in random_states(robot, 5, seed=13):
        d = mujoco_at(robot, qpos, qvel)
        kin.update(q, v)
        np.testing.assert_allclose(kin.passive_forces(), force_mj_to_pin(robot, q, d.qfrc_passive), atol=TOL_MJ)


def test_passive_forces_with_springs_dampers_and_tendon(tmp_path):
    """A Rabbit variant with joint springs, dampers, armature and a dead-band tendon spring."""
    base = load_robot("rabbit")
    spec = mujoco.MjSpec.from_file(str(base.path))
    for name, k, ref, b in (("left-knee", 80.0, 0.3, 1.5), ("right-hip", 20.0, -0.2, 0.7), ("root-x", 0.0, 0.0, 2.0)):
        j = spec.joint(name)
        j.stiffness, j.springref, j.damping, j.armature = [k, 0, 0], ref, [b, 0, 0], 0.05  # [linear, poly...]
    t = spec.add_tendon(name="coupler", stiffness=[300.0, 0, 0], damping=[3.0, 0, 0], springlength=[0.1, 0.4])
    t.wrap_joint("left-hip", 1.0)
    t.wrap_joint("right-knee", -0.5)
    path = tmp_path / "rabbit_springs.xml"
    path.write_text(spec.to_xml())
    robot = load_robot(path)
    assert len(robot.couplings) == 1 and robot.couplings[0].springlength == (0.1, 0.4)
    kin = RobotKinematics(robot)
    m = robot.mj_model
    lengths = []
    for qpos, qvel, q, v in random_states(robot, 20, seed=14):
        d = mujoco_at(robot, qpos, qvel)
        kin.update(q, v)
        np.testing.assert_allclose(kin.passive_forces(), d.qfrc_passive, atol=TOL_MJ)
        M_mj = np.zeros((m.nv, m.nv))
        mujoco.mj_fullM(m, d, M_mj)
        np.testing.assert_allclose(kin.mass_matrix(), M_mj, atol=TOL_MJ)  # armature included
        lengths.append(d.ten_length[0])
    assert min(lengths) < 0.1 and max(lengths) > 0.4  # both sides of the dead band were exercised


def test_contact_points_match_mujoco_sites(robot):
    kin = RobotKinematics(robot)
    m = robot.mj_model
    for qpos, qvel, q, v in random_states(robot, 5, seed=15):
        d = mujoco_at(robot, qpos, qvel)
        kin.update(q, v)
        T = velocity_map(robot, q)
        for side in robot.foot_sides:
            sid = robot.contact_site_ids[side]
            jacp = np.zeros((3, m.nv))
            mujoco.mj_jacSite(m, d, jacp, None, sid)
            np.testing.assert_allclose(kin.contact_position(side), d.site_xpos[sid], atol=TOL_MJ)
            np.testing.assert_allclose(kin.contact_jacobian(side), jacp @ T, atol=TOL_MJ)


# ------------------------------------------------- angular momentum about a point
def body_sum_L_pinocchio(robot, q, v, r):
    """sum over bodies of (m_i (x_i - r) x v_i + R_i I_i w_i), from Pinocchio's per-joint data."""
    pm = robot.pin_model
    pd = pm.createData()
    pin.forwardKinematics(pm, pd, q, v)
    L = np.zeros(3)
    for i in range(1, pm.njoints):
        h_world = pd.oMi[i].act(pm.inertias[i] * pd.v[i])  # momentum, world axes, at the origin
        L += h_world.angular - np.cross(r, h_world.linear)
    return L


def body_sum_L_mujoco(robot, d, r):
    m = robot.mj_model
    L = np.zeros(3)
    vel = np.zeros(6)
    for b in range(1, m.nbody):
        mujoco.mj_objectVelocity(m, d, mujoco.mjtObj.mjOBJ_BODY, b, vel, 0)  # at the CoM, world axes
        R = d.ximat[b].reshape(3, 3)
        L += m.body_mass[b] * np.cross(d.xipos[b] - r, vel[3:]) + R @ (m.body_inertia[b] * (R.T @ vel[:3]))
    return L


def test_L_about_contact_equals_sum_of_body_momenta(robot):
    kin = RobotKinematics(robot)
    for qpos, qvel, q, v in random_states(robot, 5, seed=17):
        d = mujoco_at(robot, qpos, qvel)
        kin.update(q, v)
        for side in robot.foot_sides:
            r = kin.contact_position(side)
            L = kin.angular_momentum_about_contact(side)
            np.testing.assert_allclose(L, kin.angular_momentum_about(r), atol=0)
            np.testing.assert_allclose(L, body_sum_L_pinocchio(robot, q, v, r), atol=1e-10)
            np.testing.assert_allclose(L, body_sum_L_mujoco(robot, d, r), atol=TOL_MJ)


# ----------------------------------------------------- finite differences
def test_contact_coupling_and_base_jacobians_by_finite_differences(robot):
    kin = RobotKinematics(robot)
    probe = RobotKinematics(robot)

    def at(qq, vv, getter):
        probe.update(qq, vv)
        return np.asarray(getter(probe), dtype=float).copy()

    for _qpos, _qvel, q, v in random_states(robot, 2, seed=18):
        kin.update(q, v)
        checks = [
            (
                lambda k: k.coupling_constraints()[0],
                kin.coupling_constraints()[1],
                kin.coupling_constraints()[2],
                lambda k: k.coupling_constraints()[1],
            ),
        ]
        for side in robot.foot_sides:
            checks.append(
                (
                    lambda k, s=side: k.contact_position(s),
                    kin.contact_jacobian(side),
                    kin.contact_jdot_v(side),
                    lambda k, s=side: k.contact_jacobian(s),
                )
            )
        assert_jacobians_match_fd(robot, checks, q, v, at, TOL_FD)
        # base angular velocity: R(q(t)) = R exp(w t) -> world w = log3(R^T R(t)) / t
        R0 = kin.base_rotation()
        rot_rate = fd_along(robot, lambda qq: R0 @ pin.log3(R0.T @ at(qq, v, lambda k: k.base_rotation())), q, v)
        np.testing.assert_allclose(kin.base_angular_jacobian() @ v, rot_rate, atol=TOL_FD)


def test_cassie_coupling_constraint():
    robot = load_robot("cassie")
    kin = RobotKinematics(robot)
    kin.update(robot.q_stand, np.zeros(robot.nv))
    g, G, gdv = kin.coupling_constraints()
    sm = robot.state_map
    for k, side in enumerate(("left", "right")):
        qk, qt = robot.q_stand[sm.joint_pin_q[f"{side}-knee"]], robot.q_stand[sm.joint_pin_q[f"{side}-tarsus"]]
        assert g[k] == pytest.approx(qt + qk - robot.couplings[k].springlength[0], abs=1e-15)
        assert abs(qt + qk - 0.2269) < 1e-3
        assert G[k, sm.joint_pin_v[f"{side}-knee"]] == 1.0 and G[k, sm.joint_pin_v[f"{side}-tarsus"]] == 1.0
        assert np.count_nonzero(G[k]) == 2
    np.testing.assert_array_equal(gdv, 0.0)


def test_kinematics_input_errors():
    robot = load_robot("rabbit")
    kin = RobotKinematics(robot)
    with pytest.raises(InputError, match="call update"):
        kin.outputs("left")
    with pytest.raises(InputError, match="call update"):
        kin.passive_forces()
    kin.update(robot.q_stand, np.arange(7.0))
    with pytest.raises(InputError, match="side"):
        kin.contact_position("front")
    with pytest.raises(InputError, match="side"):
        kin.angular_momentum_about_contact("front")


# ---------------------------------------------------------------- touchdown
def test_touchdown_L_about_new_contact_is_continuous():
    """Rabbit falls with v_x = 0.6 m/s, v_z = -0.3 m/s onto its left foot (right foot lifted).

    About a fixed world point r, dL/dt = (c - r) x m g + sum_contacts (p_k - r) x F_k.
    With r the ground point under the left foot at first contact, the impulsive
    contact force acts (almost) at r and contributes at most
    B = sum_t |p_k - r| |F_k| dt (the contact point moves by the sphere's
    rolling and penetration, a few mm), while gravity contributes
    G = sum_t (c - r) x m g dt, of order m g |p_x| dt_impact. So the jump of
    L_y over the impact must satisfy |dL - G| <= B (+ 1e-3 for the
    semi-implicit Euler discretization), and |dL| <= |G| + B, a few percent
    of |L|, although the impact changes the linear momentum by several N s.
    """
    robot = load_robot("rabbit")
    m = robot.mj_model
    d = robot.new_mj_data()
    kin = RobotKinematics(robot)
    qpos = robot.qpos_stand.copy()
    iq = robot.state_map.joint_pin_q
    qpos[iq["right-knee"]] = 1.0  # lift the right foot
    qpos[iq["root-z"]] += 0.005  # left foot 5 mm above the floor
    d.qpos[:] = qpos
    d.qvel[iq["root-x"]], d.qvel[iq["root-z"]] = 0.6, -0.3
    mujoco.mj_forward(m, d)
    act = robot.actuated
    q_ref = qpos[act.mj_qpos_idx].copy()
    radius = m.geom_size[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, "left-foot"), 0]
    g = np.array([0.0, 0.0, -9.81])
    dt = m.opt.timestep
    log = []
    force6 = np.zeros(6)
    for _ in range(200):
        q, v = mj_to_pin(robot, d.qpos, d.qvel)
        kin.update(q, v)
        contacts = []
        for i in range(d.ncon):
            mujoco.mj_contactForce(m, d, i, force6)
            contacts.append((d.contact[i].pos.copy(), np.linalg.norm(force6[:3])))
        log.append(
            dict(
                c=kin.com(),
                mom=kin.centroidal_momentum(),
                foot=kin.contact_position("left"),
                foot_vz=(kin.contact_jacobian("left") @ v)[2],
                contacts=contacts,
            )
        )
        tau = 300.0 * (q_ref - d.qpos[act.mj_qpos_idx]) - 10.0 * d.qvel[act.mj_dof_idx]  # internal: no effect on L
        d.ctrl[:] = np.clip(tau, act.torque_limit_Nm[:, 0], act.torque_limit_Nm[:, 1]) / act.gear
        mujoco.mj_step(m, d)
        if len(log) > 1 and log[-1]["contacts"] and log[-1]["foot_vz"] > -0.05:
            break
    k0 = next(k for k, e in enumerate(log) if e["contacts"])
    k1 = len(log) - 1
    assert 0 < k0 < k1 and log[k1]["foot_vz"] > -0.05, "the foot did not land within the window"
    assert all(len(e["contacts"]) <= 1 for e in log)  # only the left foot touches
    r = log[k0]["foot"] - np.array([0.0, 0.0, radius])
    L = lambda e: e["mom"][1] + np.cross(e["c"] - r, e["mom"][0])  # noqa: E731
    pre, post = log[k0 - 1], log[k1]
    jump = L(post) - L(pre)
    grav = sum(np.cross(log[k]["c"] - r, robot.mass_kg * g) * dt for k in range(k0 - 1, k1))
    bound = sum(np.linalg.norm(p - r) * f * dt for k in range(k0 - 1, k1) for p, f in log[k]["contacts"])
    impulse = np.linalg.norm(post["mom"][0] - pre["mom"][0] - robot.mass_kg * g * dt * (k1 - k0 + 1))
    assert impulse > 5.0  # a real impact: several N s of contact impulse
    assert abs(jump[1] - grav[1]) <= bound + 1e-3
    assert abs(jump[1]) <= abs(grav[1]) + bound + 1e-3
    assert abs(jump[1]) < 0.05 * abs(L(pre)[1])
    np.testing.assert_allclose(jump[[0, 2]], 0.0, atol=1e-9)  # planar: L stays along y


# ----------------------------------------------------------------- standing
def quasi_static_torques(robot, kin, q):
    """Motor torques holding q with both feet's force points loaded and couplings rigid.

    Static balance: h - f_passive = S^T tau + Jc^T lam + G^T mu. The base rows
    and the coupled passive rows (tarsus) fix (lam, mu) (minimum norm); the
    actuated rows then give tau. Rows of springs that are not coupled (shin)
    are left to the springs' small deflection.
    """
    kin.update(q, np.zeros(robot.nv))
    rhs = kin.nonlinear_effects() - kin.passive_forces()
    Jc = np.vstack([kin.frame_jacobian(f) for s in robot.foot_sides for f in robot.force_frame_ids[s]])
    G = kin.coupling_constraints()[1]
    Jall = np.vstack([Jc, G])
    coupled = sorted({int(i) for c in robot.couplings for i in c.pin_v_idx} - set(robot.actuated.pin_v_idx.tolist()))
    rows = np.r_[np.arange(6), coupled].astype(int)
    lam = np.linalg.lstsq(Jall[:, rows].T, rhs[rows], rcond=None)[0]
    return (rhs - Jall.T @ lam)[robot.actuated.pin_v_idx]


def test_cassie_stands_for_two_seconds():
    """Joint PD + quasi-static gravity compensation + pelvis-pitch feedback on the foot motors."""
    robot = load_robot("cassie")
    m = robot.mj_model
    d = robot.new_mj_data("stand")
    kin = RobotKinematics(robot)
    act = robot.actuated
    tau_ff = quasi_static_torques(robot, kin, robot.q_stand)
    kp = np.array([1000.0, 500.0, 1500.0, 1500.0, 1500.0] * 2)
    kd = np.array([20.0, 10.0, 30.0, 30.0, 15.0] * 2)
    foot = np.array([i for i, n in enumerate(act.joint_names) if n.endswith("-foot")])
    q_ref = d.qpos[act.mj_qpos_idx].copy()
    start = d.qpos[:3].copy()
    max_drift, min_z = 0.0, np.inf
    for _ in range(int(round(2.0 / m.opt.timestep))):
        tau = tau_ff + kp * (q_ref - d.qpos[act.mj_qpos_idx]) - kd * d.qvel[act.mj_dof_idx]
        w, x, y, z = d.qpos[3:7]
        pitch = np.arcsin(np.clip(2 * (w * y - z * x), -1, 1))
        tau[foot] -= 1000.0 * pitch + 40.0 * d.qvel[4]  # ankle strategy on the blade feet
        tau = np.clip(tau, act.torque_limit_Nm[:, 0], act.torque_limit_Nm[:, 1])
        d.ctrl[:] = tau / act.gear
        assert np.all(np.abs(d.ctrl) <= act.ctrl_range[:, 1] + 1e-12)
        mujoco.mj_step(m, d)
        max_drift = max(max_drift, np.linalg.norm(d.qpos[:2] - start[:2]))
        min_z = min(min_z, d.qpos[2])
    assert min_z > start[2] - 0.05, f"pelvis dropped to {min_z:.3f} m"
    assert max_drift < 0.02, f"pelvis drifted {max_drift:.4f} m"


def test_update_positions_drops_the_robot_caches_and_gives_the_outputs_without_velocity_terms(robot):
    """After the light update the outputs are those of update(q, 0) with a zero drift (the
    cache of the last full update is dropped), and so are the passive forces."""
    rng = np.random.default_rng(21)
    q = pin.integrate(robot.pin_model, robot.q_stand, rng.normal(0.0, 0.05, robot.nv))
    v = rng.normal(0.0, 0.5, robot.nv)
    full, light = RobotKinematics(robot), RobotKinematics(robot)
    light.update(q, v)  # a full update first: the light one must drop its caches
    light.outputs("left", 0.2), light.passive_forces()
    q2 = pin.integrate(robot.pin_model, q, rng.normal(0.0, 0.05, robot.nv))
    light.update_positions(q2)
    full.update(q2, np.zeros(robot.nv))
    for stance in robot.foot_sides:
        y, J, jdv = light.outputs(stance, 0.2)
        y_f, J_f, _ = full.outputs(stance, 0.2)
        np.testing.assert_allclose(y, y_f, atol=1e-12)
        np.testing.assert_allclose(J, J_f, atol=1e-12)
        np.testing.assert_array_equal(jdv, 0.0)
    np.testing.assert_array_equal(light.passive_forces(), full.passive_forces())
    for side in robot.foot_sides:
        np.testing.assert_array_equal(light.contact_jdot_v(side), 0.0)


def test_outputs_are_cached_per_stance_and_heading_until_the_next_update(robot):
    rng = np.random.default_rng(22)
    q = pin.integrate(robot.pin_model, robot.q_stand, rng.normal(0.0, 0.05, robot.nv))
    kin = RobotKinematics(robot)
    kin.update(q, rng.normal(0.0, 0.5, robot.nv))
    want = kin.outputs("left", 0.3)
    assert kin.outputs("left", 0.3) is want
    other = kin.outputs("right", 0.3)  # another stance (or heading) is evaluated
    assert other is not want and kin.outputs("left", 0.3) is not want
    turned = kin.outputs("left", -0.3)
    assert turned is not want and kin.outputs("left", 0.3) is not turned
    kin.update(q, np.zeros(robot.nv))
    again = kin.outputs("left", 0.3)
    assert again is not want
    np.testing.assert_array_equal(again[0], want[0])  # the outputs depend on q only
    assert not hasattr(kin, "store_outputs")  # nothing but its own output map fills the cache
    with pytest.raises(InputError, match="update"):
        RobotKinematics(robot).outputs("left", 0.0)


# --------------------------------------------------------- passive forces
def _passive_reference(robot, q, v):
    """passive_forces written plainly: damping, joint springs, tendon springs/dampers."""
    from amlip_qp.robots.passive import tendon_force

    sm = robot.state_map
    f = -robot.dof_damping * v
    pq, pv = sm.scalar_pin_q, sm.scalar_pin_v
    f[pv] -= robot.dof_stiffness[pv] * (q[pq] - robot.dof_springref[pv])
    for c in robot.couplings:
        force = tendon_force(c, float(c.coefficients @ q[c.pin_q_idx]), float(c.coefficients @ v[c.pin_v_idx]))
        f[c.pin_v_idx] += c.coefficients * force
    return f


def test_precomputed_passive_forces_equal_the_plain_formula():
    """PassiveForces (kept by RobotKinematics) is bit for bit the plain formula, also with
    general tendon coefficients, a dead band and non-contiguous joint indices."""
    import dataclasses

    from amlip_qp.robots import passive

    rng = np.random.default_rng(34)
    for name in ROBOTS:
        robot = load_robot(name)
        variants = [robot]
        if robot.couplings:
            variants.append(
                dataclasses.replace(
                    robot,
                    couplings=tuple(
                        dataclasses.replace(
                            c, coefficients=rng.normal(size=c.coefficients.size), springlength=(-0.1, 0.2)
                        )
                        for c in robot.couplings
                    ),
                )
            )
        for r in variants:
            forces = passive.PassiveForces(r)
            for _, _, q, v in random_states(r, 5, seed=35):
                expected = _passive_reference(r, q, v)
                np.testing.assert_array_equal(forces(q, v), expected)
                np.testing.assert_array_equal(passive.passive_forces(r, q, v), expected)
