"""Rotations of the estimators: quaternions ``x y z w`` (Pinocchio's order) and ``w x y z``
(MuJoCo's, the profiles'), and rotation matrices."""

from __future__ import annotations

import math

import numpy as np

from amlip_qp.exceptions import InputError


def quat_wxyz_to_rot(quat_wxyz) -> np.ndarray:
    """Rotation matrix of a quaternion ``w x y z`` (normalised here)."""
    w, x, y, z = (float(c) for c in quat_wxyz)
    return quat_xyzw_to_rot((x, y, z, w))


def quat_xyzw_to_rot(quat) -> np.ndarray:
    """Rotation matrix of a quaternion ``x y z w`` (normalised here)."""
    x, y, z, w = (float(c) for c in quat)
    n = math.sqrt(x * x + y * y + z * z + w * w)
    if not (n > 0 and math.isfinite(n)):
        raise InputError(f"the IMU quaternion must be finite and non-zero, got {list(quat)!r}")
    x, y, z, w = x / n, y / n, z / n, w / n
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )


def rot_to_quat_xyzw(R) -> np.ndarray:
    """Unit quaternion ``x y z w`` (``w >= 0``) of a rotation matrix (Shepperd's method)."""
    (r00, r01, r02), (r10, r11, r12), (r20, r21, r22) = R.tolist()
    tr = r00 + r11 + r22
    if tr > 0:
        s = 2.0 * math.sqrt(tr + 1.0)
        q = (r21 - r12) / s, (r02 - r20) / s, (r10 - r01) / s, 0.25 * s
    elif r00 > r11 and r00 > r22:
        s = 2.0 * math.sqrt(1.0 + r00 - r11 - r22)
        q = 0.25 * s, (r01 + r10) / s, (r02 + r20) / s, (r21 - r12) / s
    elif r11 > r22:
        s = 2.0 * math.sqrt(1.0 + r11 - r00 - r22)
        q = (r01 + r10) / s, 0.25 * s, (r12 + r21) / s, (r02 - r20) / s
    else:
        s = 2.0 * math.sqrt(1.0 + r22 - r00 - r11)
        q = (r02 + r20) / s, (r12 + r21) / s, 0.25 * s, (r10 - r01) / s
    out = np.array(q)
    return -out if out[3] < 0 else out
