"""One IMU sample, as the harness's sensors report it to the controller."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class ImuReading:
    """One IMU sample (SI units, the IMU's own axes).

    Attributes:
        quat_xyzw: IMU frame orientation in world, as the IMU's own filter reports it (4,).
        gyro_radps: Angular velocity of the IMU frame, IMU axes, rad/s (3,).
        accel_mps2: Specific force (a - g) in IMU axes, m/s² (3,) (reads +9.81 z when at rest, level).
    """

    quat_xyzw: np.ndarray
    gyro_radps: np.ndarray
    accel_mps2: np.ndarray
