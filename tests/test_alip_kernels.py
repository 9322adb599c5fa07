"""Tests of the dense kernels ALIP_PLAN and SWING_REFERENCE against hand-derived values."""

import numpy as np
import pytest

from amlip_qp.alip import kernels
from amlip_qp.alip.formulas import DOWNHILL_COM_SHARE as SHARE

#: Outputs per block of SWING_REFERENCE (values, first and second time derivatives).
N = kernels.N_REFERENCE_OUTPUTS

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
    assert len(kernels.SWING_REFERENCE_INPUTS) == 15 and kernels.SWING_REFERENCE_N_OUT == 30


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
    np.testing.assert_allclose(y0[:N], [0, 0, 0.05, -0.08, H, -0.2, 0.15, H, 0, 0], atol=1e-15)
    y1 = kernels.swing_reference(_ref_input(1.0)[0])
    np.testing.assert_allclose(y1[:N], [0, 0, -0.15, 0.15, H, 0.18, -0.12, H, 0, 0], atol=1e-15)
    # Velocities of the cosine blend vanish at both ends; the z parabola has slope -+4 z_cl / T.
    np.testing.assert_allclose(y0[N + 5 : 9 + 7], 0.0, atol=1e-15)
    np.testing.assert_allclose(y1[N + 5 : 9 + 7], 0.0, atol=1e-15)
    assert y0[N + 7] == pytest.approx(-4 * 0.1 / T) and y1[N + 7] == pytest.approx(4 * 0.1 / T)
    ym = kernels.swing_reference(_ref_input(0.5)[0])
    assert ym[7] == pytest.approx(H - 0.1)
    assert ym[5] == pytest.approx(0.5 * (-0.2 + 0.18))
    # Hip-yaw lines: constant slope (target - start) / T, zero acceleration.
    assert ym[N + 2] == pytest.approx((-0.15 - 0.05) / T) and ym[N + 3] == pytest.approx((0.15 + 0.08) / T)
    assert ym[2 * N + 2] == 0.0 and ym[2 * N + 3] == 0.0


def test_swing_reference_derivatives_match_finite_differences_in_time():
    rng = np.random.default_rng(0)
    dt = 1e-5
    for s in rng.uniform(0.05, 0.95, size=5):
        t = s * T
        y = kernels.swing_reference(_ref_input(s)[0])
        yp = kernels.swing_reference(_ref_input((t + dt) / T)[0])
        ym = kernels.swing_reference(_ref_input((t - dt) / T)[0])
        np.testing.assert_allclose(y[N : 2 * N], (yp[:N] - ym[:N]) / (2 * dt), atol=1e-6)
        np.testing.assert_allclose(y[2 * N :], (yp[:N] - 2 * y[:N] + ym[:N]) / dt**2, atol=2e-3)
        np.testing.assert_allclose(y[2 * N :], (yp[N : 2 * N] - ym[N : 2 * N]) / (2 * dt), atol=1e-5)


def _old_flat_plan(u):
    """ALIP_PLAN's foot placement as written before the height difference, operation for operation."""
    b = dict(zip(kernels.ALIP_PLAN_INPUTS, (float(v) for v in u)))
    m, H_, T_, g, vz = b["m"], b["H"], b["T"], b["g"], b["v_z"]
    y = kernels.alip_plan(u)
    l = np.sqrt(g / H_)
    c, s = np.cosh(l * T_), np.sinh(l * T_)
    L_hat_y, Lt_hat, p_hat_x, p_hat_y = float(y[1]), -float(y[0]), float(y[2]), float(y[3])
    px = (float(y[5]) - c * (L_hat_y + m * vz * p_hat_x)) / (m * (H_ * l * s - vz * c))
    py = (-float(y[4]) - c * (Lt_hat + m * vz * p_hat_y)) / (m * (H_ * l * s - vz * c))
    return px, py


def _old_flat_reference(u):
    """SWING_REFERENCE's z and toe outputs as written before the ground inputs: (h, dh, ddh) of outputs 4, 7, 8."""
    b = dict(zip(kernels.SWING_REFERENCE_INPUTS, (float(v) for v in u)))
    s, T_, H_, z = b["s"], b["T"], b["H"], b["z_cl"]
    swing = (4.0 * z * (s - 0.5) ** 2 + (H_ - z), 8.0 * z * (s - 0.5), 8.0 * z + 0.0 * s)
    stance, toe = (H_ + 0.0 * s, 0.0 * s, 0.0 * s), (0.0 + 0.0 * s, 0.0 * s, 0.0 * s)
    return [[stance[k], swing[k] / T_**k, toe[k] / T_**k] for k in range(3)]


def test_flat_ground_inputs_give_the_old_numbers_bit_for_bit():
    """dz_next = 0 and zero ground inputs: exactly the pre-terrain arithmetic, signs of zeros included."""
    rng = np.random.default_rng(5)
    for _ in range(200):
        u, _ = _plan_input(
            p_st_x=rng.uniform(-0.3, 0.3), L_y=rng.uniform(-20, 60), t_rem=rng.uniform(0, T),
            v_z=rng.uniform(-0.3, 0.3), vx_des=rng.uniform(-1, 2), heading_next=rng.uniform(-3, 3),
        )  # fmt: skip
        y = kernels.alip_plan(u)
        assert (float(y[6]), float(y[7])) == _old_flat_plan(u)
        v, _ = _ref_input(rng.uniform(0, 1), z_cl=rng.uniform(0, 0.2))
        h = kernels.swing_reference(v)
        for k, (stance, swing, toe) in enumerate(_old_flat_reference(v)):
            got = h[N * k + np.array([4, 7, 8])]
            assert list(got) == [stance, swing, toe]
            assert list(np.signbit(got)) == list(np.signbit([stance, swing, toe]))


@pytest.mark.parametrize("dz", [-0.15, 0.08, 0.2])
def test_alip_plan_with_a_height_difference_is_deadbeat_with_the_exact_transfer(dz):
    """Place the foot, transfer L by (r_1 - r_2) x m v with the contacts dz apart, flow a step: L = L_des."""
    rng = np.random.default_rng(6)
    for _ in range(10):
        u, b = _plan_input(
            t_rem=0.0, v_z=0.0, dz_next=dz, p_st_x=rng.uniform(-0.1, 0.2), p_st_y=rng.uniform(-0.15, 0.15),
            L_x=rng.uniform(-5, 5), L_y=rng.uniform(5, 30),
        )  # fmt: skip
        y = kernels.alip_plan(u)
        # A point mass at height H over the stance contact, L = p x m v with v_z = 0 at touchdown.
        p_st = np.array([b["p_st_x"], b["p_st_y"], H])
        v = np.array([b["L_y"], -b["L_x"], 0.0]) / (M * H)
        p_sw = np.array([y[6], y[7], H - dz])  # the next contact dz higher
        L2 = np.cross(p_sw, M * v)
        np.testing.assert_allclose(L2[:2], np.cross(p_st, M * v)[:2] + np.cross(p_sw - p_st, M * v)[:2], atol=1e-12)
        l = np.sqrt(G / H)
        Ly_end = M * H * l * np.sinh(l * T) * p_sw[0] + np.cosh(l * T) * L2[1]
        Lt_end = M * H * l * np.sinh(l * T) * p_sw[1] + np.cosh(l * T) * -L2[0]
        np.testing.assert_allclose([-Lt_end, Ly_end], y[4:6], atol=1e-10)
        # Without the height term the same placement misses L_des by m dz v cosh(lT).
        y0 = kernels.alip_plan(_plan_input(**{**b, "dz_next": 0.0})[0])
        assert abs(y0[6] - y[6]) > 0.3 * abs(dz) * abs(v[0]) * np.cosh(l * T) / (H * l * np.sinh(l * T))


@pytest.mark.parametrize("dz0, dz1", [(0.0, 0.12), (-0.1, 0.1), (0.15, -0.05), (0.0, -0.2)])
def test_swing_reference_ground_heights_and_pitches(dz0, dz1):
    zcl = 0.08
    base = dict(z_cl=zcl, dz_sw0=dz0, dz_sw=dz1, slope_pitch0=-0.2, slope_pitch=0.25)
    y0 = kernels.swing_reference(_ref_input(0.0, **base)[0])
    y1 = kernels.swing_reference(_ref_input(1.0, **base)[0])
    # CoM over stance from H + dz0 to H, CoM over swing from H to H - dz1, toe from pitch0 to pitch; on
    # a step down (dz0 > 0 at the start, dz1 < 0 at the end) the CoM takes its share of the drop.
    a, d = SHARE * max(dz0, 0.0), SHARE * min(dz1, 0.0)
    np.testing.assert_allclose(y0[[4, 7, 8]], [H + dz0 - a, H - a, -0.2], atol=1e-15)
    np.testing.assert_allclose(y1[[4, 7, 8]], [H + d, H - dz1 + d, 0.25], atol=1e-15)
    np.testing.assert_allclose(y0[N + 8], 0.0, atol=1e-15)  # the toe's blend starts and ends at rest
    np.testing.assert_allclose(y1[N + 8], 0.0, atol=1e-15)
    # the CoM rises at this step's rise from the last contact, over T, from start to end
    np.testing.assert_allclose([y0[N + 4], y1[N + 4]], [-dz0 / T, -dz0 / T], atol=1e-15)
    assert y1[N + 7] > 0.0 and y0[N + 7] < 0.0  # the foot rises at lift-off and descends at touchdown
    # The foot over the stance contact (CoM height minus CoM over swing) clears the higher end by z_cl.
    ys = np.array([kernels.swing_reference(_ref_input(s, **base)[0]) for s in np.linspace(0, 1, 2001)])
    foot = ys[:, 4] - ys[:, 7]
    assert foot[0] == pytest.approx(dz0, abs=1e-15) and foot[-1] == pytest.approx(dz1, abs=1e-15)
    apex = foot.max()
    assert max(dz0, dz1) + zcl - 1e-9 <= apex <= max(dz0, dz1) + zcl + abs(dz1 - dz0) / 8 + 1e-9


def test_the_com_height_is_continuous_across_a_touchdown_on_every_step_up_or_down():
    """At a touchdown the CoM has not moved: the new step's ``com_z_over_stance`` at s = 0 is the
    old step's at s = 1 plus the drop to the new contact, and the swing foot, which left the old
    contact, starts at the old CoM height over it. On a step down the CoM ends the step ``SHARE``
    of the drop below ``H`` (the swing leg reaches that much less far), and the next step starts
    there; a level or rising step ends at ``H``. Its vertical velocity is each step's own rise from
    the last contact over ``T`` (both contacts are fixed): continuous where the steps rise alike."""
    rng = np.random.default_rng(3)
    for _ in range(200):
        dz_prev, dz1, dz2 = rng.uniform(-0.25, 0.25, size=3)  # target heights over each stance contact
        old = kernels.swing_reference(_ref_input(1.0, dz_sw0=dz_prev, dz_sw=dz1)[0])
        new = kernels.swing_reference(_ref_input(0.0, dz_sw0=-dz1, dz_sw=dz2)[0])
        com_old = old[4]  # over the old stance contact; the new one lies dz1 higher
        assert com_old == pytest.approx(H + SHARE * min(dz1, 0.0), abs=1e-15)
        assert new[4] == pytest.approx(com_old - dz1, abs=1e-14)
        assert new[7] == pytest.approx(com_old, abs=1e-14)
        assert old[N + 4] == pytest.approx(-dz_prev / T, abs=1e-13)
        assert new[N + 4] == pytest.approx(dz1 / T, abs=1e-13)


@pytest.mark.parametrize("rise", [-0.12, -0.05, 0.07, 0.15])
def test_on_a_uniform_slope_the_com_moves_parallel_to_the_ground(rise):
    """Every step rising by the same ``rise`` (``dz_sw = -dz_sw0``): the CoM over the stance contact
    goes from ``H - rise`` to ``H`` in a straight line, at the constant rate ``rise / T`` with no
    acceleration, so its vertical velocity is the same in every step; on a way down the whole line
    lies the descent's share of the drop, :data:`SHARE` ``rise``, lower."""
    for s in np.linspace(0.0, 1.0, 21):
        y = kernels.swing_reference(_ref_input(s, dz_sw0=-rise, dz_sw=rise)[0])
        assert y[4] == pytest.approx(H - rise * (1.0 - s) + SHARE * min(rise, 0.0), abs=1e-14)
        assert y[N + 4] == pytest.approx(rise / T, abs=1e-13)
        assert y[2 * N + 4] == pytest.approx(0.0, abs=1e-12)


@pytest.mark.parametrize(
    "ground",
    [dict(), dict(dz_sw0=-0.1, dz_sw=0.12, slope_pitch0=0.1, slope_pitch=-0.3), dict(dz_sw0=0.14, dz_sw=-0.18)],
)
def test_swing_reference_ground_derivatives_match_finite_differences(ground):
    rng = np.random.default_rng(1)
    dt = 1e-5
    for s in rng.uniform(0.05, 0.95, size=5):
        t = s * T
        y = kernels.swing_reference(_ref_input(s, **ground)[0])
        yp = kernels.swing_reference(_ref_input((t + dt) / T, **ground)[0])
        ym = kernels.swing_reference(_ref_input((t - dt) / T, **ground)[0])
        np.testing.assert_allclose(y[N : 2 * N], (yp[:N] - ym[:N]) / (2 * dt), atol=1e-6)
        np.testing.assert_allclose(y[2 * N :], (yp[N : 2 * N] - ym[N : 2 * N]) / (2 * dt), atol=1e-5)
        assert np.max(np.abs(y[N + np.array([4, 8])])) > (0.05 if ground else -1.0)  # the ground terms move
