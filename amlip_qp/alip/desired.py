"""Desired angular momentum ``L^des(T_{k+1}-)`` at the end of the next step.

``L^des`` is decided in the heading frame of the next step ``D_{k+1}`` and
rotated to world axes (paper section 3, "Turning"). Its parts:

- forward speed: ``L_y = m H v_x`` (:func:`formulas.L_from_velocity`);
- walking in place with step width ``W``:
  ``L_x = +-(1/2) m H W l tanh(lT/2)``, ``+`` when the next stance leg is the
  left one (:func:`formulas.Lt_step_width`, which returns ``Lt = -L_x``);
- lateral speed (diagonal walking): ``L_x += -m H v_y``.

Velocities here are the CoM velocity *at the end of a step* (``T-``), the
quantity the paper's ``L = m H v`` describes. On the periodic LIP gait the
*mean* velocity over a step is smaller by the factor ``tanh(lT/2) / (lT/2)``;
:func:`end_of_step_velocity` and :func:`mean_step_velocity` convert between them.

Units: velocities m/s, widths and heights m, times s, mass kg, angles rad,
momenta kg m^2/s, ``g_mps2`` m/s^2.
"""

from __future__ import annotations

import math

import numpy as np

from amlip_qp.alip import _checks as C
from amlip_qp.alip import formulas as F

GRAVITY_MPS2 = F.GRAVITY_MPS2


def stance_sign(side: str) -> float:
    """``+1.0`` for ``"left"``, ``-1.0`` for ``"right"`` (the sign convention of the step-width term)."""
    return 1.0 if C.side("side", side) == "left" else -1.0


def other_side(side: str) -> str:
    """The other leg: ``"right"`` for ``"left"`` and vice versa."""
    return "right" if C.side("side", side) == "left" else "left"


def _model(mass_kg, H_m) -> None:
    C.positive("mass_kg", mass_kg, "kg")
    C.positive("H_m (CoM height over the contact)", H_m, "m")


def Ly_from_forward_speed(vx_mps, mass_kg, H_m):
    """Sagittal ``L_y^des = m H v_x`` in kg m^2/s for the end-of-step forward speed ``vx_mps`` (m/s)."""
    C.finite("vx_mps", vx_mps)
    _model(mass_kg, H_m)
    return F.L_from_velocity(vx_mps, mass_kg, H_m)


def Lx_from_lateral_speed(vy_mps, mass_kg, H_m):
    """Lateral ``L_x^des = -m H v_y`` in kg m^2/s for the end-of-step lateral speed ``vy_mps`` (m/s)."""
    C.finite("vy_mps", vy_mps)
    _model(mass_kg, H_m)
    return -F.L_from_velocity(vy_mps, mass_kg, H_m)


def Lx_from_step_width(W_m, T_s, mass_kg, H_m, next_stance: str, g_mps2=GRAVITY_MPS2):
    """Lateral ``L_x^des`` (kg m^2/s) of walking in place with step width ``W_m`` (m).

    ``+(1/2) m H W l tanh(lT/2)`` when ``next_stance`` is ``"left"``, the
    opposite when ``"right"`` (paper eq. lateral_desired_Lx); ``T_s`` is the
    step duration (s).
    """
    C.non_negative("W_m (step width)", W_m, "m")
    C.positive("T_s (step duration)", T_s, "s")
    C.positive("g_mps2", g_mps2, "m/s^2")
    _model(mass_kg, H_m)
    return -F.Lt_step_width(W_m, T_s, mass_kg, H_m, stance_sign(next_stance), g_mps2)


def desired_L_heading(vx_mps, vy_mps, W_m, T_s, mass_kg, H_m, next_stance: str, g_mps2=GRAVITY_MPS2) -> np.ndarray:
    """``L^des = (L_x, L_y)`` in the heading frame of the next step, kg m^2/s.

    ``vx_mps``, ``vy_mps``: end-of-step CoM velocity in that heading frame (m/s);
    ``W_m``: step width (m); ``next_stance``: the leg in stance during the next step.
    """
    L_y = Ly_from_forward_speed(vx_mps, mass_kg, H_m)
    L_x = Lx_from_lateral_speed(vy_mps, mass_kg, H_m) + Lx_from_step_width(W_m, T_s, mass_kg, H_m, next_stance, g_mps2)
    return np.array([L_x, L_y], dtype=float)


def desired_L_world(
    vx_mps, vy_mps, W_m, T_s, mass_kg, H_m, next_stance: str, heading_next_rad, g_mps2=GRAVITY_MPS2
) -> np.ndarray:
    """``L^des = (L_x, L_y)`` in world axes (kg m^2/s): :func:`desired_L_heading`
    rotated by the next step's heading ``heading_next_rad`` (rad)."""
    desired_L_heading(vx_mps, vy_mps, W_m, T_s, mass_kg, H_m, next_stance, g_mps2)  # validates the inputs
    C.finite("heading_next_rad", heading_next_rad)
    L = F.desired_L_world(vx_mps, vy_mps, W_m, T_s, mass_kg, H_m, stance_sign(next_stance), heading_next_rad, g_mps2)
    return np.array(L, dtype=float)


def mean_to_end_factor(T_s, H_m, g_mps2=GRAVITY_MPS2) -> float:
    """Ratio ``v(T-) / v_mean = (lT/2) / tanh(lT/2)`` (>= 1) on the periodic LIP gait (dimensionless)."""
    C.positive("T_s (step duration)", T_s, "s")
    C.positive("H_m (CoM height over the contact)", H_m, "m")
    C.positive("g_mps2", g_mps2, "m/s^2")
    half = 0.5 * math.sqrt(g_mps2 / H_m) * T_s
    return half / math.tanh(half)


def end_of_step_velocity(v_mean_mps, T_s, H_m, g_mps2=GRAVITY_MPS2):
    """End-of-step CoM velocity (m/s) of the periodic LIP gait whose mean velocity over a step is ``v_mean_mps``.

    On that gait the CoM goes from ``-a`` to ``+a`` over the stance foot in ``T``
    seconds (mean ``2a/T``) and ends at ``a l coth(lT/2)``. Applies per axis.
    """
    C.finite("v_mean_mps", v_mean_mps)
    return v_mean_mps * mean_to_end_factor(T_s, H_m, g_mps2)


def mean_step_velocity(v_end_mps, T_s, H_m, g_mps2=GRAVITY_MPS2):
    """Mean CoM velocity over a step (m/s) of the periodic LIP gait that ends each step at ``v_end_mps``."""
    C.finite("v_end_mps", v_end_mps)
    return v_end_mps / mean_to_end_factor(T_s, H_m, g_mps2)
