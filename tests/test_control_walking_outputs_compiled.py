"""The compiled output map equals the Python reference OutputMap, and how it is installed."""

import dataclasses

import numpy as np
import pytest

from amlip_qp.control.walking.outputs_compiled import CompiledOutputMap, generate_source
from amlip_qp.exceptions import InputError
from amlip_qp.robots import load_robot
from amlip_qp.robots.kinematics import RobotKinematics
from amlip_qp.robots.outputs import OutputMap


def _reordered(robot):
    """``robot`` with its outputs declared in reverse order."""
    names = tuple(reversed(robot.profile.outputs))
    return dataclasses.replace(robot, profile=dataclasses.replace(robot.profile, outputs=names))


@pytest.fixture(scope="module", params=["cassie", "rabbit", "g1", "g1 reordered"])
def robot(request):
    if request.param == "g1 reordered":
        return _reordered(load_robot("g1"))
    return load_robot(request.param)


@pytest.fixture(scope="module")
def compiled(robot):
    return CompiledOutputMap(robot)


def _kin(robot, rng, positions_only=False):
    q = robot.q_stand.copy()
    q[robot.state_map.scalar_pin_q] += rng.normal(0.0, 0.1, robot.state_map.scalar_pin_q.size)
    if robot.is_floating:
        quat = rng.normal(0.0, 0.2, 4)
        quat[3] += 1.0
        q[3:7] = quat / np.linalg.norm(quat)
    kin = RobotKinematics(robot)
    if positions_only:
        kin.update_positions(q)
    else:
        kin.update(q, rng.normal(0.0, 0.5, robot.nv))
    return kin


@pytest.mark.parametrize("positions_only", [False, True])
def test_compiled_outputs_equal_the_python_map(robot, compiled, positions_only):
    ref = OutputMap(robot)
    assert compiled.names == ref.names and compiled.size == ref.size
    rng = np.random.default_rng(1)
    for i in range(12):
        kin = _kin(robot, rng, positions_only)
        stance, heading = ("left", "right")[i % 2], float(rng.uniform(-3.0, 3.0))
        for a, b, what in zip(
            ref.evaluate(kin, stance, heading), compiled.evaluate(kin, stance, heading), ("y", "J", "Jdot_v")
        ):
            assert a.shape == b.shape
            assert np.max(np.abs(a - b) / (1.0 + np.abs(a))) < 1e-12, f"{what} differs (state {i}, {stance})"


def test_results_are_fresh_arrays(robot, compiled):
    kin = _kin(robot, np.random.default_rng(2))
    y1, J1, d1 = compiled.evaluate(kin, "left", 0.0)
    y2, J2, d2 = compiled.evaluate(kin, "right", 0.5)
    assert y1 is not y2 and J1 is not J2 and d1 is not d2
    assert not np.allclose(y1, y2)


def test_bad_side_and_heading_are_input_errors(robot, compiled):
    kin = _kin(robot, np.random.default_rng(3))
    with pytest.raises(InputError, match="stance"):
        compiled.evaluate(kin, "up", 0.0)
    with pytest.raises(InputError, match="heading"):
        compiled.evaluate(kin, "left", float("nan"))


def test_kinematics_takes_a_drop_in_map_and_rejects_a_wrong_one(robot, compiled):
    kin = _kin(robot, np.random.default_rng(4))
    y_ref = kin.outputs("left", 0.2)[0].copy()
    kin.output_map = compiled
    assert kin.output_map is compiled
    np.testing.assert_allclose(kin.outputs("left", 0.2)[0], y_ref, rtol=0, atol=1e-12)
    other = load_robot("cassie" if robot.name == "rabbit" else "rabbit")
    with pytest.raises(InputError, match="output_map"):
        kin.output_map = OutputMap(other)


def test_source_depends_on_the_outputs_only():
    cassie, rabbit = load_robot("cassie"), load_robot("rabbit")
    assert generate_source(OutputMap(cassie)) != generate_source(OutputMap(rabbit))
    assert generate_source(OutputMap(cassie)) != generate_source(OutputMap(_reordered(cassie)))
    assert generate_source(OutputMap(rabbit)) == generate_source(OutputMap(load_robot("rabbit")))


def test_controller_installs_the_compiled_map_unless_told_otherwise():
    from amlip_qp.control.walking.controller import WalkingController
    from amlip_qp.control.wbc.tracker import QPTracker

    robot = load_robot("rabbit")
    kin = RobotKinematics(robot)
    WalkingController(robot, QPTracker(robot), kin)
    assert isinstance(kin.output_map, CompiledOutputMap)
    kin = RobotKinematics(robot)
    WalkingController(robot, QPTracker(robot), kin, output_backend="python")
    assert type(kin.output_map) is OutputMap
    with pytest.raises(InputError, match="output_backend"):
        WalkingController(robot, QPTracker(robot), kin, output_backend="fortran")


def test_without_a_compiler_the_controller_keeps_the_python_map(monkeypatch):
    from amlip_qp.codegen.runtime import CodegenFallbackWarning
    from amlip_qp.control.walking.controller import WalkingController
    from amlip_qp.control.wbc.tracker import QPTracker

    robot = load_robot("rabbit")
    tracker = QPTracker(robot)
    monkeypatch.setenv("AMLIP_QP_CC", "none")
    kin = RobotKinematics(robot)
    with pytest.warns(CodegenFallbackWarning, match="Python OutputMap"):
        WalkingController(robot, tracker, kin, planner_backend="numpy")
    assert type(kin.output_map) is OutputMap
