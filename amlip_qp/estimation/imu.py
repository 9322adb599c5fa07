"""One IMU reading, as the controller receives it.

The IMU frame is rigidly attached to the body the robot's profile names
(:attr:`~amlip_qp.robots.robot.Robot.imu_mount`: a body, a position and axes
in its frame; by default the base body's origin and axes). The EKF takes the
reading turned into that of an IMU fixed to the base with the base's axes
(:mod:`~amlip_qp.estimation.imu_to_base`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class ImuReading:
    """What the IMU reports at one tick (SI units).

    Attributes:
        quat_xyzw: Orientation of the IMU frame in the world, as the IMU's own
            filter reports it (unit quaternion, x y z w), shape (4,).
        gyro_radps: Angular velocity of the IMU frame, IMU axes, rad/s, shape (3,).
        accel_mps2: Specific force ``a - g`` in IMU axes, m/s^2, shape (3,)
            (reads ``+9.81`` on z at rest, level).
    """

    quat_xyzw: np.ndarray
    gyro_radps: np.ndarray
    accel_mps2: np.ndarray

    @classmethod
    def of_packed(cls, packed: np.ndarray, start: int = 0) -> ImuReading:
        """``ImuReading(p[:4], p[4:7], p[7:10])`` of ``p = packed[start:]``: the reading of 10 floats
        (quaternion x y z w, gyro, accelerometer) of one array, holding views of it.

        The same object as the constructor's (tested), made without its three frozen
        ``object.__setattr__`` calls: the harness's per-tick reading.
        """
        reading = object.__new__(cls)
        fields = reading.__dict__
        fields["quat_xyzw"] = packed[start : start + 4]
        fields["gyro_radps"] = packed[start + 4 : start + 7]
        fields["accel_mps2"] = packed[start + 7 : start + 10]
        return reading
