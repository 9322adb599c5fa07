"""The EKF's cost per control tick, for ``amlip-qp bench``.

:func:`time_ekf` replays measurements through
:meth:`EkfBaseEstimator.fill <amlip_qp.estimation.base_estimator.EkfBaseEstimator.fill>`
(the whole per-tick cost the controller pays: leg kinematics, propagation,
correction, the base state) and returns each tick's wall time. Without
measurements it makes a stand-in sequence: the robot's ``stand`` keyframe
with the joints swaying, an IMU at rest with noise, and the contacts going
through double support, left, double support, right (300 ticks each), so the
touchdown re-initialisation is timed too. The cost does not depend on the
values, only on the contacts' pattern.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from amlip_qp.estimation.base_estimator import EkfBaseEstimator
from amlip_qp.exceptions import InputError
from amlip_qp.messages import ImuReading

if TYPE_CHECKING:  # pragma: no cover - typing only
    from amlip_qp.robots.robot import Robot


@dataclass
class _Reading:
    """The fields of a controller measurement that the EKF reads (a stand-in for ``Measurement``)."""

    t_s: float
    q: np.ndarray
    v: np.ndarray
    foot_contact: dict[str, bool] = field(default_factory=dict)
    imu: ImuReading | None = None
    base_known: bool = False


def stand_in_measurements(robot: Robot, n_ticks: int, dt_s: float = 0.0005, seed: int = 0) -> list:
    """``n_ticks`` measurement-like objects for :func:`time_ekf` (see the module doc)."""
    rng = np.random.default_rng(seed)
    left, right = robot.foot_sides
    pattern = ((True, True), (True, False), (True, True), (False, True))
    out = []
    for k in range(n_ticks):
        q = robot.q_stand.copy()
        q[7:] += 0.02 * np.sin(2 * np.pi * 1.5 * k * dt_s)
        c = pattern[(k // 300) % 4]
        imu = ImuReading(
            quat_xyzw=np.array([0.0, 0.0, 0.0, 1.0]),
            gyro_radps=0.01 * rng.normal(size=3),
            accel_mps2=np.array([0.0, 0.0, 9.81]) + 0.1 * rng.normal(size=3),
        )
        out.append(_Reading(k * dt_s, q, np.zeros(robot.nv), {left: c[0], right: c[1]}, imu))
    return out


def time_ekf(
    robot: Robot,
    imu,
    measurements: Sequence | None = None,
    n_ticks: int = 2000,
    backend: str = "c",
    dt_s: float = 0.0005,
) -> np.ndarray:
    """Wall time of each :meth:`EkfBaseEstimator.fill`, µs.

    Args:
        robot: The controller's robot (floating base).
        imu: Where the IMU sits (:class:`~amlip_qp.profiles.ImuMount`, e.g. ``robot.imu_mount``,
            or its position on the base, m, with the base's axes).
        measurements: Controller measurements to replay (each with ``imu`` and
            ``foot_contact``); default: :func:`stand_in_measurements` of ``n_ticks``.
        n_ticks: Ticks of the stand-in sequence, >= 1 (ignored with ``measurements``).
        backend: The EKF backend, ``"c"`` or ``"numpy"``.
        dt_s: Control period, s.

    Returns:
        One wall time per tick, µs, shape (number of measurements,).
    """
    if measurements is None:
        if n_ticks < 1:
            raise InputError(f"n_ticks must be >= 1, got {n_ticks}")
        measurements = stand_in_measurements(robot, n_ticks, dt_s)
    est = EkfBaseEstimator(robot, dt_s, imu, backend=backend)
    est.fill(measurements[0])  # initialisation (and a compiled library loaded) outside the timing
    est.reset()
    out = np.empty(len(measurements))
    clock = time.perf_counter_ns
    for k, m in enumerate(measurements):
        t0 = clock()
        est.fill(m)
        out[k] = (clock() - t0) * 1e-3
    return out
