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
class AchillesLinkage:
    """The achilles rod of a Cassie leg as the simplified spring model sees it (:mod:`amlip_qp.control.pbc.springs`).

    Attributes:
        shin_ratio: ``a_s / a_t``, the rod's moment arm about the shin (knee
            spring) joint over its arm about the tarsus joint (dimensionless).
        heel_ratio: ``a_h / a_t``, its arm about the heel-spring joint over its
            arm about the tarsus joint (dimensionless, > 0).
        heel_stiffness_Nmprad: The heel spring's stiffness, N m/rad (> 0).
    """

    shin_ratio: float
    heel_ratio: float
    heel_stiffness_Nmprad: float

    def __post_init__(self):
        vals = (self.shin_ratio, self.heel_ratio, self.heel_stiffness_Nmprad)
        if not (all(np.isfinite(vals)) and self.heel_ratio > 0 and self.heel_stiffness_Nmprad > 0):
            raise InputError(
                f"achilles linkage: ratios must be finite, heel_ratio and heel stiffness > 0, got {self!r}"
            )


#: Cassie's achilles rod: the moment-arm ratios of the parameter sheet's linkage at the ``stand``
#: keyframe (knee -1.1997 rad), measured on ``cassie-closed-chain.xml`` by differentiating the
#: rod's end-to-end distance (``tests/test_control_pbc_springs.py``); heel spring 1250 N m/rad.
CASSIE_ACHILLES = AchillesLinkage(shin_ratio=1.3604, heel_ratio=0.8077, heel_stiffness_Nmprad=1250.0)


#: The loads the spring model can be given (:attr:`PBCGains.spring_model_load`).
SPRING_MODEL_LOADS = ("weight", "commanded")


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
        spring_model_linkage: The leg's achilles linkage for the spring model
            (:class:`~amlip_qp.control.pbc.springs.AchillesLinkage`: the rod's
            moment on the shin and the heel spring's lever), or ``None`` for the
            controller model's own springs (the tendon of ``cassie.xml``).
        spring_model_load: The load of the spring model: ``"weight"`` (the
            whole weight ``m g``, vertical, at the stance contact) or
            ``"commanded"`` (the PBC's commanded contact force of the previous
            tick). ``docs/TUNING.md`` ("Spring model") says why Cassie uses the weight.
        hip_yaw_feedback: Gain (dimensionless, 0..1, 0 disables) of the pelvis-yaw
            feedback on the swing hip-yaw reference
            (:mod:`amlip_qp.control.pelvis_yaw`, shared with the QP tracker).
        swing_ankle_gain_scale: Factor (>= 1 in practice, > 0) on ``K_p`` of the
            swing leg's ankle (the joint the contact frame hangs on, held passive
            in stance), and its square root on ``K_d`` (same damping ratio). The
            PD is an acceleration, so its torque scales with the ankle's own tiny
            inertia (Cassie: about 0.013 kg m^2, i.e. about 5 N m/rad at 400
            1/s^2); a plant whose foot carries more than the model (a crank,
            a rod, their damping) then pulls the swing foot off its pitch
            reference. ``docs/TUNING.md`` ("Closed-chain plant: the swing
            ankle") has the numbers.
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
    spring_model_linkage: AchillesLinkage | None = None
    spring_model_load: str = "commanded"
    hip_yaw_feedback: float = 0.0
    swing_ankle_gain_scale: float = 1.0

    def __post_init__(self):
        if self.spring_model_load not in SPRING_MODEL_LOADS:
            raise InputError(
                f"spring_model_load must be one of {', '.join(SPRING_MODEL_LOADS)}, got {self.spring_model_load!r}"
            )
        if self.spring_model_linkage is not None and not isinstance(self.spring_model_linkage, AchillesLinkage):
            raise InputError(
                f"spring_model_linkage must be an AchillesLinkage or None, got {self.spring_model_linkage!r}"
            )
        vals = [getattr(self, f) for f in self.__dataclass_fields__ if not f.startswith("spring_model")]
        if (
            not all(np.isfinite(v) and v >= 0 for v in vals)
            or self.touchdown_gain_drop > 1
            or self.swing_start_fraction > 1
            or self.swing_ramp_phase <= 0
            or self.swing_torso_compensation > 1
            or self.hip_yaw_feedback > 1
            or self.swing_ankle_gain_scale <= 0
        ):
            raise InputError(
                "PBC gains must be finite and >= 0 (touchdown_gain_drop, swing_start_fraction, "
                "swing_torso_compensation, hip_yaw_feedback <= 1, "
                f"swing_ramp_phase, swing_ankle_gain_scale > 0), got {self!r}"
            )

    def swing_scale(self, phase: float, contact_weight: float) -> float:
        """Factor (dimensionless) on the swing leg's gains at this phase and touchdown weight."""
        s = float(phase) if math.isfinite(phase) else 1.0
        w = min(1.0, max(0.0, float(contact_weight))) if math.isfinite(contact_weight) else 0.0
        ramp = min(1.0, max(0.0, s) / self.swing_ramp_phase)
        start = self.swing_start_fraction + (1.0 - self.swing_start_fraction) * ramp
        return start * (1.0 - self.touchdown_gain_drop * w)


#: Cassie (leg springs): stiffer stance gains (critically damped, 2 sqrt(500) = 44.72 1/s), a
#: stiffer swing ankle, swing-leg torso compensation, pelvis-yaw feedback on the swing hip yaw, the
#: paper's spring model (the robot's achilles linkage under the robot's weight). docs/TUNING.md
#: ("Closed-chain plant: the stance gains") has the measurements behind the stance gains.
CASSIE_GAINS = PBCGains(
    kp_stance_ps2=500.0,
    kd_stance_ps=44.72,
    kp_swing_ps2=400.0,
    kd_swing_ps=40.0,
    swing_ankle_gain_scale=10.0,
    swing_torso_compensation=1.0,
    hip_yaw_feedback=1.0,
    spring_model_offset=True,
    spring_model_linkage=CASSIE_ACHILLES,
    spring_model_load="weight",
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
