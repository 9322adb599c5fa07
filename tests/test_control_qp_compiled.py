"""The compiled QP assembly equals the Python reference build, and its fallbacks."""

import warnings

import numpy as np
import pytest

from amlip_qp.codegen.runtime import CodegenFallbackWarning
from amlip_qp.control.qp_compiled import CompiledBuild, generate_source
from amlip_qp.control.qp_formulation import WholeBodyQP, default_config
from amlip_qp.control.qp_tracker import QPTracker
from amlip_qp.control.tracker import TrackingTarget
from amlip_qp.exceptions import CompilerUnavailableError, InputError
from amlip_qp.robots import load_robot
from amlip_qp.robots.kinematics import RobotKinematics

FIELDS = ("H", "g", "A", "b", "C", "l", "u", "lb", "ub")


def _states(robot, n, seed=0):
    rng = np.random.default_rng(seed)
    for i in range(n):
        q = robot.q_stand.copy()
        q[robot.state_map.scalar_pin_q] += rng.normal(0.0, 0.05, robot.state_map.scalar_pin_q.size)
        v = rng.normal(0.0, 0.3, robot.nv)
        kin = RobotKinematics(robot)
        kin.update(q, v)
        stance = ("left", "right")[i % 2]
        heading = float(rng.uniform(-1.0, 1.0))
        y, _, _ = kin.outputs(stance, heading)
        m = y.size
        # Phases: mid-step (swing forces pinned), liftoff ramp, late step with the pre-touchdown ramp.
        phase, weight = [(0.5, 0.0), (0.02, 0.0), (0.95, 0.5)][i % 3]
        target = TrackingTarget(
            stance, phase, heading, y + rng.normal(0.0, 0.01, m), rng.normal(0.0, 0.1, m), rng.normal(0.0, 1.0, m),
            swing_contact_weight=weight,
        )  # fmt: skip
        yield kin, target


def _python(builder, kin, target):
    problem = builder.build(kin, target)
    builder.limit_stance_foot_torque(problem, target)
    builder.add_stance_yaw_moment_cost(problem, kin, target)
    return problem.copy(), builder._RD.copy(), builder._Rhp.copy()


def _assert_same(ref, got, what):
    for name in FIELDS:
        a, b = getattr(ref, name), getattr(got, name)
        finite = np.isfinite(a)
        assert np.array_equal(finite, np.isfinite(b)), f"{what}: {name} has infinities elsewhere"
        assert np.array_equal(a[~finite], b[~finite]), f"{what}: {name} infinities differ"
        scale = 1.0 + np.abs(a[finite])
        assert np.max(np.abs(a[finite] - b[finite]) / scale, initial=0.0) < 1e-12, f"{what}: {name}"


@pytest.mark.parametrize(
    "name, changes",
    [
        ("cassie", {}),
        ("cassie", {"rigid_springs": "none", "touchdown_blend": 1.0, "stance_yaw_moment_weight": 0.0}),
        ("rabbit", {}),
        ("rabbit", {"touchdown_blend": 0.5}),
    ],
)
def test_compiled_build_equals_the_python_build(name, changes):
    robot = load_robot(name)
    builder = WholeBodyQP(robot, default_config(robot).with_(**changes))
    compiled = CompiledBuild(builder)
    for i, (kin, target) in enumerate(_states(robot, 8)):
        ref, RD, Rhp = _python(builder, kin, target)
        # Poison the shared arrays: the compiled build must write every varying entry.
        for arr in (builder.problem.H, builder.problem.g, builder.problem.A, builder.problem.b, builder._RD):
            arr[...] = np.nan
        got = compiled.build(kin, target)
        assert got is builder.problem
        _assert_same(ref, got, f"{name} state {i} ({target.stance}, phase {target.phase})")
        assert np.max(np.abs(builder._RD - RD) / (1.0 + np.abs(RD))) < 1e-12
        assert np.max(np.abs(builder._Rhp - Rhp) / (1.0 + np.abs(Rhp))) < 1e-12
        # The recovery maps read the same buffers.
        x = np.random.default_rng(i).normal(0.0, 10.0, builder.n_variables)
        tau = builder.torques(x)
        assert np.allclose(tau, RD[builder._sl_dyn.stop : builder._sl_dyn.stop + tau.size] @ x + Rhp[builder._sl_dyn.stop : builder._sl_dyn.stop + tau.size])
        assert builder._last_force_weight == builder.swing_force_weight(target)


def test_source_bakes_in_the_robot_and_the_config():
    robot = load_robot("rabbit")
    a, _ = generate_source(WholeBodyQP(robot))
    b, _ = generate_source(WholeBodyQP(robot))
    c, _ = generate_source(WholeBodyQP(robot, default_config(robot).with_(friction_mu=0.5)))
    assert a == b and a != c


def test_tracker_uses_the_compiled_build_and_falls_back_without_a_compiler(monkeypatch):
    robot = load_robot("rabbit")
    assert QPTracker(robot).build_backend == "c"
    assert QPTracker(robot, compiled_build=False).build_backend == "python"
    with pytest.raises(InputError, match="compiled_build"):
        QPTracker(robot, compiled_build="yes")
    monkeypatch.setenv("AMLIP_QP_CC", "none")
    with pytest.warns(CodegenFallbackWarning, match="Python build"):
        tracker = QPTracker(robot)
    assert tracker.build_backend == "python"
    with pytest.raises(CompilerUnavailableError, match="AMLIP_QP_CC=none"):
        QPTracker(robot, compiled_build=True)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert QPTracker(robot, compiled_build=False).build_backend == "python"


def test_compiled_and_python_trackers_give_the_same_torques():
    robot = load_robot("cassie")
    # Solved tightly from scratch: at the tracker's eps_abs 1e-3 a degenerate
    # direction (the stance toe's +-0.01 N m band) may end anywhere within tolerance.
    opts = {"eps_abs": 1e-9, "warm_start": False}
    fast, slow = QPTracker(robot, **opts), QPTracker(robot, compiled_build=False, **opts)
    assert fast.build_backend == "c"
    for kin, target in _states(robot, 6, seed=3):
        a, b = fast.compute(kin, target), slow.compute(kin, target)
        assert a.ok and b.ok
        np.testing.assert_allclose(a.tau_Nm, b.tau_Nm, atol=1e-6)
