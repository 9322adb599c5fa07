"""The robot's springs (``spring_rows``): one enumeration for every tracker, checked against the model's forces."""

import numpy as np
import pytest

from amlip_qp.robots import load_robot
from amlip_qp.robots.passive import contiguous_index, coupling_constraints, passive_forces, spring_rows


def test_cassie_has_an_achilles_rod_and_a_shin_spring_per_leg():
    cassie = load_robot("cassie")
    rows = spring_rows(cassie)
    assert [(r.kind, r.side) for r in rows] == [
        ("coupling", "left"), ("coupling", "right"), ("joint", "left"), ("joint", "right"),
    ]  # fmt: skip
    smap = cassie.state_map
    for r in rows:
        joints = [n for n, i in smap.joint_pin_v.items() if i in r.pin_v_idx.tolist()]
        if r.kind == "coupling":
            assert sorted(joints) == sorted([f"{r.side}-knee", f"{r.side}-tarsus"])
            assert r.stiffness == pytest.approx(1250.0)
        else:
            assert joints == [f"{r.side}-shin"] and r.stiffness == pytest.approx(1500.0)


def test_rabbit_has_no_springs():
    assert spring_rows(load_robot("rabbit")) == ()


def test_rows_give_the_model_spring_forces_and_coupling_residuals():
    """Joint rows: MuJoCo's joint spring -k (row_q . q - rest) on that joint;
    coupling rows: the tendon length minus its target (coupling_constraints)."""
    cassie = load_robot("cassie")
    rng = np.random.default_rng(3)
    q = cassie.q_stand.copy()
    q[cassie.state_map.scalar_pin_q] += rng.normal(0.0, 0.05, cassie.state_map.scalar_pin_q.size)
    v = np.zeros(cassie.nv)
    f = passive_forces(cassie, q, v)
    g, G, _ = coupling_constraints(cassie, q, v)
    rows = spring_rows(cassie)
    couplings = [r for r in rows if r.kind == "coupling"]
    for k, r in enumerate(couplings):
        assert r.row_q(cassie.nq) @ q - r.rest == pytest.approx(g[k], abs=1e-15)
        assert np.array_equal(r.row_v(cassie.nv), G[k])
    coupled = {int(i) for r in couplings for i in r.pin_v_idx}
    for r in rows:
        if r.kind == "joint":
            iv = int(r.pin_v_idx[0])
            assert iv not in coupled
            deflection = r.row_q(cassie.nq) @ q - r.rest
            assert abs(deflection) > 1e-3
            assert f[iv] == pytest.approx(-r.stiffness * deflection, rel=1e-12)


def test_a_contiguous_increasing_index_becomes_a_slice():
    assert contiguous_index(np.arange(3, 7)) == slice(3, 7)
    idx = np.array([1, 3])
    assert contiguous_index(idx) is idx
    descending = np.array([4, 3])
    assert contiguous_index(descending) is descending


def _reference_passive_forces(robot, q, v):
    """The general arithmetic (numpy dots for every tendon), the pair path's reference."""
    from amlip_qp.robots.passive import tendon_force

    f = -robot.dof_damping * v
    pv = robot.state_map.scalar_pin_v
    f[pv] -= robot.dof_stiffness[pv] * (q[robot.state_map.scalar_pin_q] - robot.dof_springref[pv])
    for c in robot.couplings:
        force = tendon_force(c, float(c.coefficients.dot(q[c.pin_q_idx])), float(c.coefficients.dot(v[c.pin_v_idx])))
        for i, k in zip(c.pin_v_idx.tolist(), c.coefficients.tolist()):
            f[i] += k * force
    return f


@pytest.mark.parametrize("coefficients", [None, (1.0, -1.0), (0.7, 1.3)])
def test_passive_forces_equal_the_general_arithmetic_bit_for_bit(coefficients):
    """The +-1 pair path (Cassie's rods) and the general path give the numpy dots' bits."""
    import dataclasses
    import types

    from amlip_qp.robots.passive import PassiveForces

    cassie = load_robot("cassie")
    robot = cassie
    if coefficients is not None:
        couplings = tuple(dataclasses.replace(c, coefficients=np.array(coefficients)) for c in cassie.couplings)
        fields = ("state_map", "dof_damping", "dof_stiffness", "dof_springref")
        robot = types.SimpleNamespace(couplings=couplings, **{k: getattr(cassie, k) for k in fields})
    forces = PassiveForces(robot)
    rng = np.random.default_rng(11)
    smap = cassie.state_map
    for scale in (1e-3, 0.05, 0.5, 3.0):
        q = cassie.q_stand.copy()
        q[smap.scalar_pin_q] += rng.normal(0.0, scale, smap.scalar_pin_q.size)
        v = rng.normal(0.0, 10 * scale, cassie.nv)
        got, want = forces(q, v), _reference_passive_forces(robot, q, v)
        assert np.array_equal(got, want)
        assert np.array_equal(np.signbit(got), np.signbit(want))
    zero = forces(cassie.q_stand.copy(), np.zeros(cassie.nv))
    assert np.array_equal(zero, _reference_passive_forces(robot, cassie.q_stand.copy(), np.zeros(cassie.nv)))
