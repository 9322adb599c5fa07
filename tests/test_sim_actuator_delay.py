"""Tests of sim/world/actuator_delay.py: the actuator commands reach the plant a whole number of ticks
late, the caller's arrays copied, bad shapes and delays refused."""

from __future__ import annotations

import numpy as np
import pytest

from amlip_qp.exceptions import InputError
from amlip_qp.sim.world.actuator_delay import ActuatorDelay


@pytest.mark.parametrize("n", [1, 3])
def test_delay_returns_the_input_n_ticks_earlier(n):
    rng = np.random.default_rng(0)
    inputs = rng.normal(size=(12, 4))
    delay = ActuatorDelay(n, 4)
    outputs = []
    for u in inputs:
        buf = u.copy()
        outputs.append(delay.push(buf))
        buf[:] = np.nan  # the caller reuses its array: the queue must have kept a copy
    for k, out in enumerate(outputs):
        np.testing.assert_array_equal(out, inputs[max(k - n, 0)])  # the first command holds until then
    delay.reset()
    np.testing.assert_array_equal(delay.push(inputs[5]), inputs[5])


def test_zero_delay_is_a_pass_through():
    delay = ActuatorDelay(0, 3)
    u = np.array([1.0, -2.0, 3.0])
    assert delay.push(u) is u


def test_delay_checks_the_vector_length():
    with pytest.raises(InputError, match=r"shape \(4,\)"):
        ActuatorDelay(1, 4).push(np.zeros(3))
    with pytest.raises(InputError, match="actuator delay"):
        ActuatorDelay(-1, 4)
