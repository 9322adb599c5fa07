"""Estimator: L about the stance contact, Kalman filtering, touchdown resets."""

import numpy as np
import pytest

from amlip_qp.control.estimator import Estimator, Measurement
from amlip_qp.exceptions import InputError
from amlip_qp.robots import RobotKinematics, load_robot


@pytest.fixture(scope="module")
def cassie():
    return load_robot("cassie")


def _state(robot, rng):
    q = robot.q_stand.copy()
    v = np.zeros(robot.nv)
    v[:3] = [0.6, 0.1, -0.05]
    v[6:] = rng.normal(0.0, 0.3, robot.nv - 6)
    return q, v


def test_measured_L_is_the_momentum_about_the_stance_contact(cassie):
    rng = np.random.default_rng(0)
    q, v = _state(cassie, rng)
    kin = RobotKinematics(cassie)
    est = Estimator(kin, 0.0005, kalman=False).update(Measurement(0.0, q, v), "right")
    ref = RobotKinematics(cassie)
    ref.update(q, v)
    r = ref.contact_position("right")
    np.testing.assert_allclose(est.stance_contact_m, r, atol=1e-12)
    np.testing.assert_allclose(est.p_st_m, ref.com() - r, atol=1e-12)
    np.testing.assert_allclose(est.L_Nms, ref.angular_momentum_about(r), atol=1e-10)
    np.testing.assert_allclose(est.L_meas_Nms, est.L_Nms, atol=0)


def test_kalman_filter_reduces_measurement_noise(cassie):
    """Noisy joint velocities make a noisy L; the filters cut its RMS error."""
    rng = np.random.default_rng(1)
    q, v = _state(cassie, rng)
    kin = RobotKinematics(cassie)
    truth = RobotKinematics(cassie)
    truth.update(q, v)
    L_true = truth.angular_momentum_about(truth.contact_position("left"))
    est = Estimator(kin, 0.0005, kalman=True)
    raw, filt = [], []
    for k in range(400):
        vn = v + np.r_[rng.normal(0, 0.02, 6), rng.normal(0, 0.05, cassie.nv - 6)]
        e = est.update(Measurement(k * 0.0005, q, vn), "left")
        if k > 100:
            raw.append(e.L_meas_Nms[:2] - L_true[:2])
            filt.append(e.L_Nms[:2] - L_true[:2])
    # The state is frozen while the filter's model predicts L_dot = m g p, so the
    # filtered value may drift slowly: compare the scatter (std), not the bias.
    raw, filt = np.array(raw), np.array(filt)
    assert np.std(filt, axis=0).max() < 0.4 * np.std(raw, axis=0).min()


def test_touchdown_restarts_the_filters_from_the_new_contact(cassie):
    rng = np.random.default_rng(2)
    q, v = _state(cassie, rng)
    kin = RobotKinematics(cassie)
    est = Estimator(kin, 0.0005)
    for k in range(5):
        est.update(Measurement(k * 0.0005, q, v), "left")
    e = est.update(Measurement(0.01, q, v), "right", touchdown=True)
    np.testing.assert_allclose(e.L_Nms, e.L_meas_Nms, atol=1e-12)


def test_bad_control_period_is_a_typed_error(cassie):
    with pytest.raises(InputError, match="dt_s"):
        Estimator(RobotKinematics(cassie), 0.0)
