"""Tests of the passive forces as a CasADi expression (amlip_qp.control.passive_symbolic)."""

from __future__ import annotations

import casadi as ca
import mujoco
import numpy as np
import pytest

from amlip_qp.control.passive_symbolic import passive_forces_expression
from amlip_qp.robots import load_robot
from amlip_qp.robots.passive import PassiveForces


def _function(robot):
    q, v = ca.MX.sym("q", robot.nq), ca.MX.sym("v", robot.nv)
    return ca.Function("taup", [q, v], [passive_forces_expression(robot, q, v)]).expand()


def _rabbit_with_springs_and_a_dead_band_tendon(tmp_path):
    spec = mujoco.MjSpec.from_file(str(load_robot("rabbit").path))
    for name, k, ref, b in (("left-knee", 80.0, 0.3, 1.5), ("right-hip", 20.0, -0.2, 0.7), ("root-x", 0.0, 0.0, 2.0)):
        j = spec.joint(name)
        j.stiffness, j.springref, j.damping = [k, 0, 0], ref, [b, 0, 0]
    t = spec.add_tendon(name="coupler", stiffness=[300.0, 0, 0], damping=[3.0, 0, 0], springlength=[0.1, 0.4])
    t.wrap_joint("left-hip", 1.0)
    t.wrap_joint("right-knee", -0.5)
    path = tmp_path / "rabbit_springs.xml"
    path.write_text(spec.to_xml())
    return load_robot(path)


@pytest.mark.parametrize("name", ["cassie", "rabbit", "rabbit-springs"])
def test_equals_the_numeric_passive_forces(name, tmp_path):
    robot = _rabbit_with_springs_and_a_dead_band_tendon(tmp_path) if name == "rabbit-springs" else load_robot(name)
    fn, numeric = _function(robot), PassiveForces(robot)
    rng = np.random.default_rng(0)
    smap = robot.state_map
    lengths = []
    for _ in range(40):
        q = robot.q_stand.copy()
        q[smap.scalar_pin_q] += rng.normal(0.0, 0.4, smap.scalar_pin_q.size)
        for c in robot.couplings:  # the tendon's length across its dead band
            q[c.pin_q_idx[0]] += rng.uniform(-0.6, 0.6)
        v = rng.normal(0.0, 2.0, robot.nv)
        want = numeric(q, v)
        assert np.any(want != 0.0) or name == "rabbit"  # the bundled Rabbit has no passive elements
        np.testing.assert_allclose(np.array(fn(q, v)).ravel(), want, rtol=1e-14, atol=1e-12)
        for c in robot.couplings:
            lengths.append(float(np.dot(c.coefficients, q[c.pin_q_idx])) - c.springlength[0])
    if name == "rabbit-springs":  # the tendon's dead band [0.1, 0.4] was left on both sides and entered
        assert min(lengths) < 0.0 and max(lengths) > 0.3
