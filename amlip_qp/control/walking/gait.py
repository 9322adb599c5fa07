"""Gait logic: fixed step time, stance switching at touchdown.

The step time ``T`` is fixed. The stance switches when the swing foot touches
down, detected from its contact switch or, without contact sensing, from its
height above the stance contact. Early touchdowns (before ``T``) are accepted
after a minimum fraction of the step, so that the foot leaving the ground is
not mistaken for a touchdown; late ones hold the phase at 1 (the references
keep pushing the foot to the ground) until contact or until a timeout, which
forces the switch.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from amlip_qp.exceptions import InputError


@dataclass(frozen=True)
class GaitParams:
    """Touchdown detection settings.

    Attributes:
        min_phase: Earliest phase at which a touchdown counts (dimensionless).
        max_phase: Phase at which the switch is forced without contact.
        touchdown_height_m: Without contact switches: the swing contact point
            must be at most this high above the stance contact, m.
    """

    min_phase: float = 0.55
    max_phase: float = 1.5
    touchdown_height_m: float = 0.01

    def __post_init__(self):
        if not (0.0 < self.min_phase <= 1.0 <= self.max_phase and math.isfinite(self.max_phase)):
            raise InputError(
                f"need 0 < min_phase <= 1 <= max_phase (finite), got {self.min_phase!r}, {self.max_phase!r}"
            )
        if not (self.touchdown_height_m >= 0.0 and math.isfinite(self.touchdown_height_m)):
            raise InputError(f"touchdown_height_m must be a finite height >= 0 m, got {self.touchdown_height_m!r}")


class GaitLogic:
    """Decides, tick by tick, whether the swing foot has touched down."""

    def __init__(self, params: GaitParams | None = None):
        self.params = params or GaitParams()
        #: Number of touchdowns detected before / after ``T`` / forced.
        self.early = 0
        self.late = 0
        self.forced = 0

    def touchdown(self, phase_unclipped: float, swing_contact: bool | None, swing_height_m: float) -> bool:
        """True if the step ends now.

        Args:
            phase_unclipped: ``(t - t_start) / T``, may exceed 1.
            swing_contact: The swing foot's contact switch, or ``None`` without sensing.
            swing_height_m: Swing contact height above the stance contact, m.
        """
        p = self.params
        if phase_unclipped < p.min_phase:
            return False
        if phase_unclipped >= p.max_phase:
            self.forced += 1
            return True
        landed = swing_contact if swing_contact is not None else swing_height_m <= p.touchdown_height_m
        if landed:
            if phase_unclipped < 1.0:
                self.early += 1
            else:
                self.late += 1
        return bool(landed)


def swing_contact_weight(phase: float) -> float:
    """0 in the air; rises over the last 10% of the step so trackers can blend forces in."""
    if phase <= 0.9:
        return 0.0
    return min(1.0, (phase - 0.9) / 0.1) if math.isfinite(phase) else 0.0
