"""The IK's evaluation by generated C reading Pinocchio in place gives the Python reference's bits, and
so do the IK's solves."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from amlip_qp.codegen.runtime import CodegenFallbackWarning
from amlip_qp.control.pbc.ik import IterativeIK
from amlip_qp.control.pbc.ik_compiled import MAX_BINDINGS
from amlip_qp.control.pbc.tracker import PBCTracker
from amlip_qp.control.walking.outputs_compiled import make_kinematics
from amlip_qp.exceptions import CompilerUnavailableError, InputError
from amlip_qp.robots import load_robot
from amlip_qp.robots.kinematics import RobotKinematics
from amlip_qp.robots.outputs import OutputMap
from robot_states import near_stand_q


@pytest.fixture(scope="module", params=["cassie", "rabbit", "g1"])
def iks(request):
    """``(robot, compiled IK, Python IK)``: Cassie's blade, Rabbit's planar point foot, G1's humanoid."""
    robot = load_robot(request.param)
    return robot, IterativeIK(robot, compiled=True), IterativeIK(robot, compiled=False)


def _estimate(robot, rng) -> RobotKinematics:
    """The controller's kinematics (the generated output map, as the walking controller makes it) at
    a state near the stand pose."""
    kin = make_kinematics(robot)
    kin.update(near_stand_q(robot, rng), rng.normal(0.0, 0.5, robot.nv))
    return kin


def _adopt(robot, *iks) -> None:
    """One solve on the controller's kinematics: the IKs evaluate its output map from then on."""
    kin = _estimate(robot, np.random.default_rng(9))
    stance = robot.foot_sides[0]
    y, _, _ = kin.outputs(stance, 0.0)
    for ik in iks:
        ik.solve(kin, stance, 0.0, y, np.zeros(ik.size), np.zeros(ik.size))


def test_the_compiled_evaluation_gives_the_python_bits(iks):
    """``A``'s varying rows, the residual, the drift, the outputs and the residual re-formed from the
    kept evaluation with new targets, at iterates off the estimate: the same bits (a rounding
    difference would change the outcome of chaotic walks)."""
    robot, compiled, python = iks
    _adopt(robot, compiled, python)
    assert compiled.evaluation_backend == "c-in-place" and python.evaluation_backend == "python"
    rng = np.random.default_rng(2)
    n = compiled.size
    for i in range(8):
        kin = _estimate(robot, rng)
        stance = robot.foot_sides[i % 2]
        fixed = compiled.equations.held_quantities(kin, stance)
        h_d = rng.normal(0.0, 0.1, n)
        q = pin.integrate(robot.pin_model, kin.q, rng.normal(0.0, 0.05, robot.nv))
        v = rng.normal(0.0, 0.5, robot.nv)
        got, want = [], []
        for ik, out in ((compiled, got), (python, want)):
            ev = ik.evaluation
            ev.set_targets(stance, h_d, fixed)
            out.append(ev.evaluate(ik.kin, stance, q, 0.4, v).copy())
            out.append(ik.equations.rows[stance].A.copy())
            out.append(ev.drift(ik.kin, stance, 0.4).copy())
            out.append(ev.y.copy())
            ev.keep(stance)
            ev.evaluate(ik.kin, stance, robot.q_stand, 0.0)  # another iterate in between
            ev.set_targets(stance, h_d + 0.01, fixed)
            out.append(ev.kept_residual(stance, q).copy())
        for name, a, b in zip(("F", "A", "drift", "y", "kept F"), got, want):
            assert np.array_equal(a, b), f"{name} differs (state {i}, {stance})"


def test_the_compiled_ik_solves_as_the_python_one(iks):
    """A cold solve, then warm ticks with moving targets: the same references, bit for bit."""
    robot, compiled, python = iks
    _adopt(robot, compiled, python)
    rng = np.random.default_rng(3)
    kin = _estimate(robot, rng)
    stance = robot.foot_sides[0]
    h0, _, _ = kin.outputs(stance, 0.1)
    compiled.reset()
    python.reset()
    for k in range(6):
        h_d = h0 + 0.002 * k
        dh_d = np.full(compiled.size, 0.05)
        ddh_d = np.full(compiled.size, 0.3)
        a = compiled.solve(kin, stance, 0.1, h_d, dh_d, ddh_d)
        b = python.solve(kin, stance, 0.1, h_d, dh_d, ddh_d)
        assert a.ok and b.ok and a.iterations == b.iterations
        for x, y in ((a.q_r, b.q_r), (a.v_r, b.v_r), (a.a_r, b.a_r)):
            np.testing.assert_array_equal(x, y)


def test_each_kinematics_is_read_from_its_own_data(iks):
    """Bound per Pinocchio data: on more IK kinematics than it keeps bound, in turns, each
    evaluation is its own iterate's."""
    robot, compiled, python = iks
    _adopt(robot, compiled, python)
    rng = np.random.default_rng(4)
    kin = _estimate(robot, rng)
    stance = robot.foot_sides[1]
    fixed = compiled.equations.held_quantities(kin, stance)
    h_d = np.zeros(compiled.size)
    kins = [RobotKinematics(robot) for _ in range(MAX_BINDINGS + 2)]
    qs = [near_stand_q(robot, rng) for _ in kins]
    compiled.evaluation.set_targets(stance, h_d, fixed)
    python.evaluation.set_targets(stance, h_d, fixed)
    for _ in range(2):
        for k, q in zip(kins, qs):
            F = compiled.evaluation.evaluate(k, stance, q, 0.0).copy()
            np.testing.assert_array_equal(F, python.evaluation.evaluate(python.kin, stance, q, 0.0))


def test_a_custom_output_map_is_evaluated_in_python():
    """Kinematics whose output map is not the robot's standard ``h_0`` are evaluated by Pinocchio's
    getters and that map (the generated C knows only the standard outputs)."""

    class Shifted(OutputMap):
        def evaluate(self, kin, stance, heading_rad=0.0):
            y, J, jdv = super().evaluate(kin, stance, heading_rad)
            return y + 0.01, J, jdv

    robot = load_robot("rabbit")
    ik = IterativeIK(robot, compiled=True)
    kin = RobotKinematics(robot, Shifted(robot))
    kin.update(robot.q_stand, np.zeros(robot.nv))
    stance = robot.foot_sides[0]
    h_d, _, _ = kin.outputs(stance, 0.0)
    res = ik.solve(kin, stance, 0.0, h_d, np.zeros(ik.size), np.zeros(ik.size))
    assert ik.evaluation_backend == "python"
    assert res.ok and res.residual < 1e-6
    np.testing.assert_allclose(res.q_r, kin.q, atol=1e-6)  # the shifted map's own h_d is the estimate


def test_without_a_compiler_the_ik_evaluates_in_python_with_a_warning(monkeypatch):
    robot = load_robot("rabbit")
    monkeypatch.setenv("AMLIP_QP_CC", "none")
    with pytest.warns(CodegenFallbackWarning, match="IterativeIK"):
        ik = IterativeIK(robot)
    assert ik.evaluation_backend == "python"
    with pytest.raises(CompilerUnavailableError):
        IterativeIK(robot, compiled=True)


@pytest.mark.parametrize("value", ["yes", 1, 0.0])
def test_compiled_takes_only_none_true_or_false(value):
    robot = load_robot("rabbit")
    with pytest.raises(InputError, match="compiled must be None, True or False"):
        IterativeIK(robot, compiled=value)
    with pytest.raises(InputError, match="compiled_ik must be None, True or False"):
        PBCTracker(robot, compiled_ik=value)


def test_the_pbc_tracker_evaluates_its_ik_in_c_by_default():
    robot = load_robot("rabbit")
    assert PBCTracker(robot).ik.evaluation_backend == "c-in-place"
    assert PBCTracker(robot, compiled_ik=False).ik.evaluation_backend == "python"
