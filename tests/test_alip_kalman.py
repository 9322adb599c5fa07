"""Tests of amlip_qp.alip.kalman: scalar Kalman filters on L."""

import numpy as np
import pytest

from amlip_qp.alip import kalman, lip
from amlip_qp.exceptions import InputError

M, H, G, T, DT = 32.0, 0.8, 9.81, 0.35, 5e-4


def _simulate_noisy_lip(rng, sigma_meas, q_true, n_steps=6):
    """Sagittal periodic LIP gait at 2 kHz with a random ankle-torque disturbance; returns p, L_true, L_meas."""
    v_end = 0.8
    l = np.sqrt(G / H)
    a = v_end * np.tanh(l * T / 2) / l
    n_tick = int(round(T / DT))
    p, L = -a, M * H * v_end
    ps, Ls = [], []
    for _ in range(n_steps):
        for _ in range(n_tick):
            ps.append(p)
            Ls.append(L)
            p, L = lip.flow(p, L, DT, M, H, G)
            L += rng.normal(0.0, np.sqrt(q_true * DT))
        # Touchdown: a deadbeat step back onto the orbit (L continuous for v_z = 0).
        p = lip.foot_placement(M * H * v_end, L, T, M, H, G)
    ps, Ls = np.array(ps), np.array(Ls)
    return ps, Ls, Ls + rng.normal(0.0, sigma_meas, size=Ls.shape)


def test_filter_beats_raw_measurement_on_a_simulated_lip():
    rng = np.random.default_rng(42)
    sigma = 0.5
    ps, L_true, L_meas = _simulate_noisy_lip(rng, sigma, q_true=kalman.DEFAULT_PROCESS_VAR_RATE)
    f = kalman.MomentumFilter1D(M, 1.0, G, L0_Nms=L_meas[0], var0=sigma**2)
    L_filt = np.empty_like(L_true)
    L_filt[0] = L_meas[0]
    for k in range(1, len(ps)):
        L_filt[k] = f.step(ps[k - 1], L_meas[k], DT)
    rms_raw = np.sqrt(np.mean((L_meas - L_true) ** 2))
    rms_filt = np.sqrt(np.mean((L_filt[200:] - L_true[200:]) ** 2))
    assert rms_raw == pytest.approx(sigma, rel=0.05)
    print(f"kalman 1-D: rms_raw={rms_raw:.4f} rms_filt={rms_filt:.4f} ratio={rms_filt / rms_raw:.3f}")
    assert rms_filt / rms_raw < 0.4  # steady-state theory: sqrt(sqrt(q dT r)) / sqrt(r) ~ 0.3


def test_two_plane_filter_uses_the_lateral_sign():
    """With no measurement weight (huge r), the filter follows dL_y = m g p_x dT and dL_x = -m g p_y dT."""
    f = kalman.AngularMomentumFilter(M, G, process_var_rate=1e-12, measurement_var=1e12, L0_Nms=(1.0, 2.0), var0=0.0)
    Lx, Ly = f.step(0.1, 0.05, 0.0, 0.0, DT)
    assert Ly == pytest.approx(2.0 + M * G * 0.1 * DT, abs=1e-12)
    assert Lx == pytest.approx(1.0 - M * G * 0.05 * DT, abs=1e-12)
    assert f.L_Nms == (Lx, Ly)
    f.reset(3.0, 4.0, var=0.5)
    assert f.L_Nms == (3.0, 4.0) and f.x.P == 0.5 and f.y.P == 0.5


def test_two_plane_filter_tracks_a_3d_lip_in_both_planes():
    rng = np.random.default_rng(7)
    p = np.array([-0.05, -0.08, H])
    v = np.array([0.6, 0.25, 0.0])
    f = kalman.AngularMomentumFilter(M, G, L0_Nms=tuple(np.cross(p, M * v)[:2]), var0=0.25)
    err_raw, err_filt = [], []
    for _ in range(600):
        L = np.cross(p, M * v)
        z = L[:2] + rng.normal(0.0, 0.5, size=2)
        Lf = np.array(f.step(p[0], p[1], z[0], z[1], DT)) if err_raw else np.array(f.L_Nms)
        err_raw.append(z - L[:2])
        err_filt.append(Lf - L[:2])
        px, Ly = lip.flow(p[0], L[1], DT, M, H, G)
        py, Lt = lip.flow(p[1], -L[0], DT, M, H, G)
        p = np.array([px, py, H])
        v = np.array([Ly / (M * H), Lt / (M * H), 0.0])
    ratio = np.sqrt(np.mean(np.square(err_filt[100:]), axis=0)) / np.sqrt(np.mean(np.square(err_raw[100:]), axis=0))
    print(f"kalman 2-plane ratio (x, y) = {ratio}")
    assert np.all(ratio < 0.35)


def test_defaults_are_documented_values():
    assert kalman.DEFAULT_PROCESS_VAR_RATE == 4.0 and kalman.DEFAULT_MEASUREMENT_VAR == 0.25
    f = kalman.MomentumFilter1D(M)
    assert f.process_var_rate == 4.0 and f.measurement_var == 0.25


@pytest.mark.parametrize(
    "call, match",
    [
        (lambda: kalman.MomentumFilter1D(0.0), "mass_kg must be > 0"),
        (lambda: kalman.MomentumFilter1D(M, sign=2.0), "sign must be"),
        (lambda: kalman.MomentumFilter1D(M, measurement_var=0.0), "measurement_var must be > 0"),
        (lambda: kalman.MomentumFilter1D(M, process_var_rate=-1.0), "process_var_rate must be > 0"),
        (lambda: kalman.MomentumFilter1D(M, L0_Nms=np.nan), "L0_Nms must be finite"),
        (lambda: kalman.MomentumFilter1D(M).predict(0.1, 0.0), "dT_s > 0"),
        (lambda: kalman.MomentumFilter1D(M).predict(np.nan, DT), "finite p_m"),
        (lambda: kalman.MomentumFilter1D(M).correct(np.inf), "L_meas_Nms must be finite"),
        (lambda: kalman.MomentumFilter1D(M).reset(np.nan), "finite L_Nms"),
        (lambda: kalman.AngularMomentumFilter(M).step(0.1, 0.1, 1.0, np.nan, DT), "L_meas_Nms must be finite"),
    ],
)
def test_bad_input_raises_input_error(call, match):
    with pytest.raises(InputError, match=match):
        call()


def test_step_is_predict_then_correct_bit_for_bit():
    rng = np.random.default_rng(3)
    a, b = kalman.MomentumFilter1D(M, -1.0), kalman.MomentumFilter1D(M, -1.0)
    for _ in range(500):
        p, z = rng.normal(0.0, 0.2), rng.normal(0.0, 5.0)
        b.predict(p, DT)
        assert a.step(p, z, DT) == b.correct(z)
        assert (a.L, a.P) == (b.L, b.P)


def test_step_with_bad_input_fails_like_predict_and_correct():
    f = kalman.MomentumFilter1D(M, L0_Nms=1.0)
    with pytest.raises(InputError, match="finite p_m"):
        f.step(np.nan, 0.0, DT)
    with pytest.raises(InputError, match="dT_s > 0"):
        f.step(0.1, 0.0, -DT)
    assert f.L == 1.0  # predict refused before changing the state
    with pytest.raises(InputError, match="L_meas_Nms must be finite"):
        f.step(0.1, np.inf, DT)
    assert f.L == 1.0 + M * G * 0.1 * DT  # as predict() then correct(): the prediction stays


def test_non_numbers_are_input_errors_and_a_bad_plane_leaves_both_untouched():
    f = kalman.AngularMomentumFilter(32.0)
    f.reset(1.0, 2.0)
    for bad in ("a", None, np.array([1.0, 2.0]), True):
        with pytest.raises(InputError):
            f.x.correct(bad)
        with pytest.raises(InputError):
            f.x.predict(bad, 0.0005)
    before = (f.x.L, f.x.P, f.y.L, f.y.P)
    with pytest.raises(InputError):
        f.step(0.01, 0.02, 1.0, float("nan"), 0.0005)
    assert (f.x.L, f.x.P, f.y.L, f.y.P) == before
    with pytest.raises(InputError):
        kalman.AngularMomentumFilter(32.0, L0_Nms=(1.0,))


def test_two_plane_step_is_the_per_plane_steps_bit_for_bit_whatever_the_number_type():
    """Python floats (the per-tick fast path), numpy scalars and ints (the checked path) give the
    per-plane steps exactly; finite inputs whose sum overflows are not taken for bad ones."""
    rng = np.random.default_rng(4)
    floats, scalars = kalman.AngularMomentumFilter(M), kalman.AngularMomentumFilter(M)
    x, y = kalman.MomentumFilter1D(M, -1.0), kalman.MomentumFilter1D(M, 1.0)
    for i in range(300):
        px, py, lx, ly = (float(a) for a in rng.normal(0.0, [0.2, 0.1, 5.0, 5.0]))
        if i % 3 == 0:
            ly = float(round(ly))  # also stepped as an int below
        expected = (x.step(py, lx, DT), y.step(px, ly, DT))
        assert floats.step(px, py, lx, ly, DT) == expected
        other = (np.float64(px), np.float64(py), np.float64(lx), int(ly) if i % 3 == 0 else np.float64(ly))
        assert scalars.step(*other, DT) == expected
    huge = kalman.AngularMomentumFilter(M)
    x, y = kalman.MomentumFilter1D(M, -1.0), kalman.MomentumFilter1D(M, 1.0)
    L = huge.step(0.0, 0.0, 1e308, 1e308, DT)  # the five add up to inf
    assert np.isfinite(L).all() and L == (x.step(0.0, 1e308, DT), y.step(0.0, 1e308, DT))
