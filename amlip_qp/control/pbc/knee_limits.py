"""Straight-knee handling of the iterative IK (:attr:`IKSettings.knee_limit_swap
<amlip_qp.control.pbc.ik_settings.IKSettings.knee_limit_swap>`).

A Newton iterate that clamps a knee at its straight-leg range limit breaks the
rows through the knee (Cassie's coupling ``q_knee + q_tarsus``), which the
next step undoes: the iterates then wander with residuals of order 1. When the
iterations end unconverged with a knee at that limit, :meth:`KneeLimits.split`
decides, per clamped knee, between

- **swap**: the knee's output is out of reach (``|y| < |h_d|``: the CoM too
  low over the stance foot, the swing foot short of its target); the output's
  row is exchanged for "knee = limit" (:func:`swap_rows`), a square system
  again, and that output gives way while all the others stay exact;
- **back off**: the output is reachable and the straight leg is only a bad
  (near-singular) iterate; the caller restarts from the knee moved off the limit.

With :attr:`IKSettings.knee_hold_short_of_limit
<amlip_qp.control.pbc.ik_settings.IKSettings.knee_hold_short_of_limit>`, a stance knee whose
CoM height is out of reach *short of* the limit is exchanged too, for "knee = its
estimate", when more iterations have not converged either. The height's highest
reachable value can lie inside the range (a fold: the stance CoM height over a
foot far ahead, with the stance springs held at the model's deflections), where
the Newton iterates circle the fold, never clamp, and give a reference that
jumps from tick to tick.

A knee entry is the tuple ``(output row, knee q index, knee v index,
straight-leg limit, other end of the range)``.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from amlip_qp.alip import other_side
from amlip_qp.robots.kinematics import RobotKinematics
from amlip_qp.robots.outputs import OutputMap

if TYPE_CHECKING:  # pragma: no cover - typing only
    from amlip_qp.control.pbc.ik_settings import IKSettings
    from amlip_qp.robots.robot import Robot

#: ``(output row, knee q index, knee v index, straight-leg limit, other end)``.
KneeEntry = tuple[int, int, int, float, float]


class KneeLimits:
    """The knees that may be held at their straight-leg limit (or the stance knee short of it), per stance side.

    Per stance: the stance knee against ``com_z_over_stance`` and the swing
    knee against ``com_x_over_swing`` (whichever outputs the robot has). The
    straight leg is the limit towards which the stance CoM height grows, read
    from the output Jacobian at the robot's standing configuration. A robot
    without knee joints (the ``knee`` role, :meth:`Robot.role_joint`) has none.

    Args:
        robot: The robot.
        settings: The IK settings (``swap_threshold``).
    """

    def __init__(self, robot: Robot, settings: IKSettings):
        self.swap_threshold = settings.swap_threshold
        names = list(OutputMap(robot).names)
        smap = robot.state_map
        m = robot.pin_model
        self._knees: dict[str, list[KneeEntry]] = {side: [] for side in robot.foot_sides}
        knees = {sd: robot.role_joint("knee", sd) for sd in robot.foot_sides}
        knee = {sd: name for sd, name in knees.items() if name is not None}
        if len(knee) != len(knees):
            return
        k0 = RobotKinematics(robot)
        k0.update_positions(robot.q_stand)
        for side in robot.foot_sides:
            other = other_side(side)
            _, J0, _ = k0.outputs(side, 0.0)
            for row_name, knee_side in (("com_z_over_stance", side), ("com_x_over_swing", other)):
                if row_name not in names:
                    continue
                iq, iv = smap.joint_pin_q[knee[knee_side]], smap.joint_pin_v[knee[knee_side]]
                # straight leg = the limit towards which the stance CoM height grows
                grow = J0[names.index("com_z_over_stance"), smap.joint_pin_v[knee[side]]]
                lo_, hi_ = float(m.lowerPositionLimit[iq]), float(m.upperPositionLimit[iq])
                limit, other_end = (hi_, lo_) if grow > 0 else (lo_, hi_)
                self._knees[side].append((names.index(row_name), iq, iv, limit, other_end))
        #: The output row a knee may be held short of its limit for: the stance CoM height.
        self._hold_row = names.index("com_z_over_stance") if "com_z_over_stance" in names else None

    def entries(self, stance: str) -> tuple[KneeEntry, ...]:
        """The knees that may be held at their limit with this stance (module doc), possibly none."""
        return tuple(self._knees[stance])

    def split(self, stance: str, q, F, y, h_d, q_est=None) -> tuple[list[KneeEntry] | None, list[KneeEntry]]:
        """For an unconverged solve (max-norm residual ``F`` above the threshold): the knees
        clamped at their straight-leg limit, as ``(swap, back_off)`` (module doc); ``swap``
        is ``None`` when empty.

        With ``q_est`` (the estimated configuration, when the settings hold a knee short of
        its limit) a stance knee off its limit whose CoM height is out of reach is in ``swap``
        as well, its entry's held value (the fourth field) replaced by its estimate
        ``q_est[knee]``, clipped to the knee's range (:meth:`short_of_limit` says when).
        """
        thr = self.swap_threshold
        if float(np.max(np.abs(F))) <= thr:
            return None, []
        swap: list[KneeEntry] = []
        back: list[KneeEntry] = []
        for sp in self._knees[stance]:
            row, iq = sp[0], sp[1]
            out_of_reach = abs(y[row]) < abs(h_d[row]) - thr
            if abs(q[iq] - sp[3]) < 1e-9:
                (swap if out_of_reach else back).append(sp)
            elif out_of_reach and q_est is not None and row == self._hold_row:
                lo, hi = min(sp[3], sp[4]), max(sp[3], sp[4])
                swap.append((row, iq, sp[2], min(hi, max(lo, float(q_est[iq]))), sp[4]))
        return (swap or None), back

    def short_of_limit(self, stance: str, q, F, y, h_d) -> bool:
        """Whether an unconverged solve (residual ``F`` above the threshold) has the stance CoM
        height out of reach with the stance knee off its limit: the case :meth:`split` holds
        the knee at its estimate for, once more iterations have not converged either."""
        thr = self.swap_threshold
        if self._hold_row is None or float(np.max(np.abs(F))) <= thr:
            return False
        row = self._hold_row
        return any(
            sp[0] == row and abs(q[sp[1]] - sp[3]) >= 1e-9 and abs(y[row]) < abs(h_d[row]) - thr
            for sp in self._knees[stance]
        )


def swap_rows(swap: list[KneeEntry] | None, q, A, F) -> None:
    """Replace each exchanged output row of ``A`` (and of the residual ``F``, if given) by
    ``q_knee - held`` (the row of that knee; ``held`` is the entry's fourth field: the
    straight-leg limit, or the knee's estimate for a knee held short of it)."""
    if swap is None:
        return
    for row, iq, iv, limit, _ in swap:
        A[row] = 0.0
        A[row, iv] = 1.0
        if F is not None:
            F[row] = q[iq] - limit
