"""Tests of amlip_qp.robots.state_reader: the per-tick state read equals mj_to_pin bit for bit."""

from __future__ import annotations

import numpy as np
import pytest

from amlip_qp.exceptions import InputError
from amlip_qp.robots import load_robot, mj_to_pin
from amlip_qp.robots.state import StateMap
from amlip_qp.robots.state_reader import StateReader
from robot_states import ROBOTS, random_mj_state


@pytest.fixture(scope="module", params=ROBOTS)
def robot(request):
    return load_robot(request.param)


def test_state_reader_is_mj_to_pin_bit_for_bit(robot):
    """The per-tick reader equals mj_to_pin exactly, unnormalized quaternions and a plant's own layout included."""
    rng = np.random.default_rng(11)
    smap = robot.state_map
    nq, nv = robot.mj_model.nq, robot.nv
    # a plant with 5 more coordinates of each kind, holding the model's in shuffled places
    qsrc, vsrc = rng.permutation(nq + 5)[:nq], rng.permutation(nv + 5)[:nv]
    first_q, first_v = np.arange(nq), np.arange(nv)  # the model's coordinates first, then 5 more
    readers = (
        (StateReader(smap), None, None),
        (StateReader(smap, qsrc, vsrc), qsrc, vsrc),
        (StateReader(smap, first_q, first_v), first_q, first_v),
    )
    for _ in range(300):
        qpos, qvel = random_mj_state(robot, rng)
        qvel *= 10.0 ** rng.uniform(-3, 3)
        if robot.is_floating:
            qpos[3:7] *= rng.uniform(0.5, 2.0)  # as after an integration step: not exactly unit
        q_ref, v_ref = mj_to_pin(robot, qpos, qvel)
        for reader, qs, vs in readers:
            if qs is None:
                big_q, big_v = qpos, qvel
            else:
                big_q, big_v = rng.normal(size=nq + 5), rng.normal(size=nv + 5)
                big_q[qs], big_v[vs] = qpos, qvel
            q, v = reader(big_q, big_v)
            assert q.dtype == v.dtype == np.float64
            assert q.tobytes() == q_ref.tobytes() and v.tobytes() == v_ref.tobytes()
            qpos_list = big_q.tolist()
            for qpos_sum in (None, sum(qpos_list)):
                qa, va, root = reader.arrays(big_q, big_v, qpos_list, qpos_sum)
                assert qa.tobytes() == q_ref.tobytes() and va.tobytes() == v_ref.tobytes()
                assert not np.shares_memory(qa, big_q) and not np.shares_memory(va, big_v)  # new arrays
                if robot.is_floating:  # the root free joint's (q, v)
                    assert root == q_ref[:7].tolist() + v_ref[:6].tolist()
                else:
                    assert root == []


def test_state_reader_refuses_nan_inf_and_zero_quaternions(robot):
    reader, nv = StateReader(robot.state_map), robot.nv
    bad = robot.qpos_stand.copy()
    bad[2] = np.nan
    with pytest.raises(InputError, match=r"qpos contains NaN or inf at indices \[2\]"):
        reader(bad, np.zeros(nv))
    bad_v = np.zeros(nv)
    bad_v[-1] = np.inf
    with pytest.raises(InputError, match=rf"qvel contains NaN or inf at indices \[{nv - 1}\]"):
        reader.arrays(robot.qpos_stand, bad_v, robot.qpos_stand.tolist())
    # the sum given is the one checked
    with pytest.raises(InputError, match=r"qpos contains NaN or inf at indices \[2\]"):
        reader.arrays(bad, np.zeros(nv), bad.tolist(), np.nan)
    if robot.is_floating:
        bad = robot.qpos_stand.copy()
        bad[3:7] = 0.0
        with pytest.raises(InputError, match="zero quaternion"):
            reader(bad, np.zeros(nv))


def test_state_reader_a_sum_that_overflows_is_checked_exactly(robot):
    qpos, qvel = robot.qpos_stand.copy(), np.zeros(robot.nv)
    qvel[-2:] = 1e308  # finite, but the sum overflows
    q, v = StateReader(robot.state_map)(qpos, qvel)
    q_ref, v_ref = mj_to_pin(robot, qpos, qvel)
    assert q.tobytes() == q_ref.tobytes() and v.tobytes() == v_ref.tobytes()
    q, v, root = StateReader(robot.state_map).arrays(qpos, qvel, qpos.tolist())
    assert q.tobytes() == q_ref.tobytes() and v.tobytes() == v_ref.tobytes()
    assert root == (q_ref[:7].tolist() + v_ref[:6].tolist() if robot.is_floating else [])


def test_state_reader_ball_joint_quaternion_is_normalized_and_reordered():
    """A ball joint (none in the bundled robots): wxyz -> xyzw, normalized, angular velocity as is."""
    i = np.intp
    smap = StateMap(
        nq_mj=5, nq_pin=5, nv=4,
        scalar_mj_q=np.array([4], i), scalar_pin_q=np.array([4], i),
        scalar_mj_v=np.array([3], i), scalar_pin_v=np.array([3], i),
        free=(), ball=((0, 0, 0, 0),), joint_pin_q={"ball": 0, "hinge": 4}, joint_pin_v={"ball": 0, "hinge": 3},
    )  # fmt: skip
    rng = np.random.default_rng(3)
    reader = StateReader(smap)
    for _ in range(100):
        qpos, qvel = rng.normal(size=5), rng.normal(size=4)
        q, v = reader(qpos, qvel)
        q_ref, v_ref = mj_to_pin(smap, qpos, qvel)
        assert q.tobytes() == q_ref.tobytes() and v.tobytes() == v_ref.tobytes()
        n = np.linalg.norm(qpos[:4])
        np.testing.assert_allclose(q[:4], np.r_[qpos[1:4], qpos[0]] / n, rtol=1e-15)
        assert v.tolist() == qvel.tolist()


def test_the_one_free_joint_path_both_when_the_normalized_quaternion_s_norm_is_one_and_when_not():
    """The free joint's rotation divides by the re-normalized quaternion's norm only when it is not 1.0."""
    robot = load_robot("cassie")
    reader, rng = StateReader(robot.state_map), np.random.default_rng(5)
    norms = set()
    for _ in range(200):
        qpos, qvel = random_mj_state(robot, rng)
        qpos[3:7] *= rng.uniform(0.5, 2.0)
        u = qpos[3:7] / np.sqrt(np.sum(qpos[3:7] ** 2))
        norms.add(bool(np.sqrt(np.sum(u**2)) == 1.0))
        q_ref, v_ref = mj_to_pin(robot, qpos, qvel)
        q, v, root = reader.arrays(qpos, qvel, qpos.tolist())
        assert q.tobytes() == q_ref.tobytes() and v.tobytes() == v_ref.tobytes()
        assert root == q_ref[:7].tolist() + v_ref[:6].tolist()
    assert norms == {True, False}


def test_bind_is_arrays_of_the_bound_arrays_read_now(robot):
    """The bound read sees the arrays' values at each call (views into them, as MuJoCo's data)."""
    reader, rng = StateReader(robot.state_map), np.random.default_rng(8)
    qpos, qvel = random_mj_state(robot, rng)
    read = reader.bind(qpos, qvel)
    for _ in range(20):
        new_q, new_v = random_mj_state(robot, rng)
        qpos[:], qvel[:] = new_q, new_v
        q, v, root = read(qpos.tolist())
        q_ref, v_ref, root_ref = reader.arrays(qpos.copy(), qvel.copy(), qpos.tolist())
        assert q.tobytes() == q_ref.tobytes() and v.tobytes() == v_ref.tobytes() and root == root_ref
