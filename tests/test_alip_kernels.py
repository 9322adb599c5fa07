"""Tests of the dense kernels ALIP_PLAN and SWING_REFERENCE against hand-derived values."""

import numpy as np
import pytest

from amlip_qp.alip import kernels

M, H, G, T = 32.0, 0.8, 9.81, 0.35


def _plan_input(**kw):
    base = dict(
        p_st_x=0.04, p_st_y=-0.09, L_x=2.0, L_y=18.0, t_rem=0.12, v_z=0.15, vx_des=0.7, vy_des=0.2,
        heading_next=0.4, next_stance_sign=-1.0, m=M, H=H, T=T, W=0.22, g=G, dz_next=0.0,
    )  # fmt: skip
    base.update(kw)
    return np.array([base[n] for n in kernels.ALIP_PLAN_INPUTS]), base


def test_layout_sizes():
    assert len(kernels.ALIP_PLAN_INPUTS) == 16 and len(kernels.ALIP_PLAN_OUTPUTS) == 8
    assert len(kernels.SWING_REFERENCE_INPUTS) == 15 and kernels.SWING_REFERENCE_N_OUT == 27


def test_alip_plan_matches_hand_derived_values():
    u, b = _plan_input()
    y = kernels.alip_plan(u)
    l = np.sqrt(G / H)
    ch, sh = np.cosh(l * b["t_rem"]), np.sinh(l * b["t_rem"])
    # Prediction, sagittal (p_x, L_y) and lateral (p_y, -L_x).
    p_hat_x = ch * b["p_st_x"] + sh / (M * H * l) * b["L_y"]
    L_hat_y = M * H * l * sh * b["p_st_x"] + ch * b["L_y"]
    p_hat_y = ch * b["p_st_y"] - sh / (M * H * l) * b["L_x"]
    L_hat_x = -(M * H * l * sh * b["p_st_y"] - ch * b["L_x"])
    np.testing.assert_allclose(y[:4], [L_hat_x, L_hat_y, p_hat_x, p_hat_y], rtol=1e-13, atol=1e-13)
    # Desired L in the next heading frame (next stance right: minus sign), rotated to world.
    Lx_h = -M * H * b["vy_des"] - 0.5 * M * H * b["W"] * l * np.tanh(l * T / 2)
    Ly_h = M * H * b["vx_des"]
    D = b["heading_next"]
    L_des = np.array([np.cos(D) * Lx_h - np.sin(D) * Ly_h, np.sin(D) * Lx_h + np.cos(D) * Ly_h])
    np.testing.assert_allclose(y[4:6], L_des, rtol=1e-13, atol=1e-12)
    # Foot placement with the v_z correction, both planes.
    cT, sT, vz = np.cosh(l * T), np.sinh(l * T), b["v_z"]
    den = M * (H * l * sT - vz * cT)
    p_sw_x = (L_des[1] - cT * (L_hat_y + M * vz * p_hat_x)) / den
    p_sw_y = (-L_des[0] - cT * (-L_hat_x + M * vz * p_hat_y)) / den
    np.testing.assert_allclose(y[6:8], [p_sw_x, p_sw_y], rtol=1e-12, atol=1e-13)


def test_alip_plan_zero_horizon_returns_the_current_state():
    u, b = _plan_input(t_rem=0.0)
    y = kernels.alip_plan(u)
    np.testing.assert_allclose(y[:4], [b["L_x"], b["L_y"], b["p_st_x"], b["p_st_y"]], atol=1e-14)


def _ref_input(s, **kw):
    base = dict(s=s, T=T, H=H, z_cl=0.1, stance_yaw0=0.05, swing_yaw0=-0.08, x0=-0.2, y0=0.15,
                p_sw_des_x=0.18, p_sw_des_y=-0.12, dD=0.3, dz_sw0=0.0, dz_sw=0.0, slope_pitch0=0.0,
                slope_pitch=0.0)  # fmt: skip
    base.update(kw)
    return np.array([base[n] for n in kernels.SWING_REFERENCE_INPUTS]), base


def test_swing_reference_start_mid_and_end_values():
    u0, b = _ref_input(0.0)
    y0 = kernels.swing_reference(u0)
    np.testing.assert_allclose(y0[:9], [0, 0, 0.05, -0.08, H, -0.2, 0.15, H, 0], atol=1e-15)
    y1 = kernels.swing_reference(_ref_input(1.0)[0])
    np.testing.assert_allclose(y1[:9], [0, 0, -0.15, 0.15, H, 0.18, -0.12, H, 0], atol=1e-15)
    # Velocities of the cosine blend vanish at both ends; the z parabola has slope -+4 z_cl / T.
    np.testing.assert_allclose(y0[9 + 5 : 9 + 7], 0.0, atol=1e-15)
    np.testing.assert_allclose(y1[9 + 5 : 9 + 7], 0.0, atol=1e-15)
    assert y0[9 + 7] == pytest.approx(-4 * 0.1 / T) and y1[9 + 7] == pytest.approx(4 * 0.1 / T)
    ym = kernels.swing_reference(_ref_input(0.5)[0])
    assert ym[7] == pytest.approx(H - 0.1)
    assert ym[5] == pytest.approx(0.5 * (-0.2 + 0.18))
    # Hip-yaw lines: constant slope (target - start) / T, zero acceleration.
    assert ym[9 + 2] == pytest.approx((-0.15 - 0.05) / T) and ym[9 + 3] == pytest.approx((0.15 + 0.08) / T)
    assert ym[18 + 2] == 0.0 and ym[18 + 3] == 0.0


def test_swing_reference_derivatives_match_finite_differences_in_time():
    rng = np.random.default_rng(0)
    dt = 1e-5
    for s in rng.uniform(0.05, 0.95, size=5):
        t = s * T
        y = kernels.swing_reference(_ref_input(s)[0])
        yp = kernels.swing_reference(_ref_input((t + dt) / T)[0])
        ym = kernels.swing_reference(_ref_input((t - dt) / T)[0])
        np.testing.assert_allclose(y[9:18], (yp[:9] - ym[:9]) / (2 * dt), atol=1e-6)
        np.testing.assert_allclose(y[18:], (yp[:9] - 2 * y[:9] + ym[:9]) / dt**2, atol=2e-3)
        np.testing.assert_allclose(y[18:], (yp[9:18] - ym[9:18]) / (2 * dt), atol=1e-5)
