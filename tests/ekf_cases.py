"""A synthetic walk for the EKF tests: a known smooth IMU path with rotation, feet fixed in the world
while in contact, alternating contacts; the exact IMU readings and contact vectors, analytically (SI)."""

from dataclasses import dataclass

import numpy as np

from amlip_qp.estimation.invariant_ekf import GRAVITY_MPS2

#: Gait period, s; the left foot is down for phase < 0.5, the right for phase >= 0.4 or < 0.1.
PERIOD_S = 0.8


def _rot(yaw, pitch, roll):
    cy, sy, cp, sp, cr, sr = np.cos(yaw), np.sin(yaw), np.cos(pitch), np.sin(pitch), np.cos(roll), np.sin(roll)
    Rz = np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
    Ry = np.array([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
    Rx = np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
    return Rz @ Ry @ Rx


def truth(t: float):
    """``(R, p, v, a, omega_body)`` of the IMU at ``t``: forward at ~0.5 m/s with sway, bounce and rotation."""
    p = np.array([0.5 * t + 0.05 * np.sin(2 * t), 0.1 * np.sin(1.5 * t), 1.0 + 0.03 * np.sin(3 * t)])
    v = np.array([0.5 + 0.1 * np.cos(2 * t), 0.15 * np.cos(1.5 * t), 0.09 * np.cos(3 * t)])
    a = np.array([-0.2 * np.sin(2 * t), -0.225 * np.sin(1.5 * t), -0.27 * np.sin(3 * t)])
    yaw, dyaw = 0.3 * np.sin(0.7 * t), 0.21 * np.cos(0.7 * t)
    pitch, dpitch = 0.1 * np.sin(2 * t), 0.2 * np.cos(2 * t)
    roll, droll = 0.05 * np.sin(1.3 * t), 0.065 * np.cos(1.3 * t)
    # body rates of the z-y-x Euler angles
    w = np.array(
        [
            droll - np.sin(pitch) * dyaw,
            np.cos(roll) * dpitch + np.sin(roll) * np.cos(pitch) * dyaw,
            -np.sin(roll) * dpitch + np.cos(roll) * np.cos(pitch) * dyaw,
        ]
    )
    return _rot(yaw, pitch, roll), p, v, a, w


def contacts(t: float) -> tuple[bool, bool]:
    ph = (t % PERIOD_S) / PERIOD_S
    return ph < 0.5, ph >= 0.4 or ph < 0.1


@dataclass
class Sample:
    t: float
    R: np.ndarray
    p: np.ndarray
    v: np.ndarray
    gyro: np.ndarray
    accel: np.ndarray
    in_contact: tuple[bool, bool]
    y: np.ndarray  # (2, 3): each foot seen from the IMU, IMU axes (swing feet: their last footfall)


def walk(duration_s: float, dt_s: float, gyro_bias=(0, 0, 0), accel_bias=(0, 0, 0), noise=0.0, seed=0):
    """The samples at ``k dt`` (exact, or with white noise of std ``noise`` on the IMU and 0.1 ``noise`` m on y)."""
    rng = np.random.default_rng(seed)
    feet = np.zeros((2, 3))
    before = (False, False)
    out = []
    for k in range(int(round(duration_s / dt_s)) + 1):
        t = k * dt_s
        R, p, v, a, w = truth(t)
        c = contacts(t)
        for i, side_y in enumerate((0.12, -0.12)):
            if c[i] and not before[i]:  # touchdown: the foot lands beside the IMU, on the ground
                feet[i] = [p[0] + 0.1, p[1] + side_y, 0.0]
        before = c
        y = (feet - p) @ R  # rows R^T (d - p)
        gyro = w + np.asarray(gyro_bias) + noise * rng.normal(size=3)
        accel = R.T @ (a - GRAVITY_MPS2) + np.asarray(accel_bias) + noise * rng.normal(size=3)
        out.append(Sample(t, R, p, v, gyro, accel, c, y + 0.1 * noise * rng.normal(size=(2, 3))))
    return out
