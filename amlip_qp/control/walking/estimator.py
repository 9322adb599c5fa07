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
from dataclasses import dataclass, fields
from typing import TYPE_CHECKING

import numpy as np

from amlip_qp.alip import other_side
from amlip_qp.alip.kalman import DEFAULT_MEASUREMENT_VAR, DEFAULT_PROCESS_VAR_RATE, AngularMomentumFilter
from amlip_qp.exceptions import InputError
from amlip_qp.messages import Measurement, StateEstimate

__all__ = ["Estimate", "Estimator", "planner_state"]

_F64 = np.dtype(np.float64)
_VECTOR3 = (3,)
#: The slot setters of :class:`~amlip_qp.messages.StateEstimate`'s fields, in field order.
_STATE_SETTERS = tuple(getattr(StateEstimate, f.name).__set__ for f in fields(StateEstimate))

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


def planner_state(
    stance: str, p_st_m: np.ndarray, L_Nms: np.ndarray, v_z_mps: float, t_in_step_s: float, com_m: np.ndarray
) -> StateEstimate:
    """The planner's :class:`~amlip_qp.messages.StateEstimate` of one tick: ``StateEstimate(stance=stance,
    ...)`` with the fields in their order, positional, the same object (tested), made cheaper for the
    controller's per-tick estimate (three float64 3-vectors and two floats, checked as the constructor
    checks them: sides, shapes, one finite sum, ``t_in_step_s >= 0``); anything else, and every failed
    check, goes through the constructor (its conversions and errors)."""
    if (
        (stance == "left" or stance == "right")
        and type(p_st_m) is np.ndarray and type(L_Nms) is np.ndarray and type(com_m) is np.ndarray
        and p_st_m.dtype is _F64 and L_Nms.dtype is _F64 and com_m.dtype is _F64
        and p_st_m.shape == L_Nms.shape == com_m.shape == _VECTOR3
        and type(v_z_mps) is float and type(t_in_step_s) is float and t_in_step_s >= 0.0
    ):  # fmt: skip
        p0, p1, p2 = p_st_m.tolist()
        L0, L1, L2 = L_Nms.tolist()
        c0, c1, c2 = com_m.tolist()
        # one finiteness test, as the constructor's: NaN and inf propagate through a sum
        if math.isfinite(p0 + p1 + p2 + (L0 + L1 + L2) + (c0 + c1 + c2) + v_z_mps + t_in_step_s):
            new = object.__new__(StateEstimate)
            put_stance, put_p, put_L, put_vz, put_t, put_com = _STATE_SETTERS
            put_stance(new, stance)
            put_p(new, p_st_m)
            put_L(new, L_Nms)
            put_vz(new, v_z_mps)
            put_t(new, t_in_step_s)
            put_com(new, com_m)
            return new
    return StateEstimate(
        stance=stance, p_st_m=p_st_m, L_Nms=L_Nms, v_z_mps=v_z_mps, t_in_step_s=t_in_step_s, com_m=com_m
    )
