"""LegKinematics: the contact sites seen from the IMU, from the joint angles only, against the full
model's kinematics at an arbitrary base pose."""

import numpy as np
import pytest

from amlip_qp.estimation.base_estimator import quat_xyzw_to_rot
from amlip_qp.estimation.leg_kinematics import LegKinematics
from amlip_qp.exceptions import InputError
from amlip_qp.robots import RobotKinematics, load_robot

IMU = np.array([0.03, -0.01, 0.09])


@pytest.fixture(scope="module")
def cassie():
    return load_robot("cassie")


def test_the_contacts_in_the_imu_frame_match_the_full_kinematics(cassie):
    rng = np.random.default_rng(0)
    legs = LegKinematics(cassie, IMU)
    kin = RobotKinematics(cassie)
    for _ in range(3):
        q = cassie.q_stand.copy()
        q[0:3] = rng.normal(size=3)
        quat = rng.normal(size=4)
        q[3:7] = quat / np.linalg.norm(quat)
        q[7:] += 0.2 * rng.normal(size=cassie.nq - 7)
        kin.update_positions(q)
        R = quat_xyzw_to_rot(q[3:7])
        y = legs.contacts_in_imu(q)
        blades = legs.blades_in_imu(q)
        for i, side in enumerate(legs.sides):
            world = q[0:3] + R @ (IMU + y[i])
            np.testing.assert_allclose(world, kin.contact_position(side), atol=1e-12)
            toe, heel = (kin.frame_translation_view(f) for f in cassie.force_frame_ids[side])
            np.testing.assert_allclose(R @ blades[i], toe - heel, atol=1e-12)
            assert abs(np.linalg.norm(blades[i]) - 0.16) < 1e-6  # Cassie's blade: 0.16 m from heel to toe
    # the base part of q is ignored
    q2 = q.copy()
    q2[0:7] = [5.0, 5.0, 5.0, 0.0, 0.0, 0.0, 1.0]
    np.testing.assert_array_equal(legs.contacts_in_imu(q2), y)


def test_standing_the_blades_are_flat(cassie):
    blades = LegKinematics(cassie, IMU).blades_in_imu(cassie.q_stand)
    world = blades @ quat_xyzw_to_rot(cassie.q_stand[3:7]).T
    assert np.abs(world[:, 2]).max() < 1e-6 and np.all(world[:, 0] > 0.15)


def test_a_robot_without_a_floating_base_or_a_bad_imu_position_is_refused(cassie):
    with pytest.raises(InputError, match="free-floating base"):
        LegKinematics(load_robot("rabbit"), IMU)
    with pytest.raises(InputError, match="imu_pos_in_base_m"):
        LegKinematics(cassie, [0.0, np.nan, 0.0])
    with pytest.raises(InputError, match="imu_pos_in_base_m"):
        LegKinematics(cassie, [0.0, 0.0])


def test_a_four_point_foot_gives_the_blade_of_its_sole_line(tmp_path):
    """G1 with its four foot spheres (tests/sole_cases.py): the blade runs from the heel pair's middle
    to the toe pair's middle (0.17 m, level at the stand pose), the mean of the front corners minus
    the mean of the back corners."""
    from sole_cases import sole_profile

    g1 = load_robot(sole_profile("g1", tmp_path))
    legs = LegKinematics(g1, IMU)
    kin = RobotKinematics(g1)
    kin.update_positions(g1.q_stand)
    R = quat_xyzw_to_rot(g1.q_stand[3:7])
    blades = legs.blades_in_imu(g1.q_stand)
    for i, side in enumerate(legs.sides):
        c = [kin.frame_translation_view(f).copy() for f in g1.force_frame_ids[side]]
        np.testing.assert_allclose(R @ blades[i], 0.5 * (c[0] + c[1]) - 0.5 * (c[2] + c[3]), atol=1e-12)
        assert abs(np.linalg.norm(blades[i]) - 0.17) < 1e-9 and abs((R @ blades[i])[2]) < 1e-3
