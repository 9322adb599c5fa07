"""The ALIP formulas, written once for numpy and CasADi.

Every function here is plain arithmetic on its arguments plus ``cosh``,
``sinh``, ``sqrt``, ``cos`` and ``sin`` taken from the arguments' backend:
numpy for floats and arrays, CasADi for ``SX``/``MX``/``DM`` symbols. The
numpy entry points with input validation live in :mod:`amlip_qp.alip.lip`,
:mod:`amlip_qp.alip.desired` and :mod:`amlip_qp.alip.outputs`; the CasADi code
generation in :mod:`amlip_qp.codegen.symbolic` calls these same functions
with symbols, so the generated C and the numpy reference cannot drift apart.

They work on the generic pair ``(p, L)`` of ``docs/ALIP_NOTES.md``:
the sagittal pair is ``(p_x, L_y)`` and the lateral pair is ``(p_y, Lt)``
with ``Lt = -L_x``. No validation happens here.

Units: p in m, L in kg m^2/s, times in s, mass in kg, heights in m,
velocities in m/s, g in m/s^2 (positive), phase ``s`` dimensionless.
"""

from __future__ import annotations

import numpy as np

#: Standard gravity, m/s^2 (positive; gravity points along -z).
GRAVITY_MPS2 = 9.81

#: The share of a step down that the CoM takes before the touchdown (:func:`stance_height`): 0
#: holds it at ``H`` over the stance contact to the end (the swing leg then reaches down the whole
#: drop below ``H``), 1 brings it to ``H`` over the lower landing point. Measured: docs/TUNING.md,
#: "The CoM's share of a step down".
DOWNHILL_COM_SHARE = 0.5


def backend(*args):
    """Return the math module for the arguments: ``casadi`` if any argument is
    a CasADi expression, else ``numpy``."""
    for a in args:
        if type(a).__module__.split(".")[0] == "casadi":
            import casadi

            return casadi
    return np


def omega(H_m, g_mps2=GRAVITY_MPS2):
    """LIP natural frequency ``l = sqrt(g / H)``, in 1/s."""
    return backend(H_m, g_mps2).sqrt(g_mps2 / H_m)


def flow(p_m, L, tau_s, mass_kg, H_m, g_mps2=GRAVITY_MPS2):
    """Flow of the ALIP pair over a horizon ``tau_s`` (paper eq. LIP_AM_Preiction).

    Returns ``(p(t+tau), L(t+tau))``::

        p' = cosh(l tau) p + sinh(l tau) / (m H l) L
        L' = m H l sinh(l tau) p + cosh(l tau) L
    """
    xp = backend(p_m, L, tau_s, mass_kg, H_m, g_mps2)
    l = omega(H_m, g_mps2)
    c = xp.cosh(l * tau_s)
    s = xp.sinh(l * tau_s)
    return c * p_m + s / (mass_kg * H_m * l) * L, mass_kg * H_m * l * s * p_m + c * L


def transfer(L_minus, p_st_m, p_sw_m, v_z_mps, mass_kg, dz_m=0.0, v_mps=0.0):
    """Momentum about the new contact after touchdown (notes, eq. AM_transfer).

    The pair component of ``L_2 = L_1 + (r_1 - r_2) x m v_c``::

        L(T+) = L(T-) + m v_z (p_st(T-) - p_sw(T-)) - m dz v

    ``p_st`` and ``p_sw`` are the CoM offsets from the old and new contacts
    just before touchdown along the pair's axis, ``v_z`` the CoM vertical
    velocity, ``dz_m`` the new contact's height minus the old one's and
    ``v_mps`` the CoM's horizontal velocity along the pair's axis (sagittal:
    ``v_x``; lateral pair ``Lt = -L_x``: ``v_y``). On flat ground
    (``dz = 0``) the last term vanishes (docs/ALIP_SLOPES.md).
    """
    return L_minus + mass_kg * v_z_mps * (p_st_m - p_sw_m) - mass_kg * dz_m * v_mps


def foot_placement(L_des, L_hat, p_hat_m, T_s, mass_kg, H_m, v_z_mps=0.0, g_mps2=GRAVITY_MPS2, dz_m=0.0):
    """Deadbeat foot placement in ``L`` at the end of the *next* step.

    ``L_hat`` and ``p_hat_m`` are the predicted ``L(T-)`` and ``p_st(T-)`` of the
    current step, ``v_z_mps`` the predicted CoM vertical velocity at touchdown
    and ``dz_m`` the next contact's height minus the stance contact's (m).
    Returns ``p_sw->CoM`` at touchdown, in m::

        [L_des - cosh(lT) (L_hat + m v_z p_hat - dz L_hat / H)] / [m (H l sinh(lT) - v_z cosh(lT))]

    The ``dz`` term is the height part of the transfer ``(r_1 - r_2) x m v_c``
    with the horizontal CoM velocity at touchdown taken as ``L_hat / (m H)``,
    exact for a point mass on any plane of intercept ``H`` over the contact
    (docs/ALIP_SLOPES.md); it is subtracted last, so ``dz = 0`` gives the
    flat-ground numbers bit for bit.
    """
    xp = backend(L_des, L_hat, p_hat_m, T_s, mass_kg, H_m, v_z_mps, g_mps2, dz_m)
    l = omega(H_m, g_mps2)
    c = xp.cosh(l * T_s)
    s = xp.sinh(l * T_s)
    return (L_des - c * (L_hat + mass_kg * v_z_mps * p_hat_m - dz_m * L_hat / H_m)) / (
        mass_kg * (H_m * l * s - v_z_mps * c)
    )


def L_from_velocity(v_mps, mass_kg, H_m):
    """Pair momentum of a point mass at height ``H`` moving at ``v``: ``m H v``.

    Sagittal: ``L_y = m H v_x``. Lateral: ``Lt = -L_x = m H v_y``.
    """
    return mass_kg * H_m * v_mps


def Lt_step_width(W_m, T_s, mass_kg, H_m, next_stance_sign, g_mps2=GRAVITY_MPS2):
    """Lateral pair momentum ``Lt = -L_x`` at the end of the next step for
    walking in place with step width ``W_m`` (paper eq. lateral_desired_Lx).

    ``next_stance_sign`` is +1 when the next stance leg is the left one and -1
    for the right one; the paper's ``L_x^des = +-(1/2) m H W l sinh(lT)/(1+cosh(lT))``
    has that sign, so ``Lt`` has the opposite one.
    """
    xp = backend(W_m, T_s, mass_kg, H_m, next_stance_sign, g_mps2)
    l = omega(H_m, g_mps2)
    return -next_stance_sign * 0.5 * mass_kg * H_m * W_m * l * xp.sinh(l * T_s) / (1.0 + xp.cosh(l * T_s))


def desired_L_world(vx_mps, vy_mps, W_m, T_s, mass_kg, H_m, next_stance_sign, heading_next_rad, g_mps2=GRAVITY_MPS2):
    """``L^des = (L_x, L_y)`` in world axes at the end of the next step (paper section 3).

    Decided in the next step's heading frame ``D_{k+1} = heading_next_rad``:
    ``L_y = m H v_x`` and ``Lt = -L_x = m H v_y + Lt_step_width``, then
    rotated by ``D_{k+1}`` to world axes. ``vx_mps``, ``vy_mps`` are
    end-of-step CoM velocities in that heading frame; ``next_stance_sign`` as
    in :func:`Lt_step_width`.
    """
    xp = backend(vx_mps, vy_mps, W_m, T_s, mass_kg, H_m, next_stance_sign, heading_next_rad, g_mps2)
    Ly_h = L_from_velocity(vx_mps, mass_kg, H_m)
    Lx_h = -(L_from_velocity(vy_mps, mass_kg, H_m) + Lt_step_width(W_m, T_s, mass_kg, H_m, next_stance_sign, g_mps2))
    c, s = xp.cos(heading_next_rad), xp.sin(heading_next_rad)
    return c * Lx_h - s * Ly_h, s * Lx_h + c * Ly_h


def world_to_heading_xy(x, y, cos_D, sin_D):
    """World ``(x, y)`` components (any unit) in the heading frame ``D``: ``(c x + s y, -s x + c y)``.

    ``cos_D``, ``sin_D`` are ``cos D`` and ``sin D``: callers that rotate
    several vectors by one heading compute them once. The one definition of
    this rotation, for the planner, the output map and its generated C.
    """
    return cos_D * x + sin_D * y, -sin_D * x + cos_D * y


def hip_yaw_split(turn_rad):
    """A step's turn ``dD`` (rad) split between the hip yaws (paper section 4):
    ``(stance, swing) = (-dD/2, +dD/2)``; the swing foot lands along ``D_{k+1}``."""
    return -0.5 * turn_rad, 0.5 * turn_rad


# --- phase-based reference shapes, with d/ds and d^2/ds^2 ---------------------


def cosine_blend(s, start, end):
    """Half-period cosine from ``start`` (s=0) to ``end`` (s=1).

    Returns ``(y, dy/ds, d2y/ds2)`` of ``1/2 [(1 + cos(pi s)) start + (1 - cos(pi s)) end]``.
    """
    xp = backend(s, start, end)
    c = xp.cos(np.pi * s)
    sn = xp.sin(np.pi * s)
    return (
        0.5 * ((1.0 + c) * start + (1.0 - c) * end),
        0.5 * np.pi * sn * (end - start),
        0.5 * np.pi**2 * c * (end - start),
    )


def line(s, start, end):
    """Straight line from ``start`` (s=0) to ``end`` (s=1): ``(y, dy/ds, d2y/ds2)``."""
    return (1.0 - s) * start + s * end, end - start, 0.0 * s


def clearance_parabola(s, H_m, z_cl_m):
    """Swing ``p^z_sw->CoM`` reference ``4 z_cl (s - 1/2)^2 + (H - z_cl)``.

    It equals ``H`` at s=0 and s=1 and ``H - z_cl`` at mid-step, lifting the foot
    by ``z_cl`` when the CoM stays at ``H``. Returns ``(y, dy/ds, d2y/ds2)`` in m.
    """
    return 4.0 * z_cl_m * (s - 0.5) ** 2 + (H_m - z_cl_m), 8.0 * z_cl_m * (s - 0.5), 8.0 * z_cl_m + 0.0 * s


def swing_height(s, H_m, z_cl_m, dz0_m, dz1_m):
    """Swing ``p^z_sw->CoM`` reference when the swing foot moves from height
    ``dz0_m`` to ``dz1_m`` over the stance contact (m), with the CoM over the
    stance as :func:`stance_height` puts it.

    The foot's height over the stance contact is
    ``dz0 + (dz1 - dz0) s + (z_cl + |dz1 - dz0| / 2) 4 s (1 - s)``: its apex is
    at least ``z_cl`` above the higher of the two ends (by at most
    ``|dz1 - dz0| / 8`` more). The reference is the CoM height minus that::

        4 z_cl (s - 1/2)^2 + (H - z_cl) - [dz0 - r(s) + (dz1 - dz0) s + |dz1 - dz0| / 2 * 4 s (1 - s)]

    with ``r(s) = dz0 (1 - s)`` the CoM's rise of :func:`com_rise` (``dz0 - r(s) = dz0 s``), plus
    the CoM's descent on a step down
    (:func:`downhill_com_terms`). It starts at ``H - a`` and ends at ``H - dz1 + d``
    (``a``, ``d`` of :func:`stance_height`: both 0 unless a step goes down); with
    ``dz0 = dz1 = 0`` it is :func:`clearance_parabola` bit for bit (the
    bracket and the descent are exact zeros, subtracted and added last). Returns
    ``(y, dy/ds, d2y/ds2)`` in m.
    """
    xp = backend(s, H_m, z_cl_m, dz0_m, dz1_m)
    y, dy, ddy = clearance_parabola(s, H_m, z_cl_m)
    c = xp.cos(np.pi * s)
    sn = xp.sin(np.pi * s)
    rise = dz1_m - dz0_m
    lift = 0.5 * abs(rise)
    # dz0 - r(s) = dz0 s and its derivatives lead the bracket (exact zeros on flat ground)
    q = dz0_m * s + rise * s + lift * (4.0 * s * (1.0 - s))
    dq = dz0_m + rise + lift * (4.0 - 8.0 * s)
    ddq = dz0_m * 0.0 - 8.0 * lift
    e, de, dde = downhill_com_terms(c, sn, xp, dz0_m, dz1_m)
    return y - q + e, dy - dq + de, ddy - ddq + dde


def downhill_com_terms(c, sn, xp, dz0_m, dz1_m):
    """The CoM's descent on a step down, added to the CoM over the stance and over the swing
    (:func:`stance_height`, :func:`swing_height`): ``d b(s) - a (1 - b(s))`` with
    ``a = share max(dz0, 0)`` (the share of the last step's drop the CoM took before its
    touchdown) and ``d = share min(dz1, 0)`` (the share of this step's drop it takes before the
    next), ``share`` = :data:`DOWNHILL_COM_SHARE`, ``c = cos(pi s)``, ``sn = sin(pi s)``. Returns
    it and its first two derivatives in ``s`` (m); exact zeros (``+0.0``) unless a step goes down."""
    a = DOWNHILL_COM_SHARE * xp.fmax(dz0_m, 0.0)
    d = DOWNHILL_COM_SHARE * xp.fmin(dz1_m, 0.0)
    k = d + a
    return d * (0.5 * (1.0 - c)) - a * (0.5 * (1.0 + c)), k * (0.5 * np.pi * sn), k * (0.5 * np.pi**2 * c)


def com_rise(s, dz0_m):
    """The CoM's height over the stance contact within a step, less ``H`` and the descent of a
    step down: the line ``r(s) = dz0 (1 - s)`` from ``dz0`` (s=0) to 0 (s=1), m.

    ``dz0`` (m) is the previous stance contact's height minus the current one's: the CoM rises
    (or drops) at the step's own rise, ``-dz0`` per unit phase, as a CoM on the plane through the
    two contacts, parallel to the ground (docs/ALIP_SLOPES.md), with ``v_z = k v`` at the
    touchdown. Written so that ``dz0 = 0`` gives exact ``+0.0`` in every term. Returns ``(r,
    dr/ds, d2r/ds2)``.
    """
    return dz0_m * (1.0 - s), 0.0 - dz0_m, dz0_m * 0.0


def stance_height(s, H_m, dz0_m, dz1_m):
    """CoM over the stance contact, m: ``H + r(s)`` (:func:`com_rise`) plus the descent on a step
    down, ``d b(s) - a (1 - b(s))`` (:func:`downhill_com_terms`). ``dz0`` (m) is the previous
    stance contact's height minus the current one's and ``dz1`` the target's minus the current
    one's. The CoM has not moved at touchdown: the reference starts at ``H + dz0 - a`` (``a`` =
    :data:`DOWNHILL_COM_SHARE` ``max(dz0, 0)``, the share of that step's drop the CoM took before
    it) and ends at ``H + d`` at s=1 (``d`` = the share ``min(dz1, 0)`` of this step's drop, below
    ``H``, so that the swing leg reaches a lower foothold), rising at the step's own rise from the
    last contact (:func:`com_rise`). Level and rising steps
    (``dz0 <= 0``, ``dz1 >= 0``) go from ``H + dz0`` to ``H``; ``dz0 = dz1 = 0`` is the constant
    ``H`` bit for bit. Returns ``(y, dy/ds, d2y/ds2)``.
    """
    xp = backend(s, H_m, dz0_m, dz1_m)
    c = xp.cos(np.pi * s)
    sn = xp.sin(np.pi * s)
    y, dy, ddy = constant(s, H_m)
    r, dr, ddr = com_rise(s, dz0_m)
    e, de, dde = downhill_com_terms(c, sn, xp, dz0_m, dz1_m)
    return y + r + e, dy + dr + de, ddy + ddr + dde


def ground_pitch_blend(s, pitch0_rad, pitch1_rad):
    """Swing toe pitch from the ground pitch at lift-off to the one at the target (rad).

    ``pitch0 (1 + cos(pi s)) / 2 + pitch1 (1 - cos(pi s)) / 2`` with both in the
    toe output's convention (rotation about the heading's y axis, positive =
    forward end down): the blade leaves and lands flat. Both 0 give exact
    zeros, the flat-ground constant. Returns ``(y, dy/ds, d2y/ds2)``.
    """
    xp = backend(s, pitch0_rad, pitch1_rad)
    c = xp.cos(np.pi * s)
    sn = xp.sin(np.pi * s)
    h = 0.5 * np.pi * sn
    hh = 0.5 * np.pi**2 * c
    return (
        pitch0_rad * (0.5 * (1.0 + c)) + pitch1_rad * (0.5 * (1.0 - c)),
        pitch0_rad * (-h) + pitch1_rad * h,
        pitch0_rad * (-hh) + pitch1_rad * hh,
    )


def constant(s, value):
    """A constant reference: ``(value, 0, 0)``."""
    return value + 0.0 * s, 0.0 * s, 0.0 * s


def to_time_derivatives(y, dy_ds, d2y_ds2, T_s):
    """Convert phase derivatives to time derivatives (``d/dt = (1/T) d/ds``)."""
    return y, dy_ds / T_s, d2y_ds2 / T_s**2
