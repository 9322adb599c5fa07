"""The base-state estimators: truth passes the measurement through; the EKF fills the base from the
IMU and the leg kinematics (standing still, divergence, determinism, bad input)."""

import numpy as np
import pytest

from amlip_qp.estimation import TruthBaseEstimator, make_base_estimator
from amlip_qp.estimation.base_estimator import quat_xyzw_to_rot, rot_to_quat_xyzw
from amlip_qp.estimation.invariant_ekf import so3_exp
from amlip_qp.exceptions import InputError
from amlip_qp.messages import ImuReading, Measurement
from amlip_qp.robots import load_robot

IMU = [0.03, 0.0, 0.09]
DT = 0.0005


@pytest.fixture(scope="module")
def cassie():
    return load_robot("cassie")


def _standing(robot, k, gyro=(0.0, 0.0, 0.0), accel=(0.0, 0.0, 9.81), contact=(True, True), base_known=False):
    q = robot.q_stand.copy()
    if not base_known:
        q[0:7] = np.nan  # robot sensors: no base state
    imu = ImuReading(np.array([0.0, 0.0, 0.0, 1.0]), np.array(gyro, dtype=float), np.array(accel, dtype=float))
    return Measurement(k * DT, q, np.zeros(robot.nv), {"left": contact[0], "right": contact[1]}, imu, base_known)


def test_truth_returns_the_measurement_itself(cassie):
    m = _standing(cassie, 0, base_known=True)
    assert TruthBaseEstimator().fill(m) is m
    assert make_base_estimator("truth", cassie, DT).fill(m) is m
    with pytest.raises(InputError, match="--estimator truth needs the true base"):
        TruthBaseEstimator().fill(_standing(cassie, 0))


def test_bad_names_and_settings_are_typed_errors(cassie):
    with pytest.raises(InputError, match="unknown estimator 'kalman'; choose one of truth, ekf"):
        make_base_estimator("kalman", cassie, DT)
    with pytest.raises(InputError, match="needs the IMU's mounting"):
        make_base_estimator("ekf", cassie, DT)
    with pytest.raises(InputError, match="free-floating base"):
        make_base_estimator("ekf", load_robot("rabbit"), DT, IMU)
    with pytest.raises(InputError, match="backend"):
        make_base_estimator("ekf", cassie, DT, IMU, backend="fortran")
    with pytest.raises(InputError, match="dt_s"):
        make_base_estimator("ekf", cassie, 0.0, IMU)
    est = make_base_estimator("ekf", cassie, DT, IMU, backend="numpy")
    m = _standing(cassie, 0)
    with pytest.raises(InputError, match="needs an IMU reading"):
        est.fill(Measurement(0.0, m.q, m.v, m.foot_contact, None, False))
    with pytest.raises(InputError, match="foot-contact switches"):
        est.fill(Measurement(0.0, m.q, m.v, {}, m.imu, False))


@pytest.mark.parametrize("backend", ["numpy", "c"])
def test_the_ekf_keeps_a_standing_robot_where_it_stands(cassie, backend):
    est = make_base_estimator("ekf", cassie, DT, IMU, backend=backend)
    out = None
    for k in range(400):
        m = _standing(cassie, k)
        out = est.fill(m)
        assert np.isnan(m.q[0])  # the input is not modified
    assert out.base_known and not est.diverged
    # the world origin: the stand keyframe's base x, y (no measured base), the contact sites at their stand height
    np.testing.assert_allclose(out.q[0:3], cassie.q_stand[0:3], atol=1e-6)
    np.testing.assert_allclose(out.q[3:7], [0, 0, 0, 1], atol=1e-6)
    np.testing.assert_allclose(out.v[0:6], 0.0, atol=1e-6)
    np.testing.assert_array_equal(out.q[7:], cassie.q_stand[7:])


def test_the_ekf_takes_the_first_measured_base_position_and_the_imu_orientation(cassie):
    est = make_base_estimator("ekf", cassie, DT, IMU, backend="numpy")
    m = _standing(cassie, 0, base_known=True)
    m.q[0:2] = [1.5, -0.5]
    yaw = 0.7
    quat = np.array([0.0, 0.0, np.sin(yaw / 2), np.cos(yaw / 2)])
    m = Measurement(0.0, m.q, m.v, m.foot_contact, ImuReading(quat, m.imu.gyro_radps, m.imu.accel_mps2), False)
    out = est.fill(m)
    np.testing.assert_allclose(out.q[0:3], [1.5, -0.5, cassie.q_stand[2]], atol=1e-9)
    np.testing.assert_allclose(out.q[3:7], quat, atol=1e-12)


def test_the_base_twist_is_the_bias_corrected_gyro_and_the_base_origin_velocity(cassie):
    """Turning about z at 0.5 rad/s with the feet free (no contact): the base origin, 3 cm behind the IMU,
    moves sideways at ``-w x r``."""
    est = make_base_estimator("ekf", cassie, DT, IMU, backend="numpy")
    est.fill(_standing(cassie, 0))
    out = est.fill(_standing(cassie, 1, gyro=(0.0, 0.0, 0.5), contact=(False, False)))
    np.testing.assert_allclose(out.v[3:6], [0.0, 0.0, 0.5], atol=1e-12)
    np.testing.assert_allclose(out.v[0:3], -np.cross([0.0, 0.0, 0.5], IMU), atol=1e-9)


@pytest.mark.parametrize("backend", ["numpy", "c"])
def test_a_nan_imu_makes_the_ekf_diverged_until_reset(cassie, backend):
    est = make_base_estimator("ekf", cassie, DT, IMU, backend=backend)
    est.fill(_standing(cassie, 0))
    est.fill(_standing(cassie, 1, gyro=(np.nan, 0.0, 0.0)))
    out = est.fill(_standing(cassie, 2))
    assert est.diverged and not np.isfinite(out.q[0:7]).all()
    est.reset()
    out = est.fill(_standing(cassie, 3))
    assert not est.diverged and np.isfinite(out.q[0:7]).all()


def test_the_ekf_is_deterministic(cassie):
    rng = np.random.default_rng(0)
    ms = [_standing(cassie, k, gyro=0.01 * rng.normal(size=3), contact=(True, k % 200 < 150)) for k in range(600)]
    runs = []
    for _ in range(2):
        est = make_base_estimator("ekf", cassie, DT, IMU, backend="numpy")
        runs.append(np.array([np.concatenate([o.q[:7], o.v[:6]]) for o in map(est.fill, ms)]))
    np.testing.assert_array_equal(runs[0], runs[1])


def test_quaternion_conversions_round_trip():
    rng = np.random.default_rng(1)
    for _ in range(20):
        R = so3_exp(2.5 * rng.normal(size=3))[0]
        q = rot_to_quat_xyzw(R)
        assert q[3] >= 0 and np.isclose(np.linalg.norm(q), 1.0)
        np.testing.assert_allclose(quat_xyzw_to_rot(q), R, atol=1e-12)
    with pytest.raises(InputError, match="quaternion"):
        quat_xyzw_to_rot([0.0, 0.0, 0.0, 0.0])


def test_without_a_compiler_the_ekf_runs_on_numpy_with_one_warning(cassie, monkeypatch):
    from amlip_qp.codegen.runtime import CodegenFallbackWarning

    monkeypatch.setenv("AMLIP_QP_CC", "none")
    with pytest.warns(CodegenFallbackWarning, match="no compiled EKF"):
        est = make_base_estimator("ekf", cassie, DT, IMU)
    assert est.compiled is None
    out = est.fill(_standing(cassie, 0))
    np.testing.assert_allclose(out.q[0:3], cassie.q_stand[0:3], atol=1e-9)


@pytest.mark.parametrize("pitch", [float("nan"), float("inf"), 1.6, -2.0])
def test_the_ground_pitch_must_be_a_finite_angle_within_a_quarter_turn(pitch):
    est = make_base_estimator("ekf", load_robot("cassie"), 0.0005, [0.03, 0.0, 0.09], backend="numpy")
    with pytest.raises(InputError, match="ground's pitch"):
        est.set_ground_pitch(pitch)
    est.set_ground_pitch(-0.5)
    assert est.ground_pitch_rad == -0.5
