"""The contact-aided invariant EKF (numpy reference): its Jacobians by finite differences, standing
still with exact and noisy biased IMUs, a known analytic walk, divergence detection, determinism."""

import copy

import numpy as np
import pytest

from amlip_qp.estimation.invariant_ekf import (
    DIM,
    GRAVITY_MPS2,
    EkfNoise,
    InvariantEKF,
    blade_is_flat,
    measurement_matrix,
    so3_exp,
)
from amlip_qp.exceptions import InputError
from ekf_cases import walk


def _random_filter(seed=1) -> InvariantEKF:
    rng = np.random.default_rng(seed)
    e = InvariantEKF()
    e.R = so3_exp(rng.normal(size=3))[0]
    e.v, e.p, e.d = rng.normal(size=3), rng.normal(size=3), rng.normal(size=(2, 3))
    e.bg, e.ba = 0.1 * rng.normal(size=3), 0.1 * rng.normal(size=3)
    e.in_contact = (True, True)
    return e


def _error(est: InvariantEKF, true: InvariantEKF) -> np.ndarray:
    """``xi`` of ``est`` relative to ``true`` to first order (right-invariant: ``eta = X_hat X^-1``)."""
    eta = est.R @ true.R.T
    phi = 0.5 * np.array([eta[2, 1] - eta[1, 2], eta[0, 2] - eta[2, 0], eta[1, 0] - eta[0, 1]])
    parts = [phi, est.v - eta @ true.v, est.p - eta @ true.p, est.d[0] - eta @ true.d[0], est.d[1] - eta @ true.d[1]]
    return np.concatenate(parts + [est.bg - true.bg, est.ba - true.ba])


def _perturbed(e: InvariantEKF, i: int, eps: float) -> InvariantEKF:
    out = copy.deepcopy(e)
    xi = np.zeros(DIM)
    xi[i] = eps
    out.retract(xi)
    return out


def test_the_measurement_jacobian_matches_finite_differences():
    e = _random_filter()
    y = (e.d - e.p) @ e.R  # the exact measurement of the true state e
    H = measurement_matrix((True, True))
    eps = 1e-6
    fd = np.column_stack([_perturbed(e, i, eps).innovation(y) / eps for i in range(DIM)])
    assert np.abs(fd - H).max() < 1e-8
    assert np.abs(e.innovation(y)).max() < 1e-12  # no error, no innovation
    assert measurement_matrix((False, True)).shape == (3, DIM) and measurement_matrix((False, False)).shape == (0, DIM)


def test_the_error_dynamics_match_finite_differences_of_the_propagation():
    """``Phi = I + A dt`` against the error between a propagated perturbed and unperturbed state."""
    e = _random_filter()
    rng = np.random.default_rng(2)
    w, a, dt, eps = rng.normal(size=3), rng.normal(size=3), 1e-3, 1e-6
    Phi = np.eye(DIM) + e.error_dynamics() * dt
    ref = copy.deepcopy(e)
    ref.propagate(w, a, dt)
    fd = np.zeros((DIM, DIM))
    for i in range(DIM):
        p = _perturbed(e, i, eps)
        p.propagate(w, a, dt)
        fd[:, i] = _error(p, ref) / eps
    # first order in dt: the neglected terms are O(dt^2 |A|^2)
    assert np.abs(fd - Phi).max() < 5e-5
    # and the bias columns are right to first order in dt (the Jacobian's content beyond the identity)
    assert np.abs((fd - np.eye(DIM))[:, 15:] / dt - e.error_dynamics()[:, 15:]).max() < 0.05
    # a wrong sign in A would be far off
    assert np.abs(fd - (np.eye(DIM) - e.error_dynamics() * dt)).max() > 1e-3


def _run_standing(seconds, dt, gyro_bias, accel_bias, noise, seed=0):
    e = InvariantEKF()
    y = np.array([[0.0, 0.13, -1.0], [0.0, -0.13, -1.0]])
    e.initialise(np.eye(3), [0, 0, 1.0], y)
    rng = np.random.default_rng(seed)
    for _ in range(int(seconds / dt)):
        gyro = np.asarray(gyro_bias) + noise * rng.normal(size=3)
        accel = -GRAVITY_MPS2 + np.asarray(accel_bias) + noise * rng.normal(size=3)
        e.propagate(gyro, accel, dt)
        e.set_contacts((True, True), y)
        e.correct(y + 0.1 * noise * rng.normal(size=(2, 3)))
    return e


def test_standing_still_with_an_exact_imu_stays_put():
    e = _run_standing(5.0, 0.002, (0, 0, 0), (0, 0, 0), 0.0)
    assert np.abs(e.v).max() < 1e-9 and np.abs(e.p - [0, 0, 1.0]).max() < 1e-9
    assert np.abs(e.R - np.eye(3)).max() < 1e-9 and not e.diverged()


@pytest.mark.parametrize("noise", [0.0, 0.02])
def test_standing_still_the_observable_biases_converge(noise):
    """Gyro x/y and accelerometer z biases are observable at rest; gyro z (yaw) and accelerometer x/y
    (against the tilt) are not, so they are not asserted."""
    bg, ba = np.array([0.01, -0.02, 0.005]), np.array([0.1, -0.05, 0.08])
    e = _run_standing(20.0, 0.004, bg, ba, noise)
    assert np.abs(e.bg[:2] - bg[:2]).max() < 0.003  # from an initial error of 0.02 rad/s
    assert abs(e.ba[2] - ba[2]) < 0.02  # from an initial error of 0.08 m/s^2
    assert np.abs(e.v).max() < 0.01
    assert np.abs(e.p[:2]).max() < 0.02 and abs(e.p[2] - 1.0) < 0.01


def _run_walk(samples, dt, noise_settings=None, bias_init=(None, None)):
    e = InvariantEKF(noise_settings)
    s0 = samples[0]
    e.initialise(s0.R, s0.p, s0.y, v=s0.v, bg=bias_init[0], ba=bias_init[1])
    e.set_contacts(s0.in_contact, s0.y)
    errs = []
    for prev, s in zip(samples[:-1], samples[1:]):
        e.propagate(prev.gyro, prev.accel, dt)
        e.set_contacts(s.in_contact, s.y)
        e.correct(s.y)
        eta = e.R @ s.R.T
        errs.append(
            (np.linalg.norm(e.v - s.v), np.linalg.norm(e.p - s.p), np.arccos(min(1.0, (np.trace(eta) - 1) / 2)))
        )
    return e, np.array(errs)


def test_a_known_walk_is_tracked_with_exact_sensors():
    dt = 0.002
    samples = walk(4.0, dt)
    e, errs = _run_walk(samples, dt)
    assert errs[:, 0].max() < 0.003  # m/s
    assert errs[:, 1].max() < 0.003  # m
    assert errs[:, 2].max() < 0.002  # rad
    assert not e.diverged()


def test_a_known_walk_is_tracked_with_biased_noisy_sensors():
    dt = 0.002
    bg, ba = np.array([0.01, -0.01, 0.0]), np.array([0.05, -0.05, 0.1])
    samples = walk(8.0, dt, gyro_bias=bg, accel_bias=ba, noise=0.02, seed=3)
    e, errs = _run_walk(samples, dt)
    late = errs[len(errs) // 2 :]
    assert np.sqrt(np.mean(late[:, 0] ** 2)) < 0.05  # velocity error RMS, m/s
    assert late[:, 2].max() < 0.02  # rad
    assert np.abs(e.bg[:2] - bg[:2]).max() < 0.005


def test_divergence_is_detected():
    e = _run_standing(0.1, 0.002, (0, 0, 0), (0, 0, 0), 0.0)
    assert not e.diverged()
    e.propagate([np.nan, 0, 0], [0, 0, 9.81], 0.002)
    assert e.diverged()
    e = _run_standing(0.1, 0.002, (0, 0, 0), (0, 0, 0), 0.0)
    e.v = np.array([25.0, 0, 0])
    assert e.diverged()
    e = _run_standing(0.1, 0.002, (0, 0, 0), (0, 0, 0), 0.0)
    e.P[3, 3] = 2e4
    assert e.diverged()


def test_the_filter_is_deterministic():
    samples = walk(1.0, 0.002, noise=0.02, seed=5)
    a, ea = _run_walk(samples, 0.002)
    b, eb = _run_walk(samples, 0.002)
    assert np.array_equal(ea, eb) and np.array_equal(a.P, b.P) and np.array_equal(a.d, b.d)


def test_a_swing_foot_is_re_initialised_at_touchdown():
    e = _run_standing(0.1, 0.002, (0, 0, 0), (0, 0, 0), 0.0)
    y_new = np.array([[0.3, 0.13, -0.9], [0.0, -0.13, -1.0]])
    e.set_contacts((False, True), y_new)
    e.set_contacts((True, True), y_new)
    assert np.allclose(e.d[0], e.p + e.R @ y_new[0])
    assert np.allclose(e.P[9:12, 9:12], e.P[6:9, 6:9] + e.noise.kinematics_std**2 * np.eye(3))
    assert np.allclose(e.P[9:12, 0:6], e.P[6:9, 0:6])


def test_a_blade_foot_is_a_contact_only_once_it_rests_flat():
    """A blade landing on its heel (toe 3 degrees up) rolls while loaded: the filter waits until it is
    flat (within 1 degree), then restarts the slot from the kinematics of that tick."""
    e = _run_standing(0.1, 0.002, (0, 0, 0), (0, 0, 0), 0.0)
    flat = np.array([[0.16, 0.0, 0.0], [0.16, 0.0, 0.0]])
    tilted = flat.copy()
    tilted[0] = [0.16 * np.cos(np.radians(3.0)), 0.0, 0.16 * np.sin(np.radians(3.0))]
    e.set_contacts((False, True), np.zeros((2, 3)), flat)
    y_heel = np.array([[0.3, 0.13, -0.9], [0.0, -0.13, -1.0]])
    e.set_contacts((True, True), y_heel, tilted)
    assert e.in_contact == (False, True)
    y_flat = np.array([[0.31, 0.13, -0.91], [0.0, -0.13, -1.0]])
    e.set_contacts((True, True), y_flat, flat)
    assert e.in_contact == (True, True)
    assert np.allclose(e.d[0], e.p + e.R @ y_flat[0])
    # the slope is judged in the world: the same blade is flat for a filter that is pitched by 3 degrees
    e.R = so3_exp([0.0, np.radians(3.0), 0.0])[0]
    assert blade_is_flat(e.R, tilted[0], np.radians(1.0)) and not blade_is_flat(e.R, flat[0], np.radians(1.0))
    # a switch that reports no contact is never overruled by a flat blade
    e.set_contacts((False, False), y_flat, flat)
    assert e.in_contact == (False, False)


@pytest.mark.parametrize("field", ["gyro_std", "kinematics_std", "max_speed_mps", "max_blade_slope_rad"])
@pytest.mark.parametrize("bad", [0.0, -1.0, float("nan")])
def test_bad_noise_settings_say_what_to_fix(field, bad):
    with pytest.raises(InputError, match=field):
        EkfNoise(**{field: bad})


def test_so3_exp_is_a_rotation_with_its_left_jacobian():
    phi = np.array([0.3, -0.2, 0.5])
    R, J = so3_exp(phi)
    assert np.allclose(R @ R.T, np.eye(3)) and np.isclose(np.linalg.det(R), 1.0)
    eps = 1e-7  # Exp(phi + d) ~ Exp(J d) Exp(phi)
    for i in range(3):
        d = np.zeros(3)
        d[i] = eps
        lhs = so3_exp(phi + d)[0] @ R.T
        assert np.allclose((lhs - np.eye(3)) / eps, so3_exp(J @ d)[0] / eps - np.eye(3) / eps, atol=1e-5)
    assert np.allclose(so3_exp(np.zeros(3))[0], np.eye(3))


def test_a_blade_is_flat_against_the_ground_it_stands_on():
    """A blade pitched 30 degrees toe-up lies flat on ground pitched 30 degrees up (pitch -30 degrees,
    positive = descending ahead) within the tolerance, not on level ground; on level ground (pitch 0)
    the test is the horizontal one, the same booleans."""
    tol = np.radians(1.0)
    up30 = 0.2 * np.array([np.cos(np.radians(30.0)), 0.0, np.sin(np.radians(30.0))])
    R = np.eye(3)
    assert blade_is_flat(R, up30, tol, np.radians(-30.0))
    assert blade_is_flat(R, up30, tol, np.radians(-29.5)) and blade_is_flat(R, up30, tol, np.radians(-30.5))
    assert not blade_is_flat(R, up30, tol, np.radians(-28.0)) and not blade_is_flat(R, up30, tol, np.radians(-32.0))
    assert not blade_is_flat(R, up30, tol) and not blade_is_flat(R, up30, tol, np.radians(30.0))
    rng = np.random.default_rng(7)
    for _ in range(2000):
        b = rng.normal(size=3) * np.array([1.0, 1.0, 0.02])
        old = abs(float(b[2])) <= np.sin(tol) * np.sqrt(float(b @ b))
        assert blade_is_flat(R, b, tol, 0.0) == old
