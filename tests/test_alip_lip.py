"""Tests of amlip_qp.alip.lip: predictor, momentum transfer, foot placement, validation."""

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from amlip_qp.alip import lip
from amlip_qp.exceptions import InputError

M, H, G, T = 32.0, 0.8, 9.81, 0.35


def test_flow_matches_numerical_integration_of_the_alip_ode():
    rng = np.random.default_rng(0)
    for _ in range(5):
        p0, L0 = rng.uniform(-0.3, 0.3), rng.uniform(-20.0, 20.0)
        tau = rng.uniform(0.0, 0.5)
        sol = solve_ivp(lambda t, x: [x[1] / (M * H), M * G * x[0]], (0.0, tau), [p0, L0], rtol=1e-12, atol=1e-12)
        p1, L1 = lip.predict_end_of_step(p0, L0, tau, M, H, G)
        assert p1 == pytest.approx(sol.y[0, -1], abs=1e-9)
        assert L1 == pytest.approx(sol.y[1, -1], abs=1e-8)


def test_predictor_matches_3d_point_mass_in_both_planes():
    """Integrate a constant-height point mass (c_xy'' = g/H p_xy) and compare L = p x m v."""
    rng = np.random.default_rng(1)
    p0 = np.array([rng.uniform(-0.2, 0.2), rng.uniform(-0.2, 0.2), H])
    v0 = np.array([rng.uniform(-1, 1), rng.uniform(-1, 1), 0.0])
    tau = 0.27
    sol = solve_ivp(
        lambda t, x: [x[2], x[3], G / H * x[0], G / H * x[1]],
        (0, tau),
        [p0[0], p0[1], v0[0], v0[1]],
        rtol=1e-12,
        atol=1e-12,
    )
    pT = np.array([sol.y[0, -1], sol.y[1, -1], H])
    vT = np.array([sol.y[2, -1], sol.y[3, -1], 0.0])
    L0 = np.cross(p0, M * v0)
    LT = np.cross(pT, M * vT)
    px, Ly = lip.flow(p0[0], L0[1], tau, M, H, G)
    py, Lt = lip.flow(p0[1], -L0[0], tau, M, H, G)
    np.testing.assert_allclose([px, py], pT[:2], atol=1e-9)
    np.testing.assert_allclose([-Lt, Ly], LT[:2], atol=1e-8)


def test_zero_horizon_is_identity_and_arrays_broadcast():
    p, L = lip.flow(np.array([0.1, -0.2]), np.array([3.0, 4.0]), 0.0, M, H)
    np.testing.assert_allclose(p, [0.1, -0.2])
    np.testing.assert_allclose(L, [3.0, 4.0])


def _random_state(rng):
    p_st = np.array([rng.uniform(-0.3, 0.3), rng.uniform(-0.3, 0.3), rng.uniform(0.6, 1.0)])
    v = rng.uniform(-1.5, 1.5, size=3)
    L_c = rng.uniform(-2.0, 2.0, size=3)  # centroidal momentum of a non-point-mass body
    return p_st, v, L_c


def test_vz_transfer_equals_exact_cross_product_on_flat_ground():
    rng = np.random.default_rng(2)
    for _ in range(20):
        p_st, v, L_c = _random_state(rng)
        p_sw = np.array([rng.uniform(-0.4, 0.4), rng.uniform(-0.4, 0.4), p_st[2]])  # same height: flat ground
        c = np.array([0.3, -0.1, p_st[2]])
        r1, r2 = c - p_st, c - p_sw
        L1 = L_c + np.cross(p_st, M * v)
        L2_exact = L1 + np.cross(r1 - r2, M * v)
        # Both ways to get the momentum about the new contact agree.
        np.testing.assert_allclose(L2_exact, L_c + np.cross(p_sw, M * v), atol=1e-12)
        # The 3-D convenience and the two generic pairs.
        np.testing.assert_allclose(lip.transfer_3d(L1, p_st, p_sw, v, M), L2_exact[:2], atol=1e-11)
        Ly2 = lip.transfer(L1[1], p_st[0], p_sw[0], v[2], M)
        Lt2 = lip.transfer(-L1[0], p_st[1], p_sw[1], v[2], M)
        assert Ly2 == pytest.approx(L2_exact[1], abs=1e-11)
        assert -Lt2 == pytest.approx(L2_exact[0], abs=1e-11)


def test_transfer_without_vz_is_continuous():
    assert lip.transfer(7.5, 0.2, -0.2, 0.0, M) == 7.5


@pytest.mark.parametrize("v_z", [0.0, 0.3, -0.4])
def test_foot_placement_is_deadbeat_on_the_ideal_lip(v_z):
    """Predict to T-, place the foot, transfer L about the new contact with v_z, flow T: L = L_des."""
    rng = np.random.default_rng(3)
    for _ in range(10):
        p, L = rng.uniform(-0.2, 0.2), rng.uniform(-15, 15)
        t_rem = rng.uniform(0.0, T)
        L_des = rng.uniform(-15, 15)
        p_hat, L_hat = lip.predict_end_of_step(p, L, t_rem, M, H, G)
        if v_z == 0.0:
            p_sw = lip.foot_placement(L_des, L_hat, T, M, H, G)
            assert p_sw == pytest.approx(lip.foot_placement_vz(L_des, L_hat, p_hat, 0.0, T, M, H, G), abs=1e-14)
        else:
            p_sw = lip.foot_placement_vz(L_des, L_hat, p_hat, v_z, T, M, H, G)
        L_plus = lip.transfer(L_hat, p_hat, p_sw, v_z, M)
        _, L_end = lip.flow(p_sw, L_plus, T, M, H, G)
        assert L_end == pytest.approx(L_des, abs=1e-9)


def test_vz_foot_placement_is_deadbeat_in_3d_with_the_cross_product_transfer():
    """Both planes at once, with the touchdown transfer computed by np.cross."""
    rng = np.random.default_rng(4)
    for _ in range(10):
        p_st, v, L_c = _random_state(rng)
        p_st[2] = H
        v[2] = rng.uniform(-0.4, 0.4)
        L1 = L_c + np.cross(p_st, M * v)
        L_des = rng.uniform(-15, 15, size=2)  # (L_x, L_y)
        p_sw_x = lip.foot_placement_vz(L_des[1], L1[1], p_st[0], v[2], T, M, H, G)
        p_sw_y = lip.foot_placement_vz(-L_des[0], -L1[0], p_st[1], v[2], T, M, H, G)
        p_sw = np.array([p_sw_x, p_sw_y, H])
        r_st, r_sw = -p_st, -p_sw  # CoM at the origin
        L2 = L1 + np.cross(r_st - r_sw, M * v)
        _, Ly_end = lip.flow(p_sw_x, L2[1], T, M, H, G)
        _, Lt_end = lip.flow(p_sw_y, -L2[0], T, M, H, G)
        np.testing.assert_allclose([-Lt_end, Ly_end], L_des, atol=1e-9)


def test_basic_law_matches_paper_formula():
    l = np.sqrt(G / H)
    L_des, L_hat = 12.0, 9.0
    expected = (L_des - np.cosh(l * T) * L_hat) / (M * H * l * np.sinh(l * T))
    assert lip.foot_placement(L_des, L_hat, T, M, H, G) == pytest.approx(expected, rel=1e-14)
    assert lip.omega(H, G) == pytest.approx(l)


@pytest.mark.parametrize(
    "call, match",
    [
        (lambda: lip.flow(0.1, 1.0, -0.01, M, H, G), "tau_s.*>= 0"),
        (lambda: lip.predict_end_of_step(0.1, 1.0, -1e-3, M, H), "t_remaining_s.*>= 0"),
        (lambda: lip.flow(0.1, 1.0, 0.1, 0.0, H), "mass_kg must be > 0"),
        (lambda: lip.flow(0.1, 1.0, 0.1, -3.0, H), "mass_kg must be > 0"),
        (lambda: lip.flow(0.1, 1.0, 0.1, M, 0.0), "H_m.*must be > 0"),
        (lambda: lip.flow(0.1, 1.0, 0.1, M, -0.8), "H_m.*must be > 0"),
        (lambda: lip.flow(np.nan, 1.0, 0.1, M, H), "p_m must be finite"),
        (lambda: lip.flow(0.1, np.inf, 0.1, M, H), "L_Nms must be finite"),
        (lambda: lip.flow(np.array([0.1, np.nan]), 1.0, 0.1, M, H), "p_m must be finite"),
        (lambda: lip.flow(0.1, 1.0, np.nan, M, H), "tau_s.*finite"),
        (lambda: lip.foot_placement(1.0, 1.0, 0.0, M, H), "T_s.*must be > 0"),
        (lambda: lip.foot_placement(1.0, 1.0, -0.3, M, H), "T_s.*must be > 0"),
        (lambda: lip.foot_placement(np.nan, 1.0, T, M, H), "L_des_Nms must be finite"),
        (lambda: lip.foot_placement_vz(1.0, 1.0, 0.1, 0.1, T, M, -1.0), "H_m.*must be > 0"),
        (lambda: lip.foot_placement_vz(1.0, 1.0, 0.1, np.inf, T, M, H), "v_z_mps must be finite"),
        (lambda: lip.foot_placement_vz(1.0, 1.0, 0.1, 10.0, T, M, H), "no solution"),
        (lambda: lip.transfer(1.0, 0.1, 0.2, 0.1, 0.0), "mass_kg must be > 0"),
        (lambda: lip.transfer(1.0, np.nan, 0.2, 0.1, M), "p_st_m must be finite"),
        (lambda: lip.transfer_3d([1, 2], [0, 0, 1], [0, 0, 1], [0, 0, 0], M), r"shape \(3,\)"),
        (lambda: lip.transfer_3d([1, 2, 3], [0, 0, np.inf], [0, 0, 1], [0, 0, 0], M), "p_st_world_m must be finite"),
        (lambda: lip.omega(0.0), "H_m.*must be > 0"),
        (lambda: lip.flow(0.1, 1.0, 0.1, M, H, 0.0), "g_mps2.*must be > 0"),
    ],
)
def test_bad_input_raises_input_error(call, match):
    with pytest.raises(InputError, match=match):
        call()


def test_input_error_is_a_value_error():
    with pytest.raises(ValueError):
        lip.flow(0.1, 1.0, -1.0, M, H)


@pytest.mark.parametrize("bad", ["a", 1j, [1.0, "x"]])
def test_non_numeric_input_is_an_input_error(bad):
    with pytest.raises(InputError, match="p_m must be a real number"):
        lip.flow(bad, 1.0, 0.3, 32.0, 0.8)


def test_transfer_with_height_equals_exact_cross_product_on_any_ground():
    """transfer_3d and the generic pairs with the contacts' height difference are (r_1 - r_2) x m v."""
    rng = np.random.default_rng(12)
    for _ in range(20):
        p_st, v, L_c = _random_state(rng)
        p_sw = np.array([rng.uniform(-0.4, 0.4), rng.uniform(-0.4, 0.4), p_st[2] + rng.uniform(-0.2, 0.2)])
        L1 = L_c + np.cross(p_st, M * v)
        L2_exact = L_c + np.cross(p_sw, M * v)  # about the new contact
        np.testing.assert_allclose(lip.transfer_3d(L1, p_st, p_sw, v, M), L2_exact[:2], atol=1e-11)
        dz = p_st[2] - p_sw[2]  # r_2z - r_1z
        Ly2 = lip.transfer(L1[1], p_st[0], p_sw[0], v[2], M, dz, v[0])
        Lt2 = lip.transfer(-L1[0], p_st[1], p_sw[1], v[2], M, dz, v[1])
        np.testing.assert_allclose([-Lt2, Ly2], L2_exact[:2], atol=1e-11)
        # The flat-ground form misses the height term m dz v.
        assert abs(lip.transfer(L1[1], p_st[0], p_sw[0], v[2], M) - L2_exact[1]) == pytest.approx(
            abs(M * dz * v[0]), abs=1e-9
        )


@pytest.mark.parametrize("dz", [-0.2, 0.15])
def test_height_foot_placement_is_deadbeat_on_the_ideal_lip(dz):
    """With L = m H v at touchdown (a point mass on a plane of intercept H), the dz law is deadbeat."""
    rng = np.random.default_rng(13)
    for _ in range(10):
        p, L, L_des, v_z = rng.uniform(-0.2, 0.2), rng.uniform(-15, 15), rng.uniform(-15, 15), rng.uniform(-0.3, 0.3)
        p_hat, L_hat = lip.predict_end_of_step(p, L, rng.uniform(0.0, T), M, H, G)
        p_sw = lip.foot_placement_vz(L_des, L_hat, p_hat, v_z, T, M, H, G, dz_m=dz)
        L_plus = lip.transfer(L_hat, p_hat, p_sw, v_z, M, dz, L_hat / (M * H))
        assert lip.flow(p_sw, L_plus, T, M, H, G)[1] == pytest.approx(L_des, abs=1e-9)
        assert lip.foot_placement_vz(L_des, L_hat, p_hat, v_z, T, M, H, G) != pytest.approx(p_sw, abs=1e-3)
    with pytest.raises(InputError, match="dz_m=1.0 m must be smaller in size than H_m"):
        lip.foot_placement_vz(1.0, 1.0, 0.0, 0.0, T, M, H, G, dz_m=1.0)
