"""Heading frames of the steps and the hip-yaw split of a turn.

Each step ``k`` has a heading ``D_k`` (yaw about world z, rad). The heading
frame is the world frame rotated by ``D_k`` about z: its x axis points along
the step's forward direction. Headings are not wrapped to (-pi, pi]: a robot
that keeps turning accumulates heading, and every function here is
2*pi-periodic anyway.
"""

from __future__ import annotations

import math

import numpy as np

from amlip_qp.alip import _checks as C
from amlip_qp.alip import formulas as F
from amlip_qp.exceptions import InputError


def rotation(heading_rad: float) -> np.ndarray:
    """2x2 rotation matrix taking heading-frame xy components to world xy (heading in rad)."""
    C.finite("heading_rad", heading_rad)
    c, s = math.cos(heading_rad), math.sin(heading_rad)
    return np.array([[c, -s], [s, c]])


def heading_to_world(xy_heading, heading_rad: float) -> np.ndarray:
    """Rotate a 2-vector (any unit) from the heading frame ``D = heading_rad`` to world axes."""
    v = C.vector("xy_heading", xy_heading, 2)
    C.finite("heading_rad", heading_rad)
    c, s = math.cos(heading_rad), math.sin(heading_rad)
    return np.array([c * v[0] - s * v[1], s * v[0] + c * v[1]])


def world_to_heading(xy_world, heading_rad: float) -> np.ndarray:
    """Rotate a 2-vector (any unit) from world axes into the heading frame ``D = heading_rad``."""
    v = C.vector("xy_world", xy_world, 2)
    C.finite("heading_rad", heading_rad)
    return np.array(F.world_to_heading_xy(v[0], v[1], math.cos(heading_rad), math.sin(heading_rad)))


def hip_yaw_targets(turn_rad: float) -> tuple[float, float]:
    """Split a step's turn ``dD = D_{k+1} - D_k`` (rad) between the hip yaws.

    Returns ``(stance_hip_yaw_target, swing_hip_yaw_target)`` in rad, which are
    ``(-dD/2, +dD/2)`` (paper section 4): the pelvis turns by ``dD/2`` over the
    stance foot and the swing foot by another ``dD/2``, so the swing foot lands
    along ``D_{k+1}``. The order matches the outputs ``stance_hip_yaw``,
    ``swing_hip_yaw``.
    """
    C.finite("turn_rad", turn_rad)
    return F.hip_yaw_split(float(turn_rad))


def yaw_of(xy_world) -> float:
    """Yaw (rad, in (-pi, pi]) of a horizontal world direction ``xy_world`` (nonzero 2-vector)."""
    v = C.vector("xy_world", xy_world, 2)
    if v[0] == 0.0 and v[1] == 0.0:
        raise InputError("xy_world must be a nonzero 2-vector to define a yaw; got (0, 0)")
    return math.atan2(v[1], v[0])
