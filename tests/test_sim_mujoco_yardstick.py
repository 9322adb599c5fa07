"""MuJoCo's step time alone on a fixed walking state (amlip_qp.experiments.mujoco_yardstick)."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from amlip_qp.experiments import mujoco_yardstick
from amlip_qp.sim.scenarios.factory import build_simulation
from amlip_qp.sim.scenarios.named import get_scenario


def test_the_snapshot_is_a_copy_of_the_state_after_the_walks_last_step():
    sim = build_simulation(get_scenario("rabbit-0.5mps"), "qp")
    step = mujoco.mj_step
    model, state = mujoco_yardstick.snapshot_walk(lambda: sim.run(0.05))
    assert mujoco.mj_step is step  # unwrapped again
    assert state.time == pytest.approx(0.05) and model.nq == state.qpos.size
    before = state.qpos.copy()
    us = mujoco_yardstick.step_time_us(model, state, steps=20, rounds=3)
    assert 0.0 < us < 1e4
    np.testing.assert_array_equal(state.qpos, before)  # the replays ran on copies
    assert state.time == pytest.approx(0.05)
    median = mujoco_yardstick.step_median_us(model, state, steps=20, rounds=3)
    assert 0.0 < median < 1e4
    np.testing.assert_array_equal(state.qpos, before)


def test_a_walk_without_a_step_is_an_error_and_unwraps_mujoco():
    step = mujoco.mj_step
    with pytest.raises(RuntimeError, match="no MuJoCo step"):
        mujoco_yardstick.snapshot_walk(lambda: None)
    assert mujoco.mj_step is step
    with pytest.raises(ZeroDivisionError):
        mujoco_yardstick.snapshot_walk(lambda: 1 / 0)
    assert mujoco.mj_step is step
