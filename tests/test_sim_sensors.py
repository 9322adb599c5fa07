"""The plant's sensors: the exact IMU against the simulator's truth, the robot model's noise statistics,
encoder quantisation, contact switches and determinism per seed."""

from __future__ import annotations

import dataclasses
import math
from types import SimpleNamespace

import mujoco
import numpy as np
import pytest

from amlip_qp.control.tracker import Tracker
from amlip_qp.exceptions import InputError
from amlip_qp.messages import TrackerResult
from amlip_qp.sim.scenarios import factory
from amlip_qp.sim.scenarios.scenarios import Scenario
from amlip_qp.sim.sensing.sensors import PlantSensors, SensorSettings, base_indices
from amlip_qp.sim.world.plant_loader import load_plant

DT = 0.0005


@pytest.fixture(scope="module")
def cassie():
    return factory.load("cassie")


@pytest.fixture(scope="module")
def plant(cassie):
    return load_plant("cassie", cassie)


class HoldTracker(Tracker):
    """Joint PD to the stand keyframe (a robot that just stands)."""

    name = "hold"

    def __init__(self, robot, kp=400.0, kd=10.0):
        self.q_idx, self.v_idx = robot.actuated.pin_q_idx, robot.actuated.pin_v_idx
        self.q_ref = robot.q_stand[self.q_idx].copy()
        self.kp, self.kd = kp, kd

    def compute(self, kin, target):
        return TrackerResult(tau_Nm=self.kp * (self.q_ref - kin.q[self.q_idx]) - self.kd * kin.v[self.v_idx])


def _tumbling_data(plant):
    """Plant data at a tilted, moving state, forwarded (the sensors are computed at this state)."""
    d = plant.new_data("stand")
    rng = np.random.default_rng(1)
    rot = np.zeros(4)
    mujoco.mju_axisAngle2Quat(rot, np.array([0.3, -0.5, 0.8]) / np.linalg.norm([0.3, -0.5, 0.8]), 0.7)
    d.qpos[3:7] = rot
    d.qpos[2] += 0.5
    d.qvel[:] = rng.uniform(-1.0, 1.0, d.qvel.size)
    mujoco.mj_forward(plant.model, d)
    return d


def test_exact_imu_is_the_base_orientation_and_angular_velocity(plant):
    d = _tumbling_data(plant)
    q, v = plant.read_state(d)
    imu = PlantSensors(plant).exact_imu(d)
    # the IMU's axes are the base's: the orientation is the base's, the gyro its angular velocity in base axes
    assert np.allclose(imu.quat_xyzw, q[3:7], atol=1e-12) or np.allclose(imu.quat_xyzw, -q[3:7], atol=1e-12)
    assert np.allclose(imu.gyro_radps, v[3:6], atol=1e-12)
    assert np.linalg.norm(imu.gyro_radps) > 0.5


def test_exact_accelerometer_reads_plus_g_up_at_rest():
    """A base welded to the world, tilted: the accelerometer reads the world's +g in IMU axes."""
    from amlip_qp.paths import MODELS_DIR
    from amlip_qp.sim.world.imu_site import IMU_ACCEL_SENSOR, IMU_QUAT_SENSOR, imu_spec_edit

    spec = mujoco.MjSpec.from_file(str(MODELS_DIR / "cassie.xml"))
    spec.delete(spec.joint("floating-base"))
    spec.delete(spec.key("stand"))
    quat = np.zeros(4)
    mujoco.mju_axisAngle2Quat(quat, np.array([1.0, 2.0, 0.5]) / np.linalg.norm([1.0, 2.0, 0.5]), 0.4)
    spec.body("cassie-pelvis").quat = quat
    imu_spec_edit(spec, "cassie-pelvis", (0.03155, 0.0, -0.07996))
    m = spec.compile()
    d = mujoco.MjData(m)
    mujoco.mj_forward(m, d)
    R = np.zeros(9)
    mujoco.mju_quat2Mat(R, quat)
    adr = {
        n: m.sensor_adr[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_SENSOR, n)]
        for n in (IMU_ACCEL_SENSOR, IMU_QUAT_SENSOR)
    }
    accel = d.sensordata[adr[IMU_ACCEL_SENSOR] : adr[IMU_ACCEL_SENSOR] + 3]
    assert np.allclose(accel, R.reshape(3, 3).T @ np.array([0.0, 0.0, 9.81]), atol=1e-9)
    assert np.allclose(d.sensordata[adr[IMU_QUAT_SENSOR] : adr[IMU_QUAT_SENSOR] + 4], quat, atol=1e-12)


def test_robot_imu_white_noise_has_the_set_standard_deviation(plant):
    d = _tumbling_data(plant)
    settings = SensorSettings(gyro_bias_walk_radps_rts=0.0, accel_bias_walk_mps2_rts=0.0)
    sens = PlantSensors(plant, "robot", dt_s=DT, seed=4, settings=settings)
    exact = sens.exact_imu(d)
    n = 20000
    gyro = np.array([sens.robot_imu(d).gyro_radps for _ in range(n)]) - exact.gyro_radps
    accel = np.array([sens.robot_imu(d).accel_mps2 for _ in range(n)]) - exact.accel_mps2
    sg = settings.gyro_noise_density_radps_rthz / math.sqrt(DT)
    sa = settings.accel_noise_density_mps2_rthz / math.sqrt(DT)
    assert sg == pytest.approx(0.0035 * math.pi / 180 * math.sqrt(2000))  # VN-100 density at 2 kHz
    assert np.allclose(gyro.std(axis=0), sg, rtol=0.03) and np.allclose(accel.std(axis=0), sa, rtol=0.03)
    assert np.all(np.abs(gyro.mean(axis=0)) < 4 * sg / math.sqrt(n))
    assert np.all(np.abs(accel.mean(axis=0)) < 4 * sa / math.sqrt(n))


def test_robot_imu_biases_drift_like_a_random_walk(plant):
    d = _tumbling_data(plant)
    walk = 0.02
    settings = SensorSettings(
        gyro_noise_density_radps_rthz=0.0,
        accel_noise_density_mps2_rthz=0.0,
        orientation_noise_rad=0.0,
        gyro_bias_walk_radps_rts=walk,
        accel_bias_walk_mps2_rts=walk,
    )
    exact = PlantSensors(plant).exact_imu(d)
    early, late = [], []
    for seed in range(150):
        sens = PlantSensors(plant, "robot", dt_s=DT, seed=seed, settings=settings)
        for k in range(400):
            imu = sens.robot_imu(d)
            if k == 99:
                early.append(imu.gyro_radps - exact.gyro_radps)
        late.append(imu.gyro_radps - exact.gyro_radps)
        assert np.allclose(imu.accel_mps2 - exact.accel_mps2, sens.accel_bias_mps2, atol=1e-12)
    var_early, var_late = np.var(early), np.var(late)
    # variance walk^2 t: 100 and 400 samples
    assert var_late == pytest.approx(walk**2 * 400 * DT, rel=0.2)
    assert var_late / var_early == pytest.approx(4.0, rel=0.3)


def test_robot_encoders_are_quantised_and_velocities_noisy(cassie, plant):
    d = plant.new_data("stand")
    sens = PlantSensors(plant, "robot", dt_s=DT, seed=0)
    q0, v0 = plant.read_state(d)
    meas = sens.measure(d, q0.copy(), v0.copy(), base_known=False)
    smap = cassie.state_map
    step_hip = 2 * math.pi / (8192 * 25)  # motor encoder through the hip-roll gear
    step_shin = 2 * math.pi / 2**18  # joint encoder of the knee spring
    for name, step in (("left-hip-roll", step_hip), ("right-shin", step_shin)):
        i = smap.joint_pin_q[name]
        assert meas.q[i] / step == pytest.approx(round(meas.q[i] / step), abs=1e-6)
        assert abs(meas.q[i] - q0[i]) <= step / 2 + 1e-15
    joints = np.array([smap.joint_pin_v[n] for n in cassie.joint_names])
    dv = meas.v[joints] - v0[joints]
    assert 0 < np.max(np.abs(dv)) < 6 * SensorSettings().joint_vel_noise_radps
    # no base state from the robot's sensors
    assert not meas.base_known and np.all(np.isnan(meas.q[:7])) and np.all(np.isnan(meas.v[:6]))
    assert meas.imu is not None


def test_contact_switches_from_a_noisy_force_threshold(cassie):
    sim = factory.build_simulation(Scenario("stand", "cassie", 0.3), HoldTracker(cassie), sensors="robot")
    sim.run(0.3)
    plant, d = sim.plant, sim.data  # standing: each foot carries about half the weight
    sens = PlantSensors(plant, "robot", dt_s=DT, seed=0)
    assert all(f > 100.0 for f in sens.contact_forces_N(d).values())
    assert sens.exact_contact(d) == {"left": True, "right": True}
    q, v = plant.read_state(d)
    assert all(all(sens.measure(d, q.copy(), v.copy(), True).foot_contact.values()) for _ in range(100))
    air = plant.new_data("stand")
    air.qpos[2] += 0.3
    mujoco.mj_forward(plant.model, air)
    assert sens.exact_contact(air) == {"left": False, "right": False}
    assert not any(any(sens.measure(air, q.copy(), v.copy(), True).foot_contact.values()) for _ in range(100))
    # a force noise far above the threshold switches at random: half the time on
    noisy = PlantSensors(plant, "robot", dt_s=DT, seed=1, settings=SensorSettings(contact_force_noise_N=1e5))
    on = [noisy.measure(air, q.copy(), v.copy(), True).foot_contact["left"] for _ in range(2000)]
    assert 0.45 < np.mean(on) < 0.55


def test_ideal_measurement_is_the_exact_state(plant):
    d = _tumbling_data(plant)
    q, v = plant.read_state(d)
    meas = PlantSensors(plant).measure(d, q.copy(), v.copy(), base_known=True)
    assert np.array_equal(meas.q, q) and np.array_equal(meas.v, v) and meas.base_known
    assert np.array_equal(meas.imu.gyro_radps, PlantSensors(plant).exact_imu(d).gyro_radps)


def test_robot_sensors_are_deterministic_for_a_seed(plant):
    d = _tumbling_data(plant)
    q, v = plant.read_state(d)

    def sample(seed):
        sens = PlantSensors(plant, "robot", dt_s=DT, seed=seed)
        return [sens.measure(d, q.copy(), v.copy(), False) for _ in range(3)]

    a, b, c = sample(5), sample(5), sample(6)
    for x, y in zip(a, b):
        assert np.array_equal(x.imu.gyro_radps, y.imu.gyro_radps) and np.array_equal(x.v, y.v, equal_nan=True)
    assert not np.array_equal(a[-1].imu.accel_mps2, c[-1].imu.accel_mps2)


def test_bad_settings_and_models_are_refused(plant):
    with pytest.raises(InputError, match="gyro_noise_density_radps_rthz must be >= 0"):
        SensorSettings(gyro_noise_density_radps_rthz=-1.0)
    with pytest.raises(InputError, match="motor_encoder_counts_per_rev must be > 0"):
        SensorSettings(motor_encoder_counts_per_rev=0.0)
    with pytest.raises(InputError, match="finite"):
        SensorSettings(joint_vel_noise_radps=float("nan"))
    with pytest.raises(InputError, match="unknown sensor model 'lidar'"):
        PlantSensors(plant, "lidar")


def _same_measurement(a, b) -> bool:
    return (
        a.t_s == b.t_s
        and a.q.tobytes() == b.q.tobytes()
        and a.v.tobytes() == b.v.tobytes()
        and a.foot_contact == b.foot_contact
        and a.base_known == b.base_known
        and all(
            getattr(a.imu, f).tobytes() == getattr(b.imu, f).tobytes()
            for f in ("quat_xyzw", "gyro_radps", "accel_mps2")
        )
    )


@pytest.mark.parametrize("model", ["ideal", "robot"])
@pytest.mark.parametrize("base_known", [True, False])
def test_bind_measures_what_measure_does(plant, model, base_known):
    """Bound once to the data, every tick: the same measurement, contact switches and noise streams included."""
    d = plant.new_data("stand")
    ref, bound = PlantSensors(plant, model, seed=4), PlantSensors(plant, model, seed=4)
    measure = bound.bind(d, base_known)
    rng = np.random.default_rng(6)
    switches = set()
    for _ in range(400):  # settling on the floor, then lifted feet: the switches change
        plant.write_ctrl(d, rng.uniform(-30.0, 30.0, plant.robot.nu))
        mujoco.mj_step(plant.model, d)
        q, v = plant.read_state(d)
        a = ref.measure(d, q.copy(), v.copy(), base_known)
        b = measure(d.time, q.copy(), v.copy())
        assert _same_measurement(a, b)
        switches.add(tuple(b.foot_contact.values()))
    assert len(switches) > 1


def test_the_base_is_the_first_free_joint_or_refused(cassie):
    """The harness logs the true base from the state reader's first free joint: the same joint."""
    bq, bv = base_indices(cassie)
    assert (bq.start, bv.start) == cassie.state_map.free[0][2:]
    for free in ((), ((0, 0, 7, 6),)):
        other = SimpleNamespace(
            name="other", is_floating=True, root_joint_names=cassie.root_joint_names,
            state_map=dataclasses.replace(cassie.state_map, free=free),
        )  # fmt: skip
        with pytest.raises(InputError, match="is not the first free joint"):
            base_indices(other)


def test_a_plant_without_the_imu_gives_ideal_measurements_without_a_reading(cassie):
    from amlip_qp.sim.world.plant import Plant

    bare = Plant(cassie.mj_model, cassie, "bare")  # the robot's own model: no IMU sensors
    d = cassie.new_mj_data("stand")  # a little above the floor
    for _ in range(100):  # 50 ms: the feet land
        mujoco.mj_step(cassie.mj_model, d)
    sens = PlantSensors(bare, "ideal", dt_s=DT)
    assert not sens.has_imu and sens.exact_imu(d) is None
    q, v = bare.read_state(d)
    meas, bound = sens.measure(d, q.copy(), v.copy(), True), sens.bind(d, True)(float(d.time), q.copy(), v.copy())
    for m in (meas, bound):  # on both feet, the exact state
        assert m.imu is None and m.foot_contact == {"left": True, "right": True}
        assert np.array_equal(m.q, q) and np.array_equal(m.v, v) and m.base_known
    with pytest.raises(InputError, match="plant bare has no sensor 'amlip-imu-quat'"):
        PlantSensors(bare, "robot", dt_s=DT)
