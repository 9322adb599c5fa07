"""Shared helpers of the whole-body QP tests: states, targets, solves (not a test module)."""

from dataclasses import replace

import numpy as np

from amlip_qp.control.tracker import TrackingTarget
from amlip_qp.control.wbc.inputs import swing_force_weight
from amlip_qp.qp.solver import ProxQPSolver
from amlip_qp.robots.kinematics import RobotKinematics

#: The problem's arrays.
FIELDS = ("H", "g", "A", "b", "C", "l", "u", "lb", "ub")

#: ``(robot name, QPConfig changes)`` the compiled builds are checked against the Python build with.
BUILD_CONFIGS = [
    ("cassie", {}),
    ("cassie", {"rigid_springs": "none", "touchdown_blend": 1.0, "stance_yaw_moment_weight": 0.0}),
    ("cassie", {"rigid_springs": "swing", "hip_yaw_feedback": 0.0, "stance_foot_torque_max_Nm": np.inf}),
    ("rabbit", {}),
    ("rabbit", {"touchdown_blend": 0.5, "reg_torque": 0.0}),
]


def kin_at(robot, seed=0, scale=0.02, v_scale=0.2):
    """Kinematics at a random state near the robot's stand pose."""
    rng = np.random.default_rng(seed)
    q = robot.q_stand.copy()
    q[robot.state_map.scalar_pin_q] += rng.normal(0.0, scale, robot.state_map.scalar_pin_q.size)
    v = rng.normal(0.0, v_scale, robot.nv)
    kin = RobotKinematics(robot)
    kin.update(q, v)
    return kin


def target_for(kin, stance="left", phase=0.5, weight=0.0, offset=0.0, heading=0.0):
    """References at the current outputs plus ``offset``, zero rates."""
    y, _, _ = kin.outputs(stance, heading)
    n = y.size
    return TrackingTarget(stance, phase, heading, y + offset, np.zeros(n), np.zeros(n), swing_contact_weight=weight)


def corrected_target(feedback, kin, target):
    """A copy of ``target`` with the swing hip-yaw reference and rate moved by the
    pelvis-yaw ``feedback``'s correction (the reference the feedback stands for)."""
    dh, ddh = feedback.correction(kin, target)
    out = replace(target, h_d=target.h_d.copy(), dh_d=target.dh_d.copy())
    out.h_d[feedback.swing_index] += dh
    out.dh_d[feedback.swing_index] += ddh
    return out


def random_cases(robot, n, seed=0):
    """``(kin, target)`` pairs: both stances, random headings and references, three phases
    (mid-step with the swing forces pinned, the liftoff ramp, late with the pre-touchdown ramp)."""
    rng = np.random.default_rng(seed)
    for i in range(n):
        kin = kin_at(robot, seed=seed * 1000 + i, scale=0.05, v_scale=0.3)
        stance = ("left", "right")[i % 2]
        heading = float(rng.uniform(-1.0, 1.0))
        y, _, _ = kin.outputs(stance, heading)
        m = y.size
        phase, weight = [(0.5, 0.0), (0.02, 0.0), (0.95, 0.5)][i % 3]
        target = TrackingTarget(
            stance, phase, heading, y + rng.normal(0.0, 0.01, m), rng.normal(0.0, 0.1, m), rng.normal(0.0, 1.0, m),
            swing_contact_weight=weight,
        )  # fmt: skip
        yield kin, target


def solve(problem):
    """A tight solve from scratch; the primal solution."""
    return ProxQPSolver(eps_abs=1e-9, warm_start=False, eps_primal_inf=1e-9).solve(problem).x


def build_and_solve(builder, kin, target):
    """``(problem, x)`` of a validated build solved tightly."""
    problem = builder.build(kin, target)
    problem.validate()
    return problem, solve(problem)


def python_build(builder, kin, target):
    """The Python build's problem (a copy) and its row maps ``RD``, ``Rhp`` (copies)."""
    problem = builder.build(kin, target)
    return problem.copy(), builder.dynamics.RD.copy(), builder.dynamics.Rhp.copy()


def assert_same_problem(ref, got, what, rtol=1e-12):
    """The problems' arrays agree: infinities at the same places, finite entries to ``rtol`` (of 1 + |ref|)."""
    for name in FIELDS:
        a, b = getattr(ref, name), getattr(got, name)
        finite = np.isfinite(a)
        assert np.array_equal(finite, np.isfinite(b)), f"{what}: {name} has infinities elsewhere"
        assert np.array_equal(a[~finite], b[~finite]), f"{what}: {name} infinities differ"
        scale = 1.0 + np.abs(a[finite])
        assert np.max(np.abs(a[finite] - b[finite]) / scale, initial=0.0) < rtol, f"{what}: {name}"


def assert_compiled_build_equals_the_python_build(builder, compiled, cases):
    """``compiled.build`` writes every varying entry (the shared arrays poisoned first) and equals the Python build."""
    name = builder.robot.name
    for i, (kin, target) in enumerate(cases):
        ref, RD, Rhp = python_build(builder, kin, target)
        P, dyn = builder.problem, builder.dynamics
        for arr in (P.H, P.g, P.A, P.b, P.lb, P.ub, P.l[builder.constraint("torque").rows], P.u, dyn.RD, dyn.Rhp):
            arr[...] = np.nan
        builder.inputs.swing_force_weight = np.nan
        got = compiled.build(kin, target)
        assert got is builder.problem
        assert_same_problem(ref, got, f"{name} state {i} ({target.stance}, phase {target.phase})")
        assert np.max(np.abs(dyn.RD - RD) / (1.0 + np.abs(RD))) < 1e-12
        assert np.max(np.abs(dyn.Rhp - Rhp) / (1.0 + np.abs(Rhp))) < 1e-12
        # The recovery maps read the same buffers.
        x = np.random.default_rng(i).normal(0.0, 10.0, builder.n_variables)
        rows = slice(dyn.elimination.n_dyn, dyn.elimination.n_dyn + dyn.T.shape[0])
        assert np.allclose(builder.torques(x), RD[rows] @ x + Rhp[rows])
        assert builder.inputs.swing_force_weight == swing_force_weight(builder.config, target)
