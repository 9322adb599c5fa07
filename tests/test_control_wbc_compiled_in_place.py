"""The in-place compiled assembly (amlip_qp.control.wbc.compiled_in_place) against the Python build."""

from dataclasses import replace

import numpy as np
import pytest

from amlip_qp.control.wbc.builder import WholeBodyQP
from amlip_qp.control.wbc.compiled import assembly_function
from amlip_qp.control.wbc.compiled_in_place import InPlaceBuild, tick_function
from amlip_qp.control.wbc.compiled_in_place import frame_terms as make_frame_terms
from amlip_qp.control.wbc.config import default_config
from amlip_qp.control.wbc.tracker import QPTracker
from amlip_qp.exceptions import InputError
from amlip_qp.robots import load_robot
from amlip_qp.robots.kinematics import RobotKinematics
from amlip_qp.robots.outputs import OutputMap, computes_standard_outputs
from wbc_cases import (
    BUILD_CONFIGS,
    assert_compiled_build_equals_the_python_build,
    assert_same_problem,
    python_build,
    random_cases,
)


@pytest.mark.parametrize(
    "name, changes",
    BUILD_CONFIGS,
)
def test_the_in_place_build_equals_the_python_build(name, changes):
    robot = load_robot(name)
    builder = WholeBodyQP(robot, default_config(robot).with_(**changes))
    assert_compiled_build_equals_the_python_build(builder, InPlaceBuild(builder), random_cases(robot, 8))


@pytest.mark.parametrize("name", ["cassie", "rabbit"])
def test_one_kinematics_updated_again_and_again_stays_bound(name):
    """The bound views follow every update of the same kinematics (Pinocchio overwrites its arrays in place)."""
    robot = load_robot(name)
    builder = WholeBodyQP(robot)
    compiled = InPlaceBuild(builder)
    kin = RobotKinematics(robot)
    for i, (other, target) in enumerate(random_cases(robot, 6, seed=8)):
        kin.update(other.q, other.v)
        ref = python_build(builder, kin, target)[0]
        kin.update(other.q, other.v)  # a fresh update, as in the walking loop
        assert_same_problem(ref, compiled.build(kin, target), f"{name} update {i}")


@pytest.mark.parametrize("name", ["cassie", "rabbit"])
def test_it_returns_the_outputs_it_computes_and_leaves_the_kinematics_alone(name):
    """It keeps h_0's (y, J, Jdot v) of the tick in ``outputs`` (the output map's, to rounding, on
    each kinematics after a rebinding to another one's data, and back) and does not put them into the
    kinematics: the first ``kin.outputs`` after a build asks the kinematics' own output map."""
    robot = load_robot(name)
    compiled = InPlaceBuild(WholeBodyQP(robot))
    assert compiled.outputs is None
    calls = []

    class Counted(OutputMap):
        standard_outputs = True

        def evaluate(self, kin, stance, heading_rad=0.0):
            calls.append(stance)
            return super().evaluate(kin, stance, heading_rad)

    cases = [(RobotKinematics(robot, output_map=Counted(robot)), other, target)
             for other, target in random_cases(robot, 4, seed=5)]  # fmt: skip
    for kin, other, target in cases + cases[:2]:
        kin.update(other.q, other.v)  # no cached outputs
        compiled.build(kin, target)
        got = compiled.outputs
        assert got is not None and calls == []  # the build did not ask the kinematics' output map
        want = kin.outputs(target.stance, target.heading_rad)
        assert calls == [target.stance]  # nothing was cached in the kinematics: its own map evaluated them
        calls.clear()
        for a, b in zip(got, want):
            np.testing.assert_allclose(a, b, rtol=0, atol=1e-12)
        previous = got
        compiled.build(kin, target)
        assert all(x is not y for x, y in zip(compiled.outputs, previous))  # new arrays each build


def test_a_subclass_of_the_output_map_is_a_drop_in_unless_it_says_otherwise():
    robot = load_robot("rabbit")

    class Sub(OutputMap):
        pass

    class Standard(OutputMap):
        standard_outputs = True

    assert computes_standard_outputs(OutputMap(robot)) and computes_standard_outputs(Standard(robot))
    assert not computes_standard_outputs(Sub(robot)) and not computes_standard_outputs(object())


def test_a_drop_in_output_map_gets_the_python_build():
    """Only the Python build reads a drop-in output map (the generated code computes the standard h_0)."""
    robot = load_robot("rabbit")
    builder = WholeBodyQP(robot)
    compiled = InPlaceBuild(builder)
    calls = []

    class Shifted:  # a drop-in: the standard names, other values
        def __init__(self):
            self.names = OutputMap(robot).names
            self.inner = OutputMap(robot)

        def evaluate(self, kin, stance, heading_rad=0.0):
            calls.append(stance)
            y, J, jdv = self.inner.evaluate(kin, stance, heading_rad)
            return y + 0.1, J, jdv

    kin, target = next(random_cases(robot, 1, seed=6))
    q, v = kin.q.copy(), kin.v.copy()
    shifted = RobotKinematics(robot, output_map=Shifted())
    shifted.update(q, v)
    got = compiled.build(shifted, target).copy()
    assert calls and compiled.outputs is None  # the Python build asked the drop-in
    kin.update(q, v)
    standard = compiled.build(kin, target)
    assert len(calls) == 1 and not np.allclose(got.g, standard.g)  # the drop-in's outputs moved the cost
    assert_same_problem(python_build(builder, kin, target)[0], standard, "standard map")


def test_a_kinematics_without_dynamics_or_a_bad_stance_is_an_input_error():
    robot = load_robot("rabbit")
    compiled = InPlaceBuild(WholeBodyQP(robot))
    kin, target = next(random_cases(robot, 1, seed=7))
    light = RobotKinematics(robot)
    light.update_positions(kin.q)
    with pytest.raises(InputError, match="dynamics"):
        compiled.build(light, target)
    with pytest.raises(InputError, match="heading_rad must be finite"):
        compiled.build(kin, replace(target, heading_rad=float("nan")))
    target.stance = "up"
    with pytest.raises(InputError, match="stance"):
        compiled.build(kin, target)


def test_the_functions_take_pinocchios_arrays_and_give_the_assembly_and_the_outputs():
    robot = load_robot("cassie")
    builder = WholeBodyQP(robot)
    terms = make_frame_terms(builder)
    fn = tick_function(builder, "left", terms)
    names_in = [fn.name_in(i) for i in range(fn.n_in())]
    assert names_in == ["M_upper", "nle", *(n for n, _ in terms.symbols), "small"]
    assert fn.name() == "wbqp_in_place_left" != assembly_function(builder, "left").name()  # no symbol clash
    names_out = [fn.name_out(i) for i in range(fn.n_out())]
    assert names_out[-3:] == ["y", "JyT", "jdv"] and "ET" in names_out and "Rhp" in names_out


def test_the_default_tracker_gives_the_same_torques_as_the_python_build():
    robot = load_robot("cassie")
    opts = {"eps_abs": 1e-9, "warm_start": False}
    fast, slow = QPTracker(robot, **opts), QPTracker(robot, compiled_build=False, **opts)
    assert fast.build_backend == "c-in-place" == QPTracker(robot, in_place_assembly=True).build_backend
    for kin, target in random_cases(robot, 6, seed=3):
        a, b = fast.compute(kin, target), slow.compute(kin, target)
        assert a.ok and b.ok
        np.testing.assert_allclose(a.tau_Nm, b.tau_Nm, atol=1e-6)
    for falsy in (False, 0):  # a falsy compiled_build is the Python build, with which True is refused
        with pytest.raises(InputError, match="in_place_assembly"):
            QPTracker(robot, in_place_assembly=True, compiled_build=falsy)  # type: ignore[arg-type]
    with pytest.raises(InputError, match="in_place_assembly"):
        QPTracker(robot, in_place_assembly="yes")


@pytest.mark.parametrize("name", ["h1", "g1"])
def test_the_in_place_build_of_a_four_point_sole_equals_the_python_build(name, tmp_path):
    """The four-point humanoids (tests/sole_cases.py): the in-place build reads the sole line's
    midpoint frames for the swing foot's pitch besides the four force frames."""
    from sole_cases import sole_profile

    robot = load_robot(sole_profile(name, tmp_path))
    builder = WholeBodyQP(robot, default_config(robot))
    assert_compiled_build_equals_the_python_build(builder, InPlaceBuild(builder), random_cases(robot, 8))


def _assert_leading_block(small, full, label):
    """``small`` is ``full``'s leading block (its variables and rows), bit for bit."""
    n, m = small.n, small.n_in
    pairs = {
        "H": (small.H, full.H[:n, :n]), "g": (small.g, full.g[:n]), "A": (small.A, full.A[:, :n]),
        "b": (small.b, full.b), "C": (small.C, full.C[:m, :n]), "l": (small.l, full.l[:m]),
        "u": (small.u, full.u[:m]), "lb": (small.lb, full.lb[:n]), "ub": (small.ub, full.ub[:n]),
    }  # fmt: skip
    for key, (a, b) in pairs.items():
        assert np.array_equal(a, b), f"{label}: {key}"


@pytest.mark.parametrize("name", ["cassie", "rabbit"])
def test_the_airborne_problem_is_the_full_problems_leading_block_bit_for_bit(name):
    """With ``airborne=True`` a build with the swing foot in the air (force ramp 0) returns the
    problem without its forces and friction rows, written by the same generated C as the full
    problem's entries: the same bits as the leading block of the full build; with the ramp up,
    the full problem as before. The stance pyramid turned to the ground is copied across."""
    from amlip_qp.control.wbc.compiled_in_place import airborne_dims

    robot = load_robot(name)
    air_builder, full_builder = WholeBodyQP(robot), WholeBodyQP(robot)
    air, full = InPlaceBuild(air_builder, airborne=True), InPlaceBuild(full_builder)
    dims = airborne_dims(air_builder)
    assert dims is not None and air.airborne_problem is not None and full.airborne_problem is None
    assert (air.airborne_problem.n, air.airborne_problem.n_in) == dims
    assert dims[0] < air_builder.problem.n and dims[1] < air_builder.problem.n_in
    friction = air_builder.constraint("friction")
    kinds = set()
    for i, (kin, target) in enumerate(random_cases(robot, 6, seed=5)):
        if i == 3 and not robot.is_planar:  # the stance pyramid turned to a 20-degree flank, in both builders
            for b in (air_builder, full_builder):
                b.constraint("friction").tilt_stance_rows(b.problem, 0.35, target.heading_rad)
            air.copy_constant_rows()
        p_full = full.build(kin, target)
        p_air = air.build(kin, target)
        if air_builder.inputs.swing_force_weight == 0.0:
            kinds.add("airborne")
            assert p_air is air.airborne_problem
            _assert_leading_block(p_air, p_full, f"{name} case {i}")
            assert dict(p_air.in_rows)["friction"].stop == dims[1] == friction.swing_rows.start
        else:
            kinds.add("loaded")
            assert p_air is air_builder.problem
            assert_same_problem(p_full, p_air, f"{name} case {i}")
    assert kinds == {"airborne", "loaded"}
