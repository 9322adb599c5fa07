"""Pelvis-yaw feedback on the swing hip-yaw reference, shared by both trackers
(:attr:`QPConfig.hip_yaw_feedback <amlip_qp.control.wbc.config.QPConfig.hip_yaw_feedback>`,
:attr:`PBCGains.hip_yaw_feedback <amlip_qp.control.pbc.gains.PBCGains.hip_yaw_feedback>`).

Cassie's two hip-yaw outputs are joint angles, so yaw that the stance foot
creeps in the plant carries over to the pelvis and, through the next foot's
placement, to every later step; the paper's hip-yaw references are open-loop.
With the feedback the swing hip-yaw reference becomes
``h_d[swing_hip_yaw] - k e_psi`` (rad), with
``e_psi = wrap(psi_pelvis - (D - h_d[stance_hip_yaw]))`` the pelvis yaw error
against its nominal value (heading ``D``), and its rate reference
``dh_d[swing_hip_yaw] - k (psidot_pelvis + dh_d[stance_hip_yaw])`` (rad/s):
the swing foot lands turned back towards the heading.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import casadi as ca
import numpy as np

if TYPE_CHECKING:  # pragma: no cover - typing only
    from amlip_qp.control.tracker import TrackingTarget
    from amlip_qp.robots.kinematics import RobotKinematics


class PelvisYawFeedback:
    """The feedback of the module doc for one output layout.

    Args:
        gain: ``k`` (dimensionless, > 0).
        stance_index: Index of the ``stance_hip_yaw`` output.
        swing_index: Index of the ``swing_hip_yaw`` output.
    """

    def __init__(self, gain: float, stance_index: int, swing_index: int):
        self.gain = float(gain)
        self.stance_index = int(stance_index)
        self.swing_index = int(swing_index)

    @classmethod
    def for_outputs(cls, names, gain: float) -> PelvisYawFeedback | None:
        """The feedback for the output ``names``; ``None`` when ``gain`` is 0 or an output is missing."""
        names = tuple(names)
        if gain > 0 and "stance_hip_yaw" in names and "swing_hip_yaw" in names:
            return cls(gain, names.index("stance_hip_yaw"), names.index("swing_hip_yaw"))
        return None

    def correction(self, kin: RobotKinematics, target: TrackingTarget) -> tuple[float, float]:
        """The change of the swing hip-yaw reference (rad) and of its rate
        (rad/s): ``(-k e_psi, -k (psidot + dh_d[stance_hip_yaw]))``."""
        i_st = self.stance_index
        k = self.gain
        _, v = kin.state()  # InputError before the first update
        base = kin.robot.base_frame_id
        R = kin.frame_rotation_view(base)
        psi = math.atan2(R[1, 0], R[0, 0])
        psi_dot = float(np.dot(kin.frame_jacobian6(base)[5], v))  # the angular row about world z
        e = psi - (target.heading_rad - float(target.h_d[i_st]))
        e = (e + math.pi) % (2.0 * math.pi) - math.pi
        return -k * e, -k * (psi_dot + float(target.dh_d[i_st]))

    def symbolic_correction(self, R, yaw_rate, heading_rad, h_d, dh_d):
        """:meth:`correction` as CasADi expressions (for generated code).

        Args:
            R: The base's world rotation (3, 3).
            yaw_rate: ``psidot`` (rad/s): the base's world-z angular velocity.
            heading_rad: The heading ``D``.
            h_d, dh_d: The output references and rates.
        """
        i_st, k = self.stance_index, self.gain
        e = ca.atan2(R[1, 0], R[0, 0]) - (heading_rad - h_d[i_st]) + math.pi
        e = ca.fmod(e, 2.0 * math.pi)  # Python's floor modulo: C's fmod, moved into [0, 2 pi)
        e = ca.if_else(e < 0.0, e + 2.0 * math.pi, e) - math.pi
        return -k * e, -k * (yaw_rate + dh_d[i_st])

    def references(self, kin: RobotKinematics, target: TrackingTarget) -> tuple[np.ndarray, np.ndarray]:
        """Copies of ``target.h_d`` (rad, m) and ``target.dh_d`` with the swing hip-yaw entries corrected."""
        dh, ddh = self.correction(kin, target)
        h_d = np.array(target.h_d, dtype=float)
        dh_d = np.array(target.dh_d, dtype=float)
        h_d[self.swing_index] += dh
        dh_d[self.swing_index] += ddh
        return h_d, dh_d
