"""The compiled QP assembly equals the Python reference build, and its fallbacks."""

import warnings

import numpy as np
import pytest

from amlip_qp.codegen.runtime import CodegenFallbackWarning
from amlip_qp.control.wbc.builder import WholeBodyQP
from amlip_qp.control.wbc.compiled import FUNCTION_STEM, CompiledBuild, assembly_function, generate_source
from amlip_qp.control.wbc.config import default_config
from amlip_qp.control.wbc.tracker import QPTracker
from amlip_qp.exceptions import CompilerUnavailableError, InputError
from amlip_qp.robots import load_robot
from wbc_cases import BUILD_CONFIGS, assert_compiled_build_equals_the_python_build, random_cases


@pytest.mark.parametrize(
    "name, changes",
    BUILD_CONFIGS,
)
def test_compiled_build_equals_the_python_build(name, changes):
    robot = load_robot(name)
    builder = WholeBodyQP(robot, default_config(robot).with_(**changes))
    assert_compiled_build_equals_the_python_build(builder, CompiledBuild(builder), random_cases(robot, 8))


def test_the_functions_follow_the_constraint_and_cost_lists():
    robot = load_robot("cassie")
    builder = WholeBodyQP(robot)
    fn = assembly_function(builder, "left")
    assert fn.name() == f"{FUNCTION_STEM}_left"
    assert [fn.name_in(i) for i in range(fn.n_in())] == ["M_upper", "hp", "JfT", "JoT", "packed"]
    sizes = {fn.name_out(i): fn.size_out(i) for i in range(fn.n_out())}
    P = builder.problem
    assert sizes["AT"] == (P.n, P.n_eq) and sizes["u_in"] == (P.n_in, 1) and sizes["lb"] == (P.n, 1)
    torque = builder.constraint("torque")
    assert sizes["TT"] == (P.n, torque.size) and sizes["l_tau"] == (torque.size, 1)
    # E: the numpy build's rows plus the yaw moment's one row.
    assert sizes["ET"] == (P.n, sum(c.size for c in builder.costs) + 1)


def test_source_bakes_in_the_robot_and_the_config():
    robot = load_robot("rabbit")
    a, _ = generate_source(WholeBodyQP(robot))
    b, _ = generate_source(WholeBodyQP(robot))
    c, _ = generate_source(WholeBodyQP(robot, default_config(robot).with_(friction_mu=0.5)))
    assert a == b and a != c


def test_tracker_uses_the_compiled_build_and_falls_back_without_a_compiler(monkeypatch):
    robot = load_robot("rabbit")
    assert QPTracker(robot).build_backend == "c-in-place"  # the default: the in-place compiled build
    assert QPTracker(robot, in_place_assembly=False).build_backend == "c"
    assert QPTracker(robot, in_place_assembly=0).build_backend == "c"  # falsy as False, not as None
    assert QPTracker(robot, compiled_build=False).build_backend == "python"
    with pytest.raises(InputError, match="compiled_build"):
        QPTracker(robot, compiled_build="yes")
    monkeypatch.setenv("AMLIP_QP_CC", "none")
    with pytest.warns(CodegenFallbackWarning, match="Python build"):
        tracker = QPTracker(robot)
    assert tracker.build_backend == "python"
    with pytest.raises(CompilerUnavailableError, match="AMLIP_QP_CC=none"):
        QPTracker(robot, compiled_build=True)
    with pytest.raises(CompilerUnavailableError, match="AMLIP_QP_CC=none"):
        CompiledBuild(WholeBodyQP(robot))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert QPTracker(robot, compiled_build=False).build_backend == "python"


def test_compiled_and_python_trackers_give_the_same_torques():
    robot = load_robot("cassie")
    # Solved tightly from scratch: at the tracker's eps_abs 1e-3 a degenerate
    # direction (the stance toe's +-0.01 N m band) may end anywhere within tolerance.
    opts = {"eps_abs": 1e-9, "warm_start": False}
    fast, slow = QPTracker(robot, in_place_assembly=False, **opts), QPTracker(robot, compiled_build=False, **opts)
    assert fast.build_backend == "c"
    for kin, target in random_cases(robot, 6, seed=3):
        a, b = fast.compute(kin, target), slow.compute(kin, target)
        assert a.ok and b.ok
        np.testing.assert_allclose(a.tau_Nm, b.tau_Nm, atol=1e-6)
        assert a.info["swing_force_weight"] == b.info["swing_force_weight"]


def test_a_four_point_sole_compiles_to_the_python_build(tmp_path):
    """H1 with its sole's four corners (tests/sole_cases.py): 6 contact rows, 4 friction pyramids per
    foot, the yaw moment over 8 force entries; the generated build gives the numpy problem to 1e-12."""
    from sole_cases import sole_profile

    robot = load_robot(sole_profile("h1", tmp_path))
    builder = WholeBodyQP(robot, default_config(robot))
    assert_compiled_build_equals_the_python_build(builder, CompiledBuild(builder), random_cases(robot, 8))
