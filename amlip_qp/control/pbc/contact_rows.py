"""The PBC's stance contact rows ``(J_c, Jdot_c v)``: the Python reference.

The rows hold the stance foot (:mod:`amlip_qp.control.pbc.tracker`, equation (2)): Rabbit's
point foot by its in-plane translation (x and z, 2 rows), a point foot by its translation
(3 rows), a foot held along its sole line (Cassie's blade; a four-point sole's toe-pair to
heel-pair line) by its translation and its rotation about the two axes normal to the line
(5 rows). The generated C of :mod:`amlip_qp.control.pbc.dynamics_compiled` forms the same rows
(:func:`~amlip_qp.control.pbc.dynamics_compiled.contact_rows_expression`).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:  # pragma: no cover - typing only
    from amlip_qp.robots.kinematics import RobotKinematics
    from amlip_qp.robots.robot import Robot


def contact_rows(
    robot: Robot, kin: RobotKinematics, stance: str, blade: bool, J_out: np.ndarray, a_out: np.ndarray
) -> None:
    """Write ``stance``'s contact rows ``J`` (n x nv) and ``Jdot_v`` (n,) into ``J_out`` and ``a_out``
    (n = 2 planar, 5 with ``blade``, else 3; world axes, m/s^2 and rad/s^2)."""
    cid = robot.contact_frame_ids[stance]
    J6 = kin.frame_jacobian6(cid)
    a6 = kin.frame_jdot_v6(cid)
    if robot.is_planar:
        J_out[0], J_out[1] = J6[0], J6[2]
        a_out[0], a_out[1] = a6[0], a6[2]
        return
    J_out[:3] = J6[:3]
    a_out[:3] = a6[:3]
    if not blade:
        return
    # the two rotation axes normal to the blade u: n1 = u x z (or u x x), n2 = u x n1 (scalar math)
    toe_id, heel_id = robot.sole_line_frame_ids[stance]
    t, h = kin.frame_translation_view(toe_id).tolist(), kin.frame_translation_view(heel_id).tolist()
    ux, uy, uz = t[0] - h[0], t[1] - h[1], t[2] - h[2]
    nu = math.sqrt(ux * ux + uy * uy + uz * uz)
    ux, uy, uz = ux / nu, uy / nu, uz / nu
    ax, ay, az = uy, -ux, 0.0
    na = math.sqrt(ax * ax + ay * ay)
    if na < 1e-6:
        ax, ay, az = 0.0, uz, -uy
        na = math.sqrt(ay * ay + az * az)
    ax, ay, az = ax / na, ay / na, az / na
    bx, by, bz = uy * az - uz * ay, uz * ax - ux * az, ux * ay - uy * ax
    Jw = J6[3:]
    N = np.array(((ax, ay, az), (bx, by, bz)))
    J_out[3:5] = np.dot(N, Jw)
    _, _, _, w0, w1, w2 = a6.tolist()
    a_out[3] = ax * w0 + ay * w1 + az * w2
    a_out[4] = bx * w0 + by * w1 + bz * w2
