"""The two per-tick planner kernels, with dense input and output layouts.

These are the functions CasADi turns into C (see :mod:`amlip_qp.codegen`).
They are written once, on top of :mod:`amlip_qp.alip.formulas`, and accept
either numpy scalars or CasADi symbols: ``alip_plan_terms`` and
``swing_reference_terms`` take a sequence of scalars and return a list of
scalar expressions. :func:`alip_plan` and :func:`swing_reference` are the
numpy reference on 1-D float arrays.

``ALIP_PLAN`` (inputs ``u``, 16):

=====  ==================  =====================================================
index  name                meaning
=====  ==================  =====================================================
0, 1   p_st_x, p_st_y      CoM minus stance contact, world axes, m
2, 3   L_x, L_y            angular momentum about the stance contact, world, kg m^2/s
4      t_rem               time left in the current step, s (>= 0)
5      v_z                 predicted CoM vertical velocity at touchdown, m/s
6, 7   vx_des, vy_des      desired velocity in the next step's heading frame, m/s
8      heading_next        heading ``D_{k+1}`` of the next step (yaw), rad
9      next_stance_sign    +1 if the next stance leg is the left one, -1 if right
10     m                   total mass, kg
11     H                   CoM height over the contact, m
12     T                   step duration, s
13     W                   step width for walking in place, m
14     g                   gravity magnitude, m/s^2
15     dz_next             next contact height minus the stance contact's, m
                           (0 on flat ground; docs/ALIP_SLOPES.md)
=====  ==================  =====================================================

``ALIP_PLAN`` outputs (8): ``L_hat_x, L_hat_y`` (predicted ``L(T-)``, world),
``p_hat_x, p_hat_y`` (predicted ``p_st(T-)``, world), ``L_des_x, L_des_y``
(desired ``L`` at the end of the next step, world), ``p_sw_des_x, p_sw_des_y``
(desired CoM minus swing contact at touchdown, world axes, m).

``SWING_REFERENCE`` (inputs ``u``, 15): ``s`` (phase), ``T`` (s), ``H`` (m),
``z_cl`` (m), ``stance_yaw0``, ``swing_yaw0`` (hip yaws at the step start, rad),
``x0``, ``y0`` (CoM minus swing contact at the step start, heading frame, m),
``p_sw_des_x``, ``p_sw_des_y`` (target at touchdown, heading frame, m),
``dD`` (turn of this step, rad), then the ground (all 0 on flat ground,
docs/ALIP_SLOPES.md): ``dz_sw0`` (ground height where the swing foot lifted
off, the previous stance contact, minus the stance contact, m), ``dz_sw``
(ground height at the swing target minus the stance contact, m),
``slope_pitch0``, ``slope_pitch`` (ground pitch along the heading at lift-off
and at the target, rad, the toe output's convention: rotation about the
heading's y axis, positive = ground descending ahead, so an uphill slope of
``a`` is ``-a``).

With the ground inputs, ``com_z_over_stance`` goes from ``H + dz_sw0`` to
``H`` (a line, at the step's rise from the last contact:
:func:`~amlip_qp.alip.formulas.com_rise`), ``com_z_over_swing`` from ``H`` to ``H - dz_sw`` (on a step down the CoM
takes :data:`~amlip_qp.alip.formulas.DOWNHILL_COM_SHARE` of the drop before the
touchdown, and both end that much lower) with the foot's apex
at least ``z_cl`` above the higher end, and ``swing_toe_pitch`` from
``slope_pitch0`` to ``slope_pitch`` (:func:`~amlip_qp.alip.formulas.swing_height`,
:func:`~amlip_qp.alip.formulas.stance_height`,
:func:`~amlip_qp.alip.formulas.ground_pitch_blend`).

``SWING_REFERENCE`` outputs (30): ``h_d`` (10), ``dh_d/dt`` (10), ``d2h_d/dt2`` (10)
of every output a robot may declare, in the order of
``amlip_qp.alip.outputs.REFERENCE_OUTPUTS``; each robot takes the entries of
its own outputs (``amlip_qp.alip.outputs.OutputSet``).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from amlip_qp.alip import formulas as F

ALIP_PLAN_INPUTS = (
    "p_st_x", "p_st_y", "L_x", "L_y", "t_rem", "v_z", "vx_des", "vy_des",
    "heading_next", "next_stance_sign", "m", "H", "T", "W", "g", "dz_next",
)  # fmt: skip
ALIP_PLAN_OUTPUTS = ("L_hat_x", "L_hat_y", "p_hat_x", "p_hat_y", "L_des_x", "L_des_y", "p_sw_des_x", "p_sw_des_y")

SWING_REFERENCE_INPUTS = (
    "s", "T", "H", "z_cl", "stance_yaw0", "swing_yaw0", "x0", "y0", "p_sw_des_x", "p_sw_des_y", "dD",
    "dz_sw0", "dz_sw", "slope_pitch0", "slope_pitch",
)  # fmt: skip
#: Outputs of the reference kernel (``amlip_qp.alip.outputs.REFERENCE_OUTPUTS``).
N_REFERENCE_OUTPUTS = 10
SWING_REFERENCE_N_OUT = 3 * N_REFERENCE_OUTPUTS


def alip_plan_terms(u: Sequence) -> list:
    """Predict ``L(T-)``, choose ``L_des`` and place the foot (layout in the module doc)."""
    p_x, p_y, L_x, L_y, t_rem, v_z, vx_des, vy_des, D_next, sign, m, H, T, W, g, dz = u
    # Prediction to the end of the current step, on the pairs (p_x, L_y) and (p_y, -L_x).
    p_hat_x, L_hat_y = F.flow(p_x, L_y, t_rem, m, H, g)
    p_hat_y, Lt_hat = F.flow(p_y, -L_x, t_rem, m, H, g)
    # Desired momentum at the end of the next step, decided in the next heading frame.
    L_des_x, L_des_y = F.desired_L_world(vx_des, vy_des, W, T, m, H, sign, D_next, g)
    # Foot placement, deadbeat at the end of the next step, with the transfer to
    # the next contact (v_z and the height difference dz).
    p_sw_x = F.foot_placement(L_des_y, L_hat_y, p_hat_x, T, m, H, v_z, g, dz)
    p_sw_y = F.foot_placement(-L_des_x, Lt_hat, p_hat_y, T, m, H, v_z, g, dz)
    return [-Lt_hat, L_hat_y, p_hat_x, p_hat_y, L_des_x, L_des_y, p_sw_x, p_sw_y]


def swing_reference_terms(u: Sequence) -> list:
    """``h_d(s)`` of every output and its first two time derivatives (layout in the module doc)."""
    s, T, H, z_cl, st_yaw0, sw_yaw0, x0, y0, x_des, y_des, dD, dz0, dz1, pitch0, pitch1 = u
    st_yaw1, sw_yaw1 = F.hip_yaw_split(dD)
    shapes = [
        F.constant(s, 0.0),  # torso pitch
        F.constant(s, 0.0),  # torso roll
        F.line(s, st_yaw0, st_yaw1),  # stance hip yaw
        F.line(s, sw_yaw0, sw_yaw1),  # swing hip yaw
        F.stance_height(s, H, dz0, dz1),  # CoM z over stance
        F.cosine_blend(s, x0, x_des),  # CoM x over swing
        F.cosine_blend(s, y0, y_des),  # CoM y over swing
        F.swing_height(s, H, z_cl, dz0, dz1),  # CoM z over swing
        F.ground_pitch_blend(s, pitch0, pitch1),  # swing toe pitch
        F.constant(s, 0.0),  # swing foot roll: level
    ]
    derivs = [F.to_time_derivatives(y, dy_ds, d2y_ds2, T) for y, dy_ds, d2y_ds2 in shapes]
    return [d[0] for d in derivs] + [d[1] for d in derivs] + [d[2] for d in derivs]


def alip_plan(u: np.ndarray) -> np.ndarray:
    """numpy reference of ``ALIP_PLAN``: 16 inputs -> 8 outputs (no validation)."""
    return np.array([float(v) for v in alip_plan_terms([float(v) for v in u])])


def swing_reference(u: np.ndarray) -> np.ndarray:
    """numpy reference of ``SWING_REFERENCE``: 15 inputs -> 30 outputs (no validation)."""
    return np.array([float(v) for v in swing_reference_terms([float(v) for v in u])])
