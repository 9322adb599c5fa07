"""Tests of the simplified spring model (amlip_qp.control.pbc.springs)."""

from __future__ import annotations

import numpy as np
import pytest

from amlip_qp.control.pbc.springs import spring_deflections_rad
from amlip_qp.robots import load_robot
from amlip_qp.robots.kinematics import RobotKinematics


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
