"""The PBC's system assembled by generated C reading Pinocchio in place equals the Python assembly,
and solves the constrained dynamics."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from amlip_qp.codegen.runtime import CodegenFallbackWarning
from amlip_qp.control.pbc.dynamics_compiled import MAX_BINDINGS
from amlip_qp.control.pbc.tracker import PBCTracker
from amlip_qp.exceptions import CompilerUnavailableError, InputError
from amlip_qp.robots import load_robot
from amlip_qp.robots.kinematics import RobotKinematics
from robot_states import near_stand_q


@pytest.fixture(scope="module", params=["cassie", "rabbit", "g1"])
def trackers(request):
    """``(robot, compiled tracker, Python tracker)``: Cassie's blade, Rabbit's planar point foot, G1's
    four-point sole held along its line."""
    robot = load_robot(request.param)
    return robot, PBCTracker(robot), PBCTracker(robot, compiled_dynamics=False)


def _kin(robot, rng):
    kin = RobotKinematics(robot)
    kin.update(near_stand_q(robot, rng), rng.normal(0.0, 0.5, robot.nv))
    return kin


def test_the_compiled_system_equals_the_python_assembly(trackers):
    robot, compiled, python = trackers
    assert compiled.dynamics_backend == "c-in-place" and python.dynamics_backend == "python"
    rng = np.random.default_rng(0)
    for i in range(8):
        kin = _kin(robot, rng)
        stance = robot.foot_sides[i % 2]
        vdot = rng.normal(0.0, 3.0, len(compiled.layout(stance).ctrl_v))
        got = compiled.solve_dynamics(kin, stance, vdot)
        want = python.solve_dynamics(kin, stance, vdot)
        a, b = compiled.layout(stance), python.layout(stance)
        scale = 1.0 + np.abs(b.K)
        assert np.max(np.abs(a.K - b.K) / scale) < 1e-13, f"K differs (state {i}, {stance})"
        assert np.max(np.abs(a.rhs - b.rhs) / (1.0 + np.abs(b.rhs))) < 1e-13, f"rhs differs (state {i})"
        for x, y in zip(got, want):
            np.testing.assert_allclose(x, y, rtol=1e-9, atol=1e-9)


def test_the_solve_satisfies_the_constrained_dynamics(trackers):
    """``M vdot + h - tau_pas = B tau + J_c^T lambda`` (Pinocchio's RNEA), ``J_c vdot + Jdot_c v = 0``
    and the controlled joints' accelerations as commanded."""
    robot, compiled, _ = trackers
    kin = _kin(robot, np.random.default_rng(1))
    stance = robot.foot_sides[0]
    lay = compiled.layout(stance)
    vdot_cmd = np.random.default_rng(2).normal(0.0, 3.0, len(lay.ctrl_v))
    vdot, tau_c, lam = compiled.solve_dynamics(kin, stance, vdot_cmd)
    Jc, jdv = compiled.constraints(kin, stance)
    tau = np.zeros(robot.nv)
    tau[lay.ctrl_v] = tau_c
    rnea = pin.rnea(robot.pin_model, robot.pin_model.createData(), kin.q, kin.v, vdot)
    residual = rnea - kin.passive_forces() - tau - Jc.T @ lam
    assert np.max(np.abs(residual)) < 1e-8 * max(1.0, np.max(np.abs(rnea)))
    np.testing.assert_allclose(Jc @ vdot + jdv, 0.0, atol=1e-8)
    np.testing.assert_allclose(vdot[lay.ctrl_v], vdot_cmd, atol=1e-9)


def test_each_kinematics_is_read_from_its_own_data(trackers):
    """Bound per Pinocchio data, rebinding one it dropped: in turns on more kinematics objects than
    it keeps bound, each system is its own state's."""
    robot, compiled, python = trackers
    rng = np.random.default_rng(3)
    kins = [_kin(robot, rng) for _ in range(MAX_BINDINGS + 2)]
    stance = robot.foot_sides[1]
    vdot = np.zeros(len(compiled.layout(stance).ctrl_v))
    for _ in range(2):
        for kin in kins:
            for x, y in zip(compiled.solve_dynamics(kin, stance, vdot), python.solve_dynamics(kin, stance, vdot)):
                np.testing.assert_allclose(x, y, rtol=1e-9, atol=1e-9)


def test_kinematics_without_dynamics_is_an_input_error(trackers):
    robot, compiled, _ = trackers
    kin = RobotKinematics(robot)
    kin.update_positions(robot.q_stand)
    stance = robot.foot_sides[0]
    with pytest.raises(InputError, match="update"):
        compiled.solve_dynamics(kin, stance, np.zeros(len(compiled.layout(stance).ctrl_v)))


def test_without_a_compiler_the_tracker_assembles_in_python_with_a_warning(monkeypatch):
    robot = load_robot("rabbit")
    monkeypatch.setenv("AMLIP_QP_CC", "none")
    with pytest.warns(CodegenFallbackWarning, match="Python assembly"):
        tracker = PBCTracker(robot)
    assert tracker.dynamics_backend == "python"
    with pytest.raises(CompilerUnavailableError):
        PBCTracker(robot, compiled_dynamics=True)


@pytest.mark.parametrize("value", ["yes", 1, 0.0])
def test_compiled_dynamics_takes_only_none_true_or_false(value):
    with pytest.raises(InputError, match="compiled_dynamics must be None, True or False"):
        PBCTracker(load_robot("rabbit"), compiled_dynamics=value)
