"""Tests of amlip_qp.sim.world.compiled_io: the generated-C state read equals the reference bit for bit."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from amlip_qp.robots import load_robot
from amlip_qp.robots.state_reader import StateReader
from amlip_qp.sim.world.compiled_io import CompiledStateRead
from robot_states import random_mj_state


@pytest.fixture(scope="module")
def cassie():
    return load_robot("cassie")


def _shuffled(robot, rng, extra: int = 5):
    """A plant layout with ``extra`` more coordinates of each kind, the model's in shuffled places."""
    nq, nv = robot.mj_model.nq, robot.nv
    return rng.permutation(nq + extra)[:nq], rng.permutation(nv + extra)[:nv]


def test_the_compiled_read_is_the_reference_bit_for_bit(cassie):
    """300 random states (quaternions not of unit norm, velocities over 6 decades), in the model's layout
    and in a shuffled plant layout: the same q, v and root row as StateReader.arrays, and the sum."""
    rng = np.random.default_rng(21)
    nq, nv = cassie.mj_model.nq, cassie.nv
    qsrc, vsrc = _shuffled(cassie, rng)
    for reader, size_q, size_v in (
        (StateReader(cassie.state_map), nq, nv),
        (StateReader(cassie.state_map, qsrc, vsrc), nq + 5, nv + 5),
    ):
        data = SimpleNamespace(qpos=np.zeros(size_q), qvel=np.zeros(size_v))
        assert reader.free_joint_plan is not None
        read = CompiledStateRead(reader.free_joint_plan, data).reader()
        unit = set()
        for _ in range(300):
            qpos, qvel = random_mj_state(cassie, rng)
            qpos[3:7] *= rng.uniform(0.5, 2.0)
            qvel *= 10.0 ** rng.uniform(-3, 3)
            if size_q == nq:
                data.qpos[:], data.qvel[:] = qpos, qvel
            else:
                data.qpos[:], data.qvel[:] = rng.normal(size=size_q), rng.normal(size=size_v)
                data.qpos[qsrc], data.qvel[vsrc] = qpos, qvel
            state, total = read()
            assert state is not None
            q, v, root = state
            q_ref, v_ref, root_ref = reader.arrays(data.qpos, data.qvel, data.qpos.tolist())
            assert q.tobytes() == q_ref.tobytes() and v.tobytes() == v_ref.tobytes() and root == root_ref
            assert not np.shares_memory(q, data.qpos) and not np.shares_memory(v, data.qvel)
            assert total == pytest.approx(data.qpos.sum() + data.qvel.sum(), rel=1e-12, abs=1e-9)
            u = q[3:7]
            unit.add(bool(np.sqrt(u[3] ** 2 + u[0] ** 2 + u[1] ** 2 + u[2] ** 2) == 1.0))
        assert unit == {True, False}  # both of the reference's branches were compared


def test_each_read_returns_new_arrays_of_the_data_now(cassie):
    rng = np.random.default_rng(4)
    reader = StateReader(cassie.state_map)
    qpos, qvel = random_mj_state(cassie, rng)
    data = SimpleNamespace(qpos=qpos, qvel=qvel)
    read = CompiledStateRead(reader.free_joint_plan, data).reader()
    first, _ = read()
    kept = first[0].copy()
    data.qpos[7:] += 0.25
    second, _ = read()
    assert np.array_equal(first[0], kept)  # the first read's arrays are not overwritten
    assert np.array_equal(second[0][7:], kept[7:] + 0.25)


@pytest.mark.parametrize("bad", ["nan_q", "inf_v", "zero_quaternion", "overflowing_sum"])
def test_a_state_the_reference_must_check_is_left_to_it(cassie, bad):
    """NaN or inf entries and a zero quaternion give no state (the reference's read then raises or, for a sum
    that overflows on finite entries, reads it); the sum says whether the entries may be non-finite."""
    rng = np.random.default_rng(6)
    qpos, qvel = random_mj_state(cassie, rng)
    if bad == "nan_q":
        qpos[9] = np.nan
    elif bad == "inf_v":
        qvel[2] = np.inf
    elif bad == "zero_quaternion":
        qpos[3:7] = 0.0
    else:
        qpos[10], qpos[11] = 1.5e308, 1.5e308
    data = SimpleNamespace(qpos=qpos, qvel=qvel)
    state, total = CompiledStateRead(StateReader(cassie.state_map).free_joint_plan, data).reader()()
    assert state is None
    assert np.isfinite(total) == (bad == "zero_quaternion")


def test_only_one_free_joint_without_ball_joints_has_a_plan():
    assert StateReader(load_robot("cassie").state_map).free_joint_plan is not None
    assert StateReader(load_robot("rabbit").state_map).free_joint_plan is None  # planar: no free joint


def test_the_harness_walks_the_same_with_and_without_the_generated_c(monkeypatch):
    """0.5 s of the QP walk: every logged signal and the controller's steps are bit-identical whether the
    harness reads and writes with the generated C (reading after each tick's plant steps) or with the
    Python reader and the NumPy writer."""
    from amlip_qp.sim.scenarios.factory import build_simulation
    from amlip_qp.sim.scenarios.named import get_scenario
    from amlip_qp.sim.world.plant import Plant

    sc = get_scenario("cassie-1mps")
    used = []
    original = Plant.compiled_reader

    def spy(self, data):
        reader = original(self, data)
        used.append(reader is not None)
        return reader

    writer = Plant.ctrl_writer
    monkeypatch.setattr(Plant, "compiled_reader", spy)
    compiled = build_simulation(sc, "qp").run(0.5)
    monkeypatch.setattr(Plant, "compiled_reader", lambda self, data: None)
    monkeypatch.setattr(Plant, "ctrl_writer", lambda self, data, compiled=False: writer(self, data, False))
    python = build_simulation(sc, "qp").run(0.5)
    assert used == [True]
    assert compiled.log.keys() == python.log.keys()
    for key, value in compiled.log.items():
        assert np.array_equal(np.asarray(value), np.asarray(python.log[key]), equal_nan=True), key
    assert [s.t_start_s for s in compiled.steps] == [s.t_start_s for s in python.steps]


def test_the_compiled_write_is_numpys_clip_bit_for_bit_and_leaves_nan_to_it():
    """Torques over 6 decades, inside and beyond the control range, both signs: the controls equal the
    NumPy writer's; a NaN torque is written by the NumPy writer (NaN stays NaN)."""
    from amlip_qp.sim.world.compiled_io import CompiledCtrlWrite

    rng = np.random.default_rng(9)
    nu = 10
    gear = rng.uniform(10.0, 60.0, nu)
    lo, hi = -rng.uniform(0.5, 1.5, nu), rng.uniform(0.5, 1.5, nu)
    ctrl, ref = np.zeros(nu + 2), np.zeros(nu)  # the controller's actuators first, two more after them
    used, at_lo, at_hi = [], 0, 0

    def numpy_write(tau):
        used.append(True)
        np.minimum(np.maximum(tau / gear, lo), hi, out=ctrl[:nu])

    write = CompiledCtrlWrite(ctrl[:nu], gear, lo, hi, numpy_write).writer()
    for _ in range(500):
        tau = rng.normal(size=nu) * 10.0 ** rng.uniform(-3, 3)
        write(tau)
        np.minimum(np.maximum(tau / gear, lo), hi, out=ref)
        assert ctrl[:nu].tobytes() == ref.tobytes() and ctrl[nu:].tolist() == [0.0, 0.0]
        at_lo, at_hi = at_lo + int((ref == lo).sum()), at_hi + int((ref == hi).sum())
    assert not used
    assert at_lo > 100 and at_hi > 100  # both bounds were reached, often
    tau = np.ones(nu)
    tau[3] = np.nan
    write(tau)
    assert used == [True] and np.isnan(ctrl[3]) and np.isnan(ctrl[:nu]).sum() == 1
    # a zero gear: 0 / 0 is NaN, which the clip would hide; the NumPy writer writes it
    gear[5] = 0.0
    write_zero_gear = CompiledCtrlWrite(ctrl[:nu], gear, lo, hi, numpy_write).writer()
    with np.errstate(invalid="ignore"):
        write_zero_gear(np.zeros(nu))
    assert used == [True, True] and np.isnan(ctrl[5]) and np.isnan(ctrl[:nu]).sum() == 1


def test_without_a_compiler_the_plant_reads_and_writes_in_python(monkeypatch):
    from amlip_qp.sim.scenarios.factory import load
    from amlip_qp.sim.world.plant_loader import load_plant

    plant = load_plant("cassie", load("cassie"))
    data = plant.new_data()
    assert plant.compiled_reader(data) is not None
    monkeypatch.setenv("AMLIP_QP_CC", "none")
    assert plant.compiled_reader(data) is None
    tau = np.linspace(-200.0, 200.0, plant.gear.size)
    plant.ctrl_writer(data, compiled=True)(tau)  # the NumPy writer: no error without a compiler
    assert np.array_equal(data.ctrl[: tau.size], plant.ctrl_from_tau(tau))
