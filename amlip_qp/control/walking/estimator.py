"""The controller's state estimate.

The estimator is the controller's only window on the plant. It receives a
:class:`Measurement` (the base pose and velocity and the joint positions and
velocities, in Pinocchio coordinates, possibly noisy, plus foot-contact
switches), updates the Pinocchio kinematics once, and derives what the
planner needs: the CoM, ``p_st = c - r_st``, the angular momentum ``L`` about
the stance contact (Kalman-filtered per plane, paper section "Filter for
Angular Momentum") and the CoM vertical velocity.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from amlip_qp.alip import other_side
from amlip_qp.alip.kalman import DEFAULT_MEASUREMENT_VAR, DEFAULT_PROCESS_VAR_RATE, AngularMomentumFilter
from amlip_qp.exceptions import InputError
from amlip_qp.messages import Measurement

__all__ = ["Estimate", "Estimator"]

if TYPE_CHECKING:  # pragma: no cover - typing only
    from amlip_qp.robots.kinematics import RobotKinematics


@dataclass
class Estimate:
    """The estimator's output at one tick (SI units, world axes).

    Attributes:
        com_m: CoM position, m.
        com_vel_mps: CoM velocity, m/s.
        stance_contact_m: Stance contact point, m.
        swing_contact_m: Swing contact point, m.
        p_st_m: ``com - stance_contact``, m.
        L_meas_Nms: ``L`` about the stance contact from the full model, kg m^2/s.
        L_Nms: ``L`` after the Kalman filters (``L_z`` unfiltered), kg m^2/s.
    """

    com_m: np.ndarray
    com_vel_mps: np.ndarray
    stance_contact_m: np.ndarray
    swing_contact_m: np.ndarray
    p_st_m: np.ndarray
    L_meas_Nms: np.ndarray
    L_Nms: np.ndarray


class Estimator:
    """Kinematic state estimate with Kalman filters on ``L``
    (:class:`~amlip_qp.alip.kalman.AngularMomentumFilter`, one scalar filter per plane).

    Args:
        kinematics: The controller's :class:`~amlip_qp.robots.kinematics.RobotKinematics`
            (updated here, once per tick; trackers reuse it).
        dt_s: Control period, s.
        kalman: Filter ``L`` (True) or pass the measurement through (False).
        process_var_rate: Kalman process-noise intensity, (kg m^2/s)^2/s.
        measurement_var: Kalman measurement variance, (kg m^2/s)^2.
    """

    def __init__(
        self,
        kinematics: RobotKinematics,
        dt_s: float,
        kalman: bool = True,
        process_var_rate: float = DEFAULT_PROCESS_VAR_RATE,
        measurement_var: float = DEFAULT_MEASUREMENT_VAR,
    ):
        if not (dt_s > 0 and math.isfinite(dt_s)):
            raise InputError(f"dt_s must be a positive control period in s, got {dt_s!r}")
        self.kin = kinematics
        self.dt_s = float(dt_s)
        self.kalman = bool(kalman)
        self._filter = AngularMomentumFilter(
            kinematics.robot.mass_kg, process_var_rate=process_var_rate, measurement_var=measurement_var
        )
        self._initialised = False

    def reset(self) -> None:
        """Forget the filter state (the next update re-initialises from the measurement)."""
        self._initialised = False

    def observe(self, measurement: Measurement) -> None:
        """Update the kinematics at this tick's measured ``(q, v)`` (once per tick)."""
        self.kin.update(measurement.q, measurement.v)

    def estimate(self, stance: str, touchdown: bool = False) -> Estimate:
        """Estimate at the last observed state with ``stance`` as the stance side.

        Args:
            stance: ``"left"`` or ``"right"``.
            touchdown: True on the tick the stance changed: the filters restart
                from the momentum measured about the new contact point.
        """
        kin = self.kin
        r_st = kin.contact_position(stance)  # raises InputError for a bad side
        r_sw = kin.contact_position(other_side(stance))
        com = kin.com()
        p_st = com - r_st
        L_meas = kin.angular_momentum_about(r_st)
        if not self.kalman:
            L = L_meas.copy()
        elif touchdown or not self._initialised:
            Lx, Ly, _ = L_meas.tolist()
            self._filter.reset(Lx, Ly)
            self._initialised = True
            L = L_meas.copy()
        else:
            Lx, Ly, Lz = L_meas.tolist()
            px, py, _ = p_st.tolist()
            L = np.array([*self._filter.step(px, py, Lx, Ly, self.dt_s), Lz])
        return Estimate(
            com_m=com,
            com_vel_mps=kin.com_velocity(),
            stance_contact_m=r_st,
            swing_contact_m=r_sw,
            p_st_m=p_st,
            L_meas_Nms=L_meas,
            L_Nms=L,
        )
