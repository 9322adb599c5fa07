"""Tests of amlip_qp.robots.model_kinematics: Pinocchio's passes, frames, CoM, momentum and dynamics of a model,
against MuJoCo, finite differences and fresh reads of Pinocchio's data."""

from __future__ import annotations

import mujoco
import numpy as np
import pinocchio as pin
import pytest

from amlip_qp.exceptions import InputError
from amlip_qp.robots import bias_mj_to_pin, load_robot, mass_matrix_mj_to_pin, velocity_map
from amlip_qp.robots.model_kinematics import ModelKinematics
from robot_states import ROBOTS, assert_jacobians_match_fd, mujoco_at, random_states

TOL_MJ = 1e-8  # Pinocchio vs MuJoCo (both exact rigid-body algorithms; only round-off differs)
TOL_FD = 1e-6  # central differences with h = 1e-6: truncation ~h^2, round-off ~1e-16/h


@pytest.fixture(scope="module", params=ROBOTS)
def robot(request):
    return load_robot(request.param)


# ------------------------------------------------------- Pinocchio vs MuJoCo
def test_mass_and_com_match_mujoco(robot):
    kin = ModelKinematics(robot.pin_model)
    for qpos, qvel, q, v in random_states(robot, 5, seed=10):
        d = mujoco_at(robot, qpos, qvel)
        kin.update(q, v)
        assert kin.mass_kg == pytest.approx(robot.mass_kg, abs=1e-12)
        assert robot.mass_kg == pytest.approx(robot.mj_model.body_subtreemass[0], abs=1e-12)
        np.testing.assert_allclose(kin.com(), d.subtree_com[0], atol=TOL_MJ)
        np.testing.assert_allclose(kin.com_velocity(), d.subtree_linvel[0], atol=TOL_MJ)


def test_the_mass_taken_once_has_the_bits_of_every_update(robot):
    """mass_kg is read once: Pinocchio's total mass has the same bits at every configuration and after
    each kind of update (the full one, the kinematics-only one, the positions-only one)."""
    kin = ModelKinematics(robot.pin_model)
    for k, (_, _, q, v) in enumerate(random_states(robot, 6, seed=11)):
        (kin.update, kin.update_kinematics, lambda q, v: kin.update_positions(q))[k % 3](q, v)
        assert float(kin.data.mass[0]).hex() == kin.mass_kg.hex()


def test_mass_matrix_matches_mujoco_including_armature(robot):
    kin = ModelKinematics(robot.pin_model)
    m = robot.mj_model
    for qpos, qvel, q, v in random_states(robot, 5, seed=11):
        d = mujoco_at(robot, qpos, qvel)
        M_mj = np.zeros((m.nv, m.nv))
        mujoco.mj_fullM(m, d, M_mj)
        kin.update(q, v)
        M = kin.mass_matrix()
        np.testing.assert_allclose(M, M.T, atol=0)
        np.testing.assert_allclose(M, mass_matrix_mj_to_pin(robot, q, M_mj), atol=TOL_MJ)
    np.testing.assert_allclose(robot.pin_model.armature, robot.dof_armature, atol=0)


def test_bias_forces_match_mujoco_full_base_velocity(robot):
    """h_pin = T^T (b_mj + M_mj Tdot v), with qvel = T v (derivation in state.bias_mj_to_pin)."""
    kin = ModelKinematics(robot.pin_model)
    m = robot.mj_model
    for qpos, qvel, q, v in random_states(robot, 5, seed=12):
        d = mujoco_at(robot, qpos, qvel)
        M_mj = np.zeros((m.nv, m.nv))
        mujoco.mj_fullM(m, d, M_mj)
        kin.update(q, v)
        expect = bias_mj_to_pin(robot, q, v, d.qfrc_bias, M_mj)
        np.testing.assert_allclose(kin.nonlinear_effects(), expect, atol=TOL_MJ * max(1.0, np.abs(expect).max()))
        if robot.is_floating:  # the Tdot term matters: without it the base rows disagree
            naive = velocity_map(robot, q).T @ d.qfrc_bias
            assert np.abs(naive - kin.nonlinear_effects()).max() > 1e-3


def test_frame_positions_and_jacobians_match_mujoco_sites(robot):
    kin = ModelKinematics(robot.pin_model)
    m = robot.mj_model
    for qpos, qvel, q, v in random_states(robot, 5, seed=15):
        d = mujoco_at(robot, qpos, qvel)
        kin.update(q, v)
        T = velocity_map(robot, q)
        for side in robot.foot_sides:
            sites = [(robot.contact_site_ids[side], robot.contact_frame_ids[side])]
            sites += list(zip(robot.force_site_ids[side], robot.force_frame_ids[side]))
            for sid, fid in sites:
                jacp = np.zeros((3, m.nv))
                mujoco.mj_jacSite(m, d, jacp, None, sid)
                np.testing.assert_allclose(kin.frame_position(fid), d.site_xpos[sid], atol=TOL_MJ)
                np.testing.assert_allclose(kin.frame_jacobian(fid), jacp @ T, atol=TOL_MJ)


def test_centroidal_momentum_matches_mujoco(robot):
    kin = ModelKinematics(robot.pin_model)
    for qpos, qvel, q, v in random_states(robot, 5, seed=16):
        d = mujoco_at(robot, qpos, qvel)
        kin.update(q, v)
        lin, ang = kin.centroidal_momentum()
        np.testing.assert_allclose(lin, robot.mass_kg * d.subtree_linvel[0], atol=TOL_MJ)
        np.testing.assert_allclose(ang, d.subtree_angmom[0], atol=TOL_MJ)
        np.testing.assert_allclose(kin.centroidal_momentum_matrix() @ v, np.r_[lin, ang], atol=1e-10)


def test_angular_momentum_about_a_point_is_the_centroidal_momentum_moved_there(robot):
    """``L = L_c + (c - r) x m v_c``, against numpy's cross product; a non-finite point is refused."""
    kin = ModelKinematics(robot.pin_model)
    rng = np.random.default_rng(19)
    for _, _, q, v in random_states(robot, 3, seed=19):
        kin.update(q, v)
        lin, ang = kin.centroidal_momentum()
        r = rng.normal(0.0, 0.5, 3)
        np.testing.assert_allclose(
            kin.angular_momentum_about(r), ang + np.cross(kin.com() - r, lin), rtol=0, atol=1e-12
        )
        np.testing.assert_array_equal(kin.angular_momentum_about(kin.com()), ang)
    with pytest.raises(InputError, match="finite 3-vector"):
        kin.angular_momentum_about([0.0, np.nan, 0.0])
    with pytest.raises(InputError, match="finite 3-vector"):
        kin.angular_momentum_about([0.0, 1.0])


# ----------------------------------------------------- finite differences
def test_com_and_frame_jacobians_and_drifts_by_finite_differences(robot):
    kin = ModelKinematics(robot.pin_model)
    probe = ModelKinematics(robot.pin_model)

    def at(qq, vv, getter):
        probe.update(qq, vv)
        return np.asarray(getter(probe), dtype=float).copy()

    for _qpos, _qvel, q, v in random_states(robot, 2, seed=18):
        kin.update(q, v)
        checks = [(lambda k: k.com(), kin.com_jacobian(), kin.com_jdot_v(), lambda k: k.com_jacobian())]
        for side in robot.foot_sides:
            for f in (robot.contact_frame_ids[side], *robot.force_frame_ids[side]):
                checks.append(
                    (
                        lambda k, f=f: k.frame_position(f),
                        kin.frame_jacobian(f),
                        kin.frame_jdot_v(f),
                        lambda k, f=f: k.frame_jacobian(f),
                    )
                )
        assert_jacobians_match_fd(robot, checks, q, v, at, TOL_FD)


def test_model_kinematics_input_errors():
    robot = load_robot("rabbit")
    kin = ModelKinematics(robot.pin_model)
    with pytest.raises(InputError, match="call update"):
        kin.com()
    with pytest.raises(InputError, match="call update"):
        kin.state()
    with pytest.raises(InputError, match="call update"):
        kin.require_dynamics()
    with pytest.raises(InputError, match=r"shapes \(7,\), \(7,\)"):
        kin.update(np.zeros(6), np.zeros(7))
    with pytest.raises(InputError, match="NaN"):
        kin.update(np.full(7, np.nan), np.zeros(7))
    v = np.arange(7.0)
    kin.update(robot.q_stand, v)
    q_now, v_now = kin.state()
    assert q_now is kin.q and v_now is kin.v  # the attributes themselves, not copies
    np.testing.assert_array_equal(q_now, robot.q_stand)
    np.testing.assert_array_equal(v_now, v)
    kin.update_positions(robot.q_stand)
    np.testing.assert_array_equal(kin.state()[1], 0.0)  # the light update sets v = 0
    with pytest.raises(InputError, match="update_positions"):
        kin.require_dynamics()


# ------------------------------------------------------------ light update
def test_update_positions_matches_full_update_without_velocity_terms(robot):
    """The light update gives the same positions and Jacobians as update(q, 0); velocity
    terms are zero and the dynamics getters refuse until the next full update."""
    rng = np.random.default_rng(21)
    q = pin.integrate(robot.pin_model, robot.q_stand, rng.normal(0.0, 0.05, robot.nv))
    v = rng.normal(0.0, 0.5, robot.nv)
    full, light = ModelKinematics(robot.pin_model), ModelKinematics(robot.pin_model)
    light.update(q, v)  # a full update first: the light one must drop its caches
    cid = robot.contact_frame_ids["left"]
    light.frame_jacobian6(cid), light.frame_jdot_v6(cid), light.mass_matrix()
    q2 = pin.integrate(robot.pin_model, q, rng.normal(0.0, 0.05, robot.nv))
    light.update_positions(q2)
    full.update(q2, np.zeros(robot.nv))
    assert light.positions_only and not full.positions_only
    np.testing.assert_array_equal(light.v, 0.0)
    np.testing.assert_allclose(light.com(), full.com(), atol=1e-12)
    np.testing.assert_allclose(light.com_jacobian(), full.com_jacobian(), atol=1e-12)
    for fid in list(robot.contact_frame_ids.values()) + [robot.base_frame_id]:
        np.testing.assert_allclose(light.frame_position(fid), full.frame_position(fid), atol=1e-12)
        np.testing.assert_allclose(light.frame_rotation(fid), full.frame_rotation(fid), atol=1e-12)
        np.testing.assert_allclose(light.frame_jacobian6(fid), full.frame_jacobian6(fid), atol=1e-12)
        np.testing.assert_array_equal(light.frame_jdot_v6(fid), 0.0)
    np.testing.assert_array_equal(light.com_velocity(), 0.0)
    np.testing.assert_array_equal(light.com_jdot_v(), 0.0)
    for getter in (
        light.mass_matrix,
        light.nonlinear_effects,
        light.centroidal_momentum_matrix,
        light.centroidal_momentum,
    ):
        with pytest.raises(InputError):
            getter()
    # a full update makes everything valid again
    light.update(q2, v)
    assert not light.positions_only
    np.testing.assert_allclose(light.mass_matrix(), full.mass_matrix(), atol=1e-12)
    np.testing.assert_allclose(light.frame_jdot_v6(cid), _jdot_v6_at(robot, q2, v, cid), atol=1e-12)


def _jdot_v6_at(robot, q, v, fid):
    k = ModelKinematics(robot.pin_model)
    k.update(q, v)
    return k.frame_jdot_v6(fid)


# ------------------------------------------------------- cached reads and views
def _fresh_reads(kin, fid):
    """The quantities the getters serve, read from Pinocchio's data afresh."""
    d = kin.data
    return {
        "position": d.oMf[fid].translation.copy(),
        "rotation": d.oMf[fid].rotation.copy(),
        "com": d.com[0].copy(),
        "vcom": d.vcom[0].copy(),
        "acom": d.acom[0].copy(),
        "hg": d.hg.vector.copy(),
        "jacobian": pin.getFrameJacobian(kin.model, d, fid, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED),
        "drift": pin.getFrameClassicalAcceleration(kin.model, d, fid, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED).linear,
    }


def test_getters_follow_every_update_exactly(robot):
    """Frame placements, the CoM and the momentum are read through views made once:
    after many updates (full and light), every getter equals a fresh read of the data."""
    kin = ModelKinematics(robot.pin_model)
    fid = robot.contact_frame_ids["left"]
    for k, (_, _, q, v) in enumerate(random_states(robot, 6, seed=31)):
        if k % 3 == 2:
            kin.update_positions(q)
        else:
            kin.update(q, v)
        fresh = _fresh_reads(kin, fid)
        np.testing.assert_array_equal(kin.frame_position(fid), fresh["position"])
        np.testing.assert_array_equal(kin.frame_rotation(fid), fresh["rotation"])
        np.testing.assert_array_equal(kin.com(), fresh["com"])
        # the per-update caches: the translational rows are those of the 6-row Jacobian, both refreshed
        np.testing.assert_array_equal(kin.frame_jacobian(fid), fresh["jacobian"][:3])
        np.testing.assert_array_equal(kin.frame_jacobian6(fid), fresh["jacobian"])
        if kin.positions_only:
            assert not kin.frame_jdot_v(fid).any()
            continue
        np.testing.assert_array_equal(kin.frame_jdot_v(fid), fresh["drift"])
        np.testing.assert_array_equal(kin.frame_jdot_v6(fid)[:3], fresh["drift"])
        np.testing.assert_array_equal(kin.com_velocity(), fresh["vcom"])
        np.testing.assert_array_equal(kin.com_jdot_v(), fresh["acom"])
        lin, ang = kin.centroidal_momentum()
        np.testing.assert_array_equal(np.concatenate([lin, ang]), fresh["hg"])


def test_getters_return_copies_that_later_updates_leave_alone(robot):
    kin = ModelKinematics(robot.pin_model)
    states = list(random_states(robot, 2, seed=32))
    fid = robot.contact_frame_ids["right"]
    kin.update(states[0][2], states[0][3])
    held = [kin.frame_position(fid), kin.com(), kin.com_velocity(), kin.frame_rotation(fid), kin.frame_jdot_v6(fid)]
    snapshot = [h.copy() for h in held]
    import gc

    gc.collect()
    kin.update(states[1][2], states[1][3])
    kin.frame_jdot_v6(fid)
    for h, s in zip(held, snapshot):
        np.testing.assert_array_equal(h, s)
    held[0][:] = 123.0  # writing into a returned copy does not reach the kinematics
    assert not np.any(kin.frame_position(fid) == 123.0)


def test_drifts_equal_a_separate_zero_acceleration_pass(robot):
    """update() relies on computeAllTerms leaving data.a at vdot = 0: the drifts are
    bit for bit those of an explicit forwardKinematics(q, v, 0) pass."""
    kin = ModelKinematics(robot.pin_model)
    m = robot.pin_model
    ref = m.createData()
    for _, _, q, v in random_states(robot, 5, seed=33):
        kin.update(q, v)
        pin.computeAllTerms(m, ref, q, v)
        pin.forwardKinematics(m, ref, q, v, np.zeros(m.nv))
        pin.updateFramePlacements(m, ref)
        pin.centerOfMass(m, ref, pin.KinematicLevel.ACCELERATION, False)
        for fid in [robot.base_frame_id, *robot.contact_frame_ids.values()]:
            a = pin.getFrameClassicalAcceleration(m, ref, fid, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)
            np.testing.assert_array_equal(kin.frame_jdot_v6(fid), np.concatenate([a.linear, a.angular]))
            np.testing.assert_array_equal(kin.frame_position(fid), ref.oMf[fid].translation)
        np.testing.assert_array_equal(kin.com_jdot_v(), ref.acom[0])
        np.testing.assert_array_equal(kin.com(), ref.com[0])


def test_replacing_data_rebinds_the_views():
    robot = load_robot("rabbit")
    kin = ModelKinematics(robot.pin_model)
    kin.update(robot.q_stand, np.zeros(robot.nv))
    kin.data = robot.pin_model.createData()
    q = robot.q_stand.copy()
    q[0] += 0.25
    kin.update(q, np.zeros(robot.nv))
    fid = robot.contact_frame_ids["left"]
    np.testing.assert_array_equal(kin.frame_position(fid), kin.data.oMf[fid].translation)
    np.testing.assert_array_equal(kin.com(), kin.data.com[0])


def test_huge_finite_states_pass_the_finiteness_test():
    """The cheap per-tick test (a sum) may overflow for huge finite values; the exact
    check then decides, so only NaN and inf are refused."""
    robot = load_robot("rabbit")
    kin = ModelKinematics(robot.pin_model)
    v = np.zeros(robot.nv)
    v[:2] = 1e308
    kin.update(robot.q_stand, v)  # sum overflows to inf, entries are finite
    for bad in (np.inf, -np.inf, np.nan):
        v[3] = bad
        with pytest.raises(InputError, match="NaN or inf"):
            kin.update(robot.q_stand, v)


def test_position_only_drifts_are_read_only_shared_zeros(robot):
    kin = ModelKinematics(robot.pin_model)
    kin.update_positions(robot.q_stand)
    fid = robot.contact_frame_ids["left"]
    a = kin.frame_jdot_v(fid)
    assert np.all(a == 0.0)
    with pytest.raises(ValueError):
        a[0] = 1.0  # would corrupt every later drift


def test_update_kinematics_gives_the_kinematics_of_the_full_update_without_the_dynamics(robot):
    """update_kinematics(q, v): every frame and CoM quantity, the CoM Jacobian included, the same bits
    as after update(q, v); the dynamics raise."""
    full, light = ModelKinematics(robot.pin_model), ModelKinematics(robot.pin_model)
    m = robot.pin_model
    for _, _, q, v in random_states(robot, 3, seed=17):
        full.update(q, v)
        light.update(q, v)  # a full update first: the light one must drop its dynamics
        light.mass_matrix()
        light.update_kinematics(q, v)
        np.testing.assert_array_equal(light.state()[0], q)
        np.testing.assert_array_equal(light.state()[1], v)
        for f in range(m.nframes):
            np.testing.assert_array_equal(light.frame_position(f), full.frame_position(f))
            np.testing.assert_array_equal(light.frame_rotation(f), full.frame_rotation(f))
            np.testing.assert_array_equal(light.frame_jacobian6(f), full.frame_jacobian6(f))
            np.testing.assert_array_equal(light.frame_jdot_v6(f), full.frame_jdot_v6(f))
        np.testing.assert_array_equal(light.com(), full.com())
        np.testing.assert_array_equal(light.com_velocity(), full.com_velocity())
        np.testing.assert_array_equal(light.com_jdot_v(), full.com_jdot_v())
        np.testing.assert_array_equal(light.com_jacobian(), full.com_jacobian())
        for getter in (light.mass_matrix, light.nonlinear_effects, light.centroidal_momentum_matrix):
            with pytest.raises(InputError, match="update_kinematics"):
                getter()
