"""Validated numpy API of the ALIP model: flow, predictor, momentum transfer
at touchdown and deadbeat foot placement.

The arithmetic lives once in :mod:`amlip_qp.alip.formulas`; this module only
checks its inputs and calls it. Every function works on the generic pair
``(p, L)`` of ``docs/ALIP_NOTES.md``: the sagittal pair is
``(p_x, L_y)`` and the lateral pair is ``(p_y, Lt)`` with ``Lt = -L_x``.
:func:`transfer_3d` is the one 3-D convenience; it does the pair mapping for
the caller.

Units (SI): ``p`` in m, ``L`` in kg m^2/s (= N m s), times in s, mass in kg,
heights in m, velocities in m/s, ``g_mps2`` in m/s^2 (positive). Scalars and
numpy arrays of matching shape are both accepted (the arithmetic broadcasts).
Bad input raises :class:`amlip_qp.exceptions.InputError`.
"""

from __future__ import annotations

import numpy as np

from amlip_qp.alip import _checks as C
from amlip_qp.alip import formulas as F
from amlip_qp.exceptions import InputError

GRAVITY_MPS2 = F.GRAVITY_MPS2


def _model(mass_kg, H_m, g_mps2) -> None:
    C.positive("mass_kg", mass_kg, "kg")
    C.positive("H_m (CoM height over the contact)", H_m, "m")
    C.positive("g_mps2 (gravity magnitude)", g_mps2, "m/s^2")


def omega(H_m, g_mps2=GRAVITY_MPS2):
    """LIP natural frequency ``l = sqrt(g / H)`` in 1/s, for ``H_m`` in m."""
    C.positive("H_m (CoM height over the contact)", H_m, "m")
    C.positive("g_mps2 (gravity magnitude)", g_mps2, "m/s^2")
    return F.omega(H_m, g_mps2)


def flow(p_m, L_Nms, tau_s, mass_kg, H_m, g_mps2=GRAVITY_MPS2):
    """Flow the pair ``(p, L)`` forward by ``tau_s >= 0`` seconds of zero-torque LIP motion.

    Args:
        p_m: CoM minus contact along the pair's axis, m.
        L_Nms: the pair's angular momentum about the contact, kg m^2/s.
        tau_s: horizon, s (>= 0; a negative horizon raises InputError).
        mass_kg, H_m, g_mps2: total mass (kg), CoM height (m), gravity (m/s^2).

    Returns:
        ``(p(t+tau) in m, L(t+tau) in kg m^2/s)``.
    """
    C.finite("p_m", p_m)
    C.finite("L_Nms", L_Nms)
    C.non_negative("tau_s (horizon)", tau_s, "s")
    _model(mass_kg, H_m, g_mps2)
    return F.flow(p_m, L_Nms, tau_s, mass_kg, H_m, g_mps2)


def predict_end_of_step(p_m, L_Nms, t_remaining_s, mass_kg, H_m, g_mps2=GRAVITY_MPS2):
    """Predicted ``(p(T-), L(T-))`` of the current step (paper eq. LIP_AM_Preiction).

    ``t_remaining_s`` (s, >= 0) is the time left in the step; ``p_m`` (m) and
    ``L_Nms`` (kg m^2/s) are the current pair values. Returns ``(p_hat in m,
    L_hat in kg m^2/s)``. A late touchdown must be handled by the caller by
    clamping the remaining time to 0 (see :func:`amlip_qp.alip.phase.time_remaining`).
    """
    C.finite("p_m", p_m)
    C.finite("L_Nms", L_Nms)
    C.non_negative("t_remaining_s (prediction horizon)", t_remaining_s, "s")
    _model(mass_kg, H_m, g_mps2)
    return F.flow(p_m, L_Nms, t_remaining_s, mass_kg, H_m, g_mps2)


def transfer(L_minus_Nms, p_st_m, p_sw_m, v_z_mps, mass_kg, dz_m=0.0, v_mps=0.0):
    """Pair momentum about the new contact just after touchdown.

    ``L(T+) = L(T-) + m v_z (p_st(T-) - p_sw(T-)) - m dz v`` where ``p_st`` and
    ``p_sw`` (m) are the CoM offsets from the old and the new contact along the
    pair's axis, ``v_z_mps`` the CoM vertical velocity (m/s), ``L_minus_Nms`` the
    pair momentum about the old contact (kg m^2/s), ``dz_m`` the new contact's
    height minus the old one's (m; 0 on flat ground) and ``v_mps`` the CoM's
    horizontal velocity along the pair's axis (m/s; ``v_y`` for the lateral pair
    ``Lt = -L_x``). Returns ``L(T+)`` in kg m^2/s.
    """
    C.finite("L_minus_Nms", L_minus_Nms)
    C.finite("p_st_m", p_st_m)
    C.finite("p_sw_m", p_sw_m)
    C.finite("v_z_mps", v_z_mps)
    C.finite("dz_m", dz_m)
    C.finite("v_mps", v_mps)
    C.positive("mass_kg", mass_kg, "kg")
    return F.transfer(L_minus_Nms, p_st_m, p_sw_m, v_z_mps, mass_kg, dz_m, v_mps)


def transfer_3d(L_minus_world_Nms, p_st_world_m, p_sw_world_m, v_com_world_mps, mass_kg) -> np.ndarray:
    """World-frame momentum ``(L_x, L_y)`` about the new contact after touchdown.

    Args:
        L_minus_world_Nms: (3,) angular momentum about the old (stance) contact, world axes, kg m^2/s.
        p_st_world_m: (3,) CoM minus old contact, world axes, m.
        p_sw_world_m: (3,) CoM minus new contact, world axes, m.
        v_com_world_mps: (3,) CoM velocity, world axes, m/s.
        mass_kg: total mass, kg.

    Returns:
        ``np.array([L_x, L_y])`` about the new contact, kg m^2/s.

    It applies the generic :func:`transfer` to the sagittal pair ``(p_x, L_y)``
    and to the lateral pair ``(p_y, Lt = -L_x)`` with the contacts' height
    difference ``dz = r_2z - r_1z = p_st_z - p_sw_z``. That is the exact
    ``L_2 = L_1 + (r_1 - r_2) x m v_c`` (x and y components), on any ground.
    """
    L = C.vector("L_minus_world_Nms", L_minus_world_Nms, 3)
    p_st = C.vector("p_st_world_m", p_st_world_m, 3)
    p_sw = C.vector("p_sw_world_m", p_sw_world_m, 3)
    v = C.vector("v_com_world_mps", v_com_world_mps, 3)
    C.positive("mass_kg", mass_kg, "kg")
    dz = p_st[2] - p_sw[2]
    L_y = F.transfer(L[1], p_st[0], p_sw[0], v[2], mass_kg, dz, v[0])
    Lt = F.transfer(-L[0], p_st[1], p_sw[1], v[2], mass_kg, dz, v[1])
    return np.array([-Lt, L_y])


def foot_placement(L_des_Nms, L_hat_Nms, T_s, mass_kg, H_m, g_mps2=GRAVITY_MPS2):
    """Deadbeat foot placement without the ``v_z`` correction (paper eq. Desired_Footplacement).

    ``p_sw^des = (L_des - cosh(lT) L_hat) / (m H l sinh(lT))`` in m: the CoM minus
    swing contact at touchdown along the pair's axis that makes the pair momentum
    at the end of the *next* step equal ``L_des_Nms`` (kg m^2/s). ``L_hat_Nms``
    is the predicted ``L(T-)`` of the current step, ``T_s`` the step duration (s).
    """
    C.finite("L_des_Nms", L_des_Nms)
    C.finite("L_hat_Nms", L_hat_Nms)
    C.positive("T_s (step duration)", T_s, "s")
    _model(mass_kg, H_m, g_mps2)
    return F.foot_placement(L_des_Nms, L_hat_Nms, 0.0, T_s, mass_kg, H_m, 0.0, g_mps2)


def vz_limit(T_s, H_m, g_mps2=GRAVITY_MPS2):
    """Upper bound (m/s) on the ``v_z`` the ``v_z``-corrected law accepts: ``H l tanh(lT)``.

    At ``v_z = H l tanh(lT)`` the law's denominator ``m (H l sinh(lT) - v_z cosh(lT))``
    vanishes and the foot placement is undefined; above it the sign flips.
    Negative ``v_z`` only enlarges the denominator.
    """
    C.positive("T_s (step duration)", T_s, "s")
    l = omega(H_m, g_mps2)
    return H_m * l * np.tanh(l * T_s)


def foot_placement_vz(L_des_Nms, L_hat_Nms, p_hat_m, v_z_mps, T_s, mass_kg, H_m, g_mps2=GRAVITY_MPS2, dz_m=0.0):
    """Deadbeat foot placement with the full momentum transfer at touchdown.

    ``p_sw^des = [L_des - cosh(lT)(L_hat + m v_z p_hat - dz L_hat / H)] / [m (H l sinh(lT) - v_z cosh(lT))]``
    in m (notes, "Foot placement"; the paper's typeset denominator is wrong;
    the ``dz`` term: docs/ALIP_SLOPES.md). ``p_hat_m`` is the predicted
    ``p_st(T-)`` (m), ``v_z_mps`` the predicted CoM vertical velocity at
    touchdown (m/s), ``dz_m`` the next contact's height minus the stance
    contact's (m), the other arguments as in :func:`foot_placement`. Raises
    InputError when ``v_z >= H l tanh(lT)`` (:func:`vz_limit`), where the law
    has no solution, and when ``|dz| >= H``.
    """
    C.finite("L_des_Nms", L_des_Nms)
    C.finite("L_hat_Nms", L_hat_Nms)
    C.finite("p_hat_m", p_hat_m)
    C.finite("v_z_mps", v_z_mps)
    C.finite("dz_m", dz_m)
    C.positive("T_s (step duration)", T_s, "s")
    _model(mass_kg, H_m, g_mps2)
    if np.any(np.abs(np.asarray(dz_m, dtype=float)) >= H_m):
        raise InputError(
            f"dz_m={dz_m!r} m must be smaller in size than H_m={H_m!r} m (the CoM height over the contact)"
        )
    limit = vz_limit(T_s, H_m, g_mps2)
    if np.any(np.asarray(v_z_mps, dtype=float) >= limit):
        raise InputError(
            f"v_z_mps={v_z_mps!r} m/s is at or above H l tanh(lT) = {limit:.4g} m/s, where the v_z-corrected "
            "foot placement has no solution; pass a smaller predicted vertical velocity"
        )
    return F.foot_placement(L_des_Nms, L_hat_Nms, p_hat_m, T_s, mass_kg, H_m, v_z_mps, g_mps2, dz_m)
