"""Gains of the PBC tracker, and the tuned gains of each bundled robot.

Each robot's tuned gains are a table of its profile file (``[trackers.pbc]``,
:mod:`amlip_qp.profiles`), turned into :class:`PBCGains` by
:func:`gains_from_table`; :func:`default_gains` looks them up. The measured tuning behind them
is in ``docs/TUNING.md`` ("PBC tracker and walking loop").

This module imports numpy only, so reading a profile's ``"pbc"``
configuration does not load the tracker.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, fields
from typing import TYPE_CHECKING, Any

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
        shortest_step_s: The shortest step the PBC's swing leg follows, s (0: no bound): the
            tracker's :attr:`~amlip_qp.control.tracker.Tracker.shortest_step_s`, below which the
            step-timing MPC plans no step. ``docs/TUNING.md`` ("The PBC's shortest step") has
            the numbers.
        release_pulling_contact: When the tick's solve of (1)-(3) gives the stance contact a
            negative normal force (the ground would have to pull the foot), solve the tick again
            without the stance contact's rows: the foot free and its force zero, the springs still
            held (:func:`~amlip_qp.control.pbc.contact_release.solve_released`). Off by
            default: the paper's PBC holds the contact as an equality in every tick.
            ``docs/TUNING.md`` ("The PBC's pulling contact") has the measurements.
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
    shortest_step_s: float = 0.0
    release_pulling_contact: bool = False

    def __post_init__(self):
        if not isinstance(self.release_pulling_contact, bool):
            raise InputError(f"release_pulling_contact must be True or False, got {self.release_pulling_contact!r}")
        if self.spring_model_load not in SPRING_MODEL_LOADS:
            raise InputError(
                f"spring_model_load must be one of {', '.join(SPRING_MODEL_LOADS)}, got {self.spring_model_load!r}"
            )
        if self.spring_model_linkage is not None and not isinstance(self.spring_model_linkage, AchillesLinkage):
            raise InputError(
                f"spring_model_linkage must be an AchillesLinkage or None, got {self.spring_model_linkage!r}"
            )
        flags = ("release_pulling_contact",)
        vals = [getattr(self, f) for f in self.__dataclass_fields__ if not (f.startswith("spring_model") or f in flags)]
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


def gains_from_table(table: Mapping[str, Any]) -> PBCGains:
    """:class:`PBCGains` from a profile's ``[trackers.pbc]`` table (field name -> value; the
    sub-table ``spring_model_linkage`` gives the :class:`AchillesLinkage`); every other field keeps
    its default.

    Raises:
        InputError: An unknown key (naming the known ones), a value of the wrong type, or a value
            :class:`PBCGains` refuses.
    """
    known = {f.name for f in fields(PBCGains)}
    kwargs: dict[str, Any] = {}
    for key, value in table.items():
        if key not in known:
            raise InputError(f"unknown key {key!r} (known: {', '.join(sorted(known))})")
        if key == "spring_model_linkage":
            link_known = {f.name for f in fields(AchillesLinkage)}
            if not isinstance(value, Mapping) or set(value) != link_known:
                raise InputError(f"spring_model_linkage must be a table of {', '.join(sorted(link_known))}")
            if not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in value.values()):
                raise InputError(f"spring_model_linkage's values must be numbers, got {dict(value)!r}")
            kwargs[key] = AchillesLinkage(**{k: float(v) for k, v in value.items()})
        elif key in ("spring_model_offset", "release_pulling_contact"):
            if not isinstance(value, bool):
                raise InputError(f"{key} must be true or false, got {value!r}")
            kwargs[key] = value
        elif key == "spring_model_load":
            kwargs[key] = value
        elif isinstance(value, bool) or not isinstance(value, (int, float)):
            raise InputError(f"{key} must be a number, got {value!r}")
        else:
            kwargs[key] = float(value)
    return PBCGains(**kwargs)


def default_gains(robot: Robot) -> PBCGains:
    """The tuned PBC gains of ``robot``.

    A robot with a profile gets its ``[trackers.pbc]`` table
    (:meth:`amlip_qp.profiles.RobotProfile.tracker_config`). Any other model
    (an MJCF file without a profile) gets the gains of a bundled robot it
    resembles: one with springs if it has springs (a coupling or a passive
    joint), one without otherwise. They are a starting point, not a tuning
    for that model.

    Raises:
        InputError: The profile's ``[trackers.pbc]`` table is invalid, or its ``[unsupported]``
            table says why the PBC does not run on this robot.
    """
    from amlip_qp.profiles import PROFILES

    profile = robot.profile
    if profile is not None:
        profile.check_supported("pbc")
    if profile is None or "pbc" not in profile.trackers:
        from amlip_qp.robots.outputs import output_names

        springy = bool(robot.couplings or len(robot.passive_v_idx))
        names = output_names(robot)
        candidates = [p for p in PROFILES.values() if "pbc" in p.trackers]
        # the same outputs and springs, else the same springs, else any
        profile = next(
            (p for p in candidates if _has_springs(p) == springy and p.outputs == names),
            next((p for p in candidates if _has_springs(p) == springy), candidates[0]),
        )
    return profile.tracker_config("pbc")


def _has_springs(profile) -> bool:
    """Whether a bundled profile's PBC gains are tuned for legs with springs (they model them)."""
    return bool(profile.trackers["pbc"].get("spring_model_offset", False))
