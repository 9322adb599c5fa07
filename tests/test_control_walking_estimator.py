"""Estimator: L about the stance contact, Kalman filtering, touchdown resets."""

import numpy as np
import pytest

from amlip_qp.alip.kalman import AngularMomentumFilter
from amlip_qp.control.walking.estimator import Estimator, planner_state
from amlip_qp.exceptions import InputError
from amlip_qp.messages import Measurement, StateEstimate
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
    estimator = Estimator(kin, 0.0005, kalman=False)
    estimator.observe(Measurement(0.0, q, v))
    est = estimator.estimate("right")
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
        est.observe(Measurement(k * 0.0005, q, vn))
        e = est.estimate("left")
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
        est.observe(Measurement(k * 0.0005, q, v))
        est.estimate("left")
    est.observe(Measurement(0.01, q, v))
    e = est.estimate("right", touchdown=True)
    np.testing.assert_allclose(e.L_Nms, e.L_meas_Nms, atol=1e-12)


def test_bad_control_period_is_a_typed_error(cassie):
    with pytest.raises(InputError, match="dt_s"):
        Estimator(RobotKinematics(cassie), 0.0)


def test_the_filters_are_the_librarys_momentum_filter(cassie):
    """The estimator's L is AngularMomentumFilter's, bit for bit: reset from the first
    measurement, then one step per tick with p_st and the measured L about the stance contact."""
    rng = np.random.default_rng(3)
    q, v = _state(cassie, rng)
    kin = RobotKinematics(cassie)
    est = Estimator(kin, 0.0005)
    ref = AngularMomentumFilter(cassie.mass_kg)
    for k in range(20):
        vn = v + rng.normal(0, 0.05, cassie.nv)
        est.observe(Measurement(k * 0.0005, q, vn))
        e = est.estimate("left")
        Lx, Ly, Lz = e.L_meas_Nms.tolist()
        if k == 0:
            ref.reset(Lx, Ly)
            expect = (Lx, Ly)
        else:
            expect = ref.step(e.p_st_m[0], e.p_st_m[1], Lx, Ly, 0.0005)
        assert tuple(e.L_Nms[:2]) == expect and e.L_Nms[2] == Lz


def test_planner_state_is_the_state_estimate_constructor_with_its_checks_and_errors():
    """The positional fast path gives the constructor's object (the arrays kept), and for every bad input
    the constructor's InputError."""
    H = 0.8  # a CoM height, m
    names = ("stance", "p_st_m", "L_Nms", "v_z_mps", "t_in_step_s", "com_m")
    good = dict(stance="right", p_st_m=np.array([0.03, -0.1, H]), L_Nms=np.array([1.5, 12.0, 0.2]),
                v_z_mps=0.05, t_in_step_s=0.1, com_m=np.array([1.0, 0.5, H]))  # fmt: skip
    got, ref = planner_state(*good.values()), StateEstimate(**good)
    assert type(got) is StateEstimate and repr(got) == repr(ref)
    assert all(getattr(got, n) is good[n] for n in names)
    with pytest.raises(AttributeError):
        got.v_z_mps = 0.0  # type: ignore[misc]
    converted = planner_state("left", [0.03, -0.1, H], np.array([1, 12, 0]), 0, 0.1, good["com_m"])
    assert converted.L_Nms.dtype == np.float64 and converted.p_st_m.tolist() == [0.03, -0.1, H]
    bad = [
        (dict(stance="middle"), "stance must be 'left' or 'right'"),
        (dict(p_st_m=np.array([0.0, np.nan, H])), r"NaN or inf in \['p_st_m'\]"),
        (dict(L_Nms=np.array([np.inf, 0.0, 0.0])), r"NaN or inf in \['L_Nms'\]"),
        (dict(com_m=np.array([0.0, 0.0, -np.inf])), r"NaN or inf in \['com_m'\]"),
        (dict(v_z_mps=np.nan), r"NaN or inf in \['v_z_mps'\]"),
        (dict(t_in_step_s=np.inf), r"NaN or inf in \['t_in_step_s'\]"),
        (dict(t_in_step_s=np.nan), r"NaN or inf in \['t_in_step_s'\]"),
        (dict(t_in_step_s=-0.01), "t_in_step_s must be >= 0"),
        (dict(p_st_m=np.zeros(2)), r"p_st_m must have shape \(3,\)"),
        (dict(com_m=np.array([1e308, 1e308, 0.0])), "NaN or inf in a value too large to add"),
    ]
    for change, match in bad:
        with pytest.raises(InputError, match=match):
            planner_state(*{**good, **change}.values())
