"""Gains of the PBC tracker, and the tuned gains of each bundled robot.

The robot profiles (:mod:`amlip_qp.profiles`) register :data:`CASSIE_GAINS`
and :data:`RABBIT_GAINS` as their ``"pbc"`` tracker configuration;
:func:`default_gains` reads them from there. The measured tuning behind them
is in ``docs/TUNING.md`` ("PBC tracker and walking loop").

This module imports numpy only, so reading a profile's ``"pbc"``
configuration does not load the tracker.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from amlip_qp.exceptions import InputError

if TYPE_CHECKING:  # pragma: no cover - typing only
    from amlip_qp.robots.robot import Robot


@dataclass(frozen=True)
class PBCGains:
    """Gains of the PBC (acceleration level) and of its fallback (torque level).

    Attributes:
        kp_stance_ps2: ``K_p`` on the stance leg's joints, 1/s^2.
        kd_stance_ps: ``K_d`` on the stance leg's joints, 1/s.
        kp_swing_ps2: ``K_p`` on the swing leg's joints, 1/s^2.
        kd_swing_ps: ``K_d`` on the swing leg's joints, 1/s.
        swing_start_fraction: Swing gains at the start of a step, as a fraction
            of the full gains (phase schedule: the swing leg leaves the ground
            with the old stance leg's velocity, far from the reference's).
        swing_ramp_phase: Phase over which the swing gains ramp linearly to full.
        touchdown_gain_drop: Fraction by which the swing gains drop as
            ``target.swing_contact_weight`` goes from 0 to 1 (softer landing).
        fallback_kp_Nmprad: Fallback joint stiffness, N m/rad.
        fallback_kd_Nmsprad: Fallback joint damping, N m s/rad.
        swing_torso_compensation: Fraction (0..1) of the torso-orientation error
            the swing leg compensates: its joint references are moved to the IK
            solution for the *measured* torso pitch/roll (first order, through
            the IK's ``A^-1``), so the swing foot follows its output reference
            relative to the CoM even when the torso is off its reference.
        spring_model_offset: The paper's spring compensation ("Springs"): the IK
            holds the springs at the deflections of the simplified model
            (:func:`~amlip_qp.control.pbc.springs.spring_deflections_rad` on the
            stance leg under the previous tick's commanded contact force; the
            swing leg rigid at rest) instead of at their encoder estimates; the
            stance knee reference then carries the compensating offset, exactly,
            through the IK.
    """

    kp_stance_ps2: float = 400.0
    kd_stance_ps: float = 40.0
    kp_swing_ps2: float = 400.0
    kd_swing_ps: float = 40.0
    swing_start_fraction: float = 1.0
    swing_ramp_phase: float = 0.2
    touchdown_gain_drop: float = 0.0
    fallback_kp_Nmprad: float = 100.0
    fallback_kd_Nmsprad: float = 5.0
    swing_torso_compensation: float = 0.0
    spring_model_offset: bool = False

    def __post_init__(self):
        vals = [getattr(self, f) for f in self.__dataclass_fields__ if f != "spring_model_offset"]
        if (
            not all(np.isfinite(v) and v >= 0 for v in vals)
            or self.touchdown_gain_drop > 1
            or self.swing_start_fraction > 1
            or self.swing_ramp_phase <= 0
            or self.swing_torso_compensation > 1
        ):
            raise InputError(
                "PBC gains must be finite and >= 0 (touchdown_gain_drop, swing_start_fraction <= 1, "
                f"swing_ramp_phase > 0), got {self!r}"
            )

    def swing_scale(self, phase: float, contact_weight: float) -> float:
        """Factor (dimensionless) on the swing leg's gains at this phase and touchdown weight."""
        s = float(phase) if math.isfinite(phase) else 1.0
        w = min(1.0, max(0.0, float(contact_weight))) if math.isfinite(contact_weight) else 0.0
        ramp = min(1.0, max(0.0, s) / self.swing_ramp_phase)
        start = self.swing_start_fraction + (1.0 - self.swing_start_fraction) * ramp
        return start * (1.0 - self.touchdown_gain_drop * w)


#: Cassie (leg springs): softer stance gains, swing-leg torso compensation, the paper's spring model.
CASSIE_GAINS = PBCGains(
    kp_stance_ps2=200.0,
    kd_stance_ps=28.0,
    kp_swing_ps2=400.0,
    kd_swing_ps=40.0,
    swing_torso_compensation=1.0,
    spring_model_offset=True,
)

#: Rabbit (rigid legs): the defaults, 400 1/s^2 and 40 1/s on both legs, no torso compensation.
RABBIT_GAINS = PBCGains()


def default_gains(robot: Robot) -> PBCGains:
    """The tuned PBC gains of ``robot``.

    A bundled robot gets its profile's ``"pbc"`` configuration
    (:meth:`amlip_qp.profiles.RobotProfile.tracker_config`). Any other model
    (an MJCF file that is not a bundled robot) gets the gains of the bundled
    robot it resembles: :data:`CASSIE_GAINS` if it has springs (a coupling or
    a passive joint), :data:`RABBIT_GAINS` otherwise. They are a starting
    point, not a tuning for that model.

    Raises:
        InputError: The profile's ``"pbc"`` entry is not a :class:`PBCGains`.
    """
    profile = robot.profile
    if profile is not None and "pbc" in profile.tracker_configs:
        gains = profile.tracker_config("pbc")
        if not isinstance(gains, PBCGains):
            raise InputError(f"robot {robot.name!r}: the 'pbc' tracker configuration is not PBCGains: {gains!r}")
        return gains
    if robot.couplings or len(robot.passive_v_idx):
        return CASSIE_GAINS
    return RABBIT_GAINS
