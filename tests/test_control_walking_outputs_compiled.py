"""The compiled output map equals the Python reference OutputMap, and how a kinematics object gets it."""

import dataclasses

import numpy as np
import pytest

from amlip_qp.control.walking.outputs_compiled import (
    MAX_BINDINGS,
    CompiledOutputMap,
    generate_source,
    make_kinematics,
)
from amlip_qp.exceptions import InputError
from amlip_qp.robots import load_robot
from amlip_qp.robots.kinematics import RobotKinematics
from amlip_qp.robots.outputs import OutputMap
from robot_states import near_stand_q


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


def _kin(robot, rng, update="full"):
    """Kinematics at a random state after ``update``: ``"full"``, ``"kinematics"`` or ``"positions"``."""
    q, v = near_stand_q(robot, rng), rng.normal(0.0, 0.5, robot.nv)
    kin = RobotKinematics(robot)
    if update == "positions":
        kin.update_positions(q)
    elif update == "kinematics":
        kin.update_kinematics(q, v)
    else:
        kin.update(q, v)
    return kin


@pytest.mark.parametrize("update", ["full", "kinematics", "positions"])
def test_compiled_outputs_equal_the_python_map(robot, compiled, update):
    ref = OutputMap(robot)
    assert compiled.names == ref.names and compiled.size == ref.size
    rng = np.random.default_rng(1)
    for i in range(12):
        kin = _kin(robot, rng, update)
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
    fast = RobotKinematics(robot, output_map=compiled)
    assert fast.output_map is compiled
    fast.update(kin.q, kin.v)
    np.testing.assert_allclose(fast.outputs("left", 0.2)[0], y_ref, rtol=0, atol=1e-12)
    other = load_robot("cassie" if robot.name == "rabbit" else "rabbit")
    with pytest.raises(InputError, match="output_map"):
        RobotKinematics(robot, output_map=OutputMap(other))
    with pytest.raises(AttributeError):
        kin.output_map = compiled  # chosen when the object is made, not swapped later


def test_source_depends_on_the_robot_and_its_outputs():
    cassie, rabbit = load_robot("cassie"), load_robot("rabbit")
    assert generate_source(OutputMap(cassie)) != generate_source(OutputMap(rabbit))
    assert generate_source(OutputMap(cassie)) != generate_source(OutputMap(_reordered(cassie)))
    assert generate_source(OutputMap(rabbit)) == generate_source(OutputMap(load_robot("rabbit")))


def test_one_map_reads_each_kinematics_own_pinocchio_data(robot, compiled):
    """The map is bound to each Pinocchio data it is given (the controller's and its IK's), and
    rebinds one it dropped: evaluated in turns on more kinematics objects than it keeps bound,
    each gives its own state's outputs."""
    ref = OutputMap(robot)
    rng = np.random.default_rng(5)
    kins = [_kin(robot, rng, ("full", "kinematics")[i % 2]) for i in range(MAX_BINDINGS + 2)]
    for _ in range(2):
        for i, kin in enumerate(kins):
            stance = robot.foot_sides[i % 2]
            for a, b in zip(ref.evaluate(kin, stance, 0.4), compiled.evaluate(kin, stance, 0.4)):
                np.testing.assert_allclose(b, a, rtol=1e-12, atol=1e-12)


def test_a_position_update_after_a_full_one_gives_zero_drift(robot, compiled):
    """Pinocchio's velocity terms of the earlier update stay in its data; after a position-only
    update (``v = 0``) the drift is zero and the values are those of the new configuration."""
    rng = np.random.default_rng(6)
    kin = _kin(robot, rng, "full")
    assert np.any(compiled.evaluate(kin, "left", 0.0)[2] != 0.0)
    kin.update_positions(near_stand_q(robot, rng))
    y, J, jdv = compiled.evaluate(kin, "left", 0.0)
    y_ref, J_ref, _ = OutputMap(robot).evaluate(kin, "left", 0.0)
    np.testing.assert_array_equal(jdv, np.zeros(compiled.size))
    np.testing.assert_allclose(y, y_ref, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(J, J_ref, rtol=1e-12, atol=1e-12)


def test_make_kinematics_chooses_the_map_and_the_controller_keeps_the_one_it_is_given():
    from amlip_qp.control.walking.controller import WalkingController
    from amlip_qp.control.wbc.tracker import QPTracker

    robot = load_robot("rabbit")
    assert isinstance(make_kinematics(robot).output_map, CompiledOutputMap)
    assert type(make_kinematics(robot, output_backend="python").output_map) is OutputMap
    with pytest.raises(InputError, match="output_backend"):
        make_kinematics(robot, output_backend="fortran")
    own = WalkingController(robot, QPTracker(robot))  # makes its kinematics: the compiled map
    assert isinstance(own.kin.output_map, CompiledOutputMap)
    kin = RobotKinematics(robot)
    given = WalkingController(robot, QPTracker(robot), kin)
    assert given.kin is kin and type(kin.output_map) is OutputMap
    cassie = load_robot("cassie")
    with pytest.raises(InputError, match="output_map must evaluate the outputs"):
        WalkingController(robot, QPTracker(robot), RobotKinematics(cassie))


def test_without_a_compiler_the_controller_makes_the_python_map_with_a_warning(monkeypatch):
    from amlip_qp.codegen.runtime import CodegenFallbackWarning
    from amlip_qp.control.walking.controller import WalkingController
    from amlip_qp.control.wbc.tracker import QPTracker

    robot = load_robot("rabbit")
    tracker = QPTracker(robot)
    monkeypatch.setenv("AMLIP_QP_CC", "none")
    with pytest.warns(CodegenFallbackWarning, match="Python OutputMap") as caught:
        controller = WalkingController(robot, tracker, planner_backend="numpy")
    assert type(controller.kin.output_map) is OutputMap
    fallback = [w for w in caught if issubclass(w.category, CodegenFallbackWarning)]
    assert fallback[0].filename == __file__  # the warning names the line that made the controller
    with pytest.warns(CodegenFallbackWarning, match="Python OutputMap"):
        assert type(make_kinematics(robot).output_map) is OutputMap
