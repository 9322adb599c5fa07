"""ImuReading: a frozen record of one IMU sample, re-exported where the controller's Measurement lives."""

import dataclasses

import numpy as np
import pytest

from amlip_qp.messages import ImuReading, Measurement
from amlip_qp.messages import ImuReading as Reexported


def test_an_imu_reading_is_frozen_and_rides_in_the_measurement():
    r = ImuReading(np.array([0.0, 0.0, 0.0, 1.0]), np.zeros(3), np.array([0.0, 0.0, 9.81]))
    with pytest.raises(dataclasses.FrozenInstanceError):
        r.gyro_radps = np.ones(3)  # type: ignore[misc]
    assert Reexported is ImuReading
    m = Measurement(0.0, np.zeros(3), np.zeros(3))
    assert m.imu is None and m.base_known  # the defaults: no IMU, the base is measured
    m = Measurement(0.0, np.zeros(3), np.zeros(3), imu=r, base_known=False)
    assert m.imu is r and not m.base_known
    assert [f.name for f in dataclasses.fields(ImuReading)] == ["quat_xyzw", "gyro_radps", "accel_mps2"]


def test_of_packed_is_the_constructor_on_views_of_one_array():
    """The same fields (views of the array, not copies), frozen as well, equal repr."""
    packed = np.arange(10.0) * 0.5
    fast, ref = ImuReading.of_packed(packed), ImuReading(packed[:4], packed[4:7], packed[7:])
    assert type(fast) is ImuReading and vars(fast).keys() == vars(ref).keys()
    for f in ("quat_xyzw", "gyro_radps", "accel_mps2"):
        a, b = getattr(fast, f), getattr(ref, f)
        assert a.tobytes() == b.tobytes() and a.shape == b.shape and np.shares_memory(a, packed)
    assert repr(fast) == repr(ref)
    with pytest.raises(dataclasses.FrozenInstanceError):
        fast.quat_xyzw = np.ones(4)  # type: ignore[misc]


def test_of_packed_from_a_start_reads_the_ten_floats_there():
    """A reading inside a longer array: its 10 floats from ``start``, views of it."""
    packed = np.arange(25.0)
    fast, ref = ImuReading.of_packed(packed, 7), ImuReading(packed[7:11], packed[11:14], packed[14:17])
    for f in ("quat_xyzw", "gyro_radps", "accel_mps2"):
        a, b = getattr(fast, f), getattr(ref, f)
        assert a.tobytes() == b.tobytes() and a.shape == b.shape and np.shares_memory(a, packed)
