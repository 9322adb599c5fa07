"""Tests of amlip_qp.alip.desired: desired angular momentum and velocity conversions."""

import numpy as np
import pytest

from amlip_qp.alip import desired, kernels, lip
from amlip_qp.exceptions import InputError

M, H, G, T = 32.0, 0.8, 9.81, 0.35
L_OMEGA = np.sqrt(G / H)


def test_forward_and_lateral_speed_terms():
    assert desired.Ly_from_forward_speed(0.7, M, H) == pytest.approx(M * H * 0.7)
    assert desired.Lx_from_lateral_speed(0.3, M, H) == pytest.approx(-M * H * 0.3)


def test_step_width_term_sign_and_value():
    W = 0.25
    expected = 0.5 * M * H * W * L_OMEGA * np.sinh(L_OMEGA * T) / (1 + np.cosh(L_OMEGA * T))
    assert expected == pytest.approx(0.5 * M * H * W * L_OMEGA * np.tanh(L_OMEGA * T / 2))
    assert desired.Lx_from_step_width(W, T, M, H, "left", G) == pytest.approx(expected, rel=1e-14)
    assert desired.Lx_from_step_width(W, T, M, H, "right", G) == pytest.approx(-expected, rel=1e-14)


def test_step_width_momentum_is_the_periodic_walking_in_place_orbit():
    """Left stance starting midway between feet (p_y = -W/2) with the orbit's L_x returns to the same state."""
    W = 0.3
    Lx_end_left = desired.Lx_from_step_width(W, T, M, H, "left", G)
    # Start of a left stance: the orbit is symmetric, so L_x(0+) = -L_x(T-) and p_y(0+) = p_y(T-) = -W/2,
    # where L_x(T-) ends the previous (right) stance: the mirror image of the left stance's end.
    Lx_end_right = -Lx_end_left
    p_y, Lt = lip.flow(-W / 2, -Lx_end_right, T, M, H, G)
    assert p_y == pytest.approx(-W / 2, abs=1e-12)
    assert -Lt == pytest.approx(Lx_end_left, abs=1e-12)


def test_composition_and_rotation_match_the_kernel():
    rng = np.random.default_rng(0)
    for _ in range(5):
        vx, vy, W, D = rng.uniform(-1, 1), rng.uniform(-0.5, 0.5), rng.uniform(0, 0.3), rng.uniform(-3, 3)
        for side, sign in (("left", 1.0), ("right", -1.0)):
            L_h = desired.desired_L_heading(vx, vy, W, T, M, H, side, G)
            assert L_h[1] == pytest.approx(M * H * vx)
            assert L_h[0] == pytest.approx(-M * H * vy + desired.Lx_from_step_width(W, T, M, H, side, G))
            L_w = desired.desired_L_world(vx, vy, W, T, M, H, side, D, G)
            R = np.array([[np.cos(D), -np.sin(D)], [np.sin(D), np.cos(D)]])
            np.testing.assert_allclose(L_w, R @ L_h, atol=1e-12)
            u = np.array([0.05, -0.02, 1.0, 2.0, 0.1, 0.0, vx, vy, D, sign, M, H, T, W, G, 0.0])
            np.testing.assert_allclose(kernels.alip_plan(u)[4:6], L_w, atol=1e-11)


def test_mean_and_end_of_step_velocity_on_the_periodic_gait():
    """On the periodic sagittal orbit that ends each step at v_end, the CoM advances v_mean * T per step."""
    v_end = 0.9
    a_end = v_end * np.tanh(L_OMEGA * T / 2) / L_OMEGA  # p(T-) = a on the orbit p(t) = a sinh(l(t-T/2))/sinh(lT/2)
    p0, L0 = -a_end, M * H * v_end
    pT, LT = lip.flow(p0, L0, T, M, H, G)
    assert pT == pytest.approx(a_end, abs=1e-12) and LT == pytest.approx(L0, abs=1e-10)
    v_mean = (pT - p0) / T
    assert desired.mean_step_velocity(v_end, T, H, G) == pytest.approx(v_mean, rel=1e-12)
    assert desired.end_of_step_velocity(v_mean, T, H, G) == pytest.approx(v_end, rel=1e-12)
    assert desired.mean_to_end_factor(T, H, G) > 1.0


def test_sides():
    assert desired.stance_sign("left") == 1.0 and desired.stance_sign("right") == -1.0
    assert desired.other_side("left") == "right" and desired.other_side("right") == "left"


@pytest.mark.parametrize(
    "call, match",
    [
        (lambda: desired.Ly_from_forward_speed(np.nan, M, H), "vx_mps must be finite"),
        (lambda: desired.Ly_from_forward_speed(1.0, 0.0, H), "mass_kg must be > 0"),
        (lambda: desired.Lx_from_lateral_speed(0.1, M, -H), "H_m.*must be > 0"),
        (lambda: desired.Lx_from_step_width(-0.1, T, M, H, "left"), "W_m.*>= 0"),
        (lambda: desired.Lx_from_step_width(0.1, 0.0, M, H, "left"), "T_s.*must be > 0"),
        (lambda: desired.Lx_from_step_width(0.1, T, M, H, "middle"), "'left' or 'right'"),
        (lambda: desired.desired_L_world(0.1, 0.0, 0.1, T, M, H, "left", np.inf), "heading_next_rad must be finite"),
        (lambda: desired.end_of_step_velocity(1.0, -T, H), "T_s.*must be > 0"),
        (lambda: desired.stance_sign("up"), "'left' or 'right'"),
    ],
)
def test_bad_input_raises_input_error(call, match):
    with pytest.raises(InputError, match=match):
        call()
