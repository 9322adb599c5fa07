"""ImuReading: a frozen record of one IMU sample, re-exported where the controller's Measurement lives."""

import dataclasses

import numpy as np
import pytest

from amlip_qp.control.walking.estimator import ImuReading as Reexported
from amlip_qp.control.walking.estimator import Measurement
from amlip_qp.estimation.imu import ImuReading


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
