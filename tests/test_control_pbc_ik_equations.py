"""Tests of the IK's equations (amlip_qp.control.pbc.ik_equations): a square system per robot."""

import numpy as np
import pytest

from amlip_qp.control.pbc.ik_equations import IKEquations
from amlip_qp.exceptions import MJCFError
from amlip_qp.robots import OutputMap, load_robot


@pytest.fixture(scope="module", params=["cassie", "rabbit"])
def robot(request):
    return load_robot(request.param)


def test_outputs_and_held_coordinates_make_a_square_system(robot):
    n_out = OutputMap(robot).size
    eq = IKEquations(robot, n_out)
    for side in robot.foot_sides:
        rows = eq.rows[side]
        held_ankle = len(eq.held_v[side])
        # outputs + contact pose + (ankle) + springs = nv: Cassie 9 + 6 + 1 + 4, Rabbit 4 + 3
        assert n_out + len(eq.pose_rows) + held_ankle + len(eq.held_springs) == robot.nv
        assert rows.A.shape == (robot.nv, robot.nv) and rows.n_var == n_out + len(eq.pose_rows)
        assert rows.lin_q.shape == (robot.nv - rows.n_var, robot.nq)
        # the controlled joints: every actuated joint but the held stance ankle
        ctrl = eq.controlled_actuated(side)
        assert len(ctrl) == robot.nu - held_ankle
        assert not set(eq.held_v[side]) & set(robot.actuated.pin_v_idx[ctrl])
    if robot.name == "cassie":
        assert len(eq.pose_rows) == 6 and eq.held_v["left"] == (robot.state_map.joint_pin_v["left-foot"],)
        assert [s.kind for s in eq.held_springs] == ["joint", "joint", "coupling", "coupling"]
        rest = eq.spring_rest_values()
        np.testing.assert_allclose(rest, [s.rest for s in eq.held_springs])
    else:
        np.testing.assert_array_equal(eq.pose_rows, [0, 2, 4])  # in-plane x, z, pitch
        assert eq.held_springs == () and eq.spring_rest_values().size == 0


def test_a_model_that_is_not_square_is_an_mjcf_error(robot):
    with pytest.raises(MJCFError, match="IK needs"):
        IKEquations(robot, OutputMap(robot).size + 2)


def test_a_humanoid_with_an_ankle_roll_holds_both_stance_ankle_joints():
    """G1: 12 leg joints, the stance ankle's pitch and roll passive: 10 outputs + the stance foot's
    pose (6) + the 17 waist and arm joints + the two stance ankle joints = nv = 35."""
    g1 = load_robot("g1")
    eq = IKEquations(g1, OutputMap(g1).size)
    assert OutputMap(g1).size == 10 and len(eq.posture_v) == 17 and g1.nv == 35
    for side in g1.foot_sides:
        v_idx = g1.state_map.joint_pin_v
        assert eq.held_v[side] == (v_idx[f"{side}_ankle_pitch_joint"], v_idx[f"{side}_ankle_roll_joint"])
        assert len(eq.controlled_actuated(side)) == g1.nu - 2
        assert eq.rows[side].A.shape == (35, 35)
