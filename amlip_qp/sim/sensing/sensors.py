"""The plant's sensors: the IMU added to every plant, and what the controller is given.

Two sensor models (``--sensors``):

- ``ideal``: the exact state in the controller's coordinates (as before
  sensor models existed), the exact foot-contact switches (floor normal force
  on the foot above a threshold) and the exact IMU sample;
- ``robot``: only what Cassie's hardware gives. The IMU (orientation, gyro,
  accelerometer) with white noise and random-walk gyro and accelerometer
  biases; joint encoders on the motor and spring joints, quantised, with
  noisy velocities; foot contact from the force threshold on a noisy force.
  No base position and no base linear velocity (``base_known=False``: the
  estimator gives the base), unless the estimator is ``truth``: then the
  harness fills the simulator's true base state.

The IMU is a site ``amlip-imu`` where the robot's profile puts it
(:attr:`~amlip_qp.robots.robot.Robot.imu_mount`: any body, a position and axes
in its frame; by default the base body's origin and axes) with MuJoCo sensors
``amlip-imu-quat`` (framequat), ``amlip-imu-gyro`` and ``amlip-imu-accel``, in
the site's own axes; :func:`~amlip_qp.sim.world.imu_site.imu_spec_edit` adds them to a plant's model.
A plant without them (a user's own model, :class:`~amlip_qp.sim.loop.mujoco_loop.MujocoLoop`)
has only the ``ideal`` model, whose measurements then carry no IMU reading.
MuJoCo computes sensors at the start of each plant step, so after the step a
sample describes the state the step started from and the acceleration of the
step (a sample-and-hold, one plant step old); sensors change no trajectory.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, fields

import mujoco
import numpy as np

from amlip_qp.exceptions import InputError
from amlip_qp.messages import ImuReading, Measurement
from amlip_qp.sim.world.contact_sensors import contact_sensor_indices, list_switcher
from amlip_qp.sim.world.imu_site import IMU_ACCEL_SENSOR, IMU_GYRO_SENSOR, IMU_QUAT_SENSOR
from amlip_qp.sim.world.plant import Plant

#: The sensor models of ``--sensors``.
SENSOR_MODELS: tuple[str, ...] = ("ideal", "robot")

_DEG = math.pi / 180.0
_G0 = 9.80665  # standard gravity, m/s^2 (datasheets' "g")


@dataclass(frozen=True)
class SensorSettings:
    """Noise of the ``robot`` sensor model (SI units), modelled on Cassie's hardware.

    IMU: the VectorNav VN-100 (datasheet): gyro noise density 0.0035 deg/s/sqrt(Hz),
    in-run bias stability 10 deg/h; accelerometer noise density 0.14 mg/sqrt(Hz),
    in-run bias stability 0.04 mg; attitude (pitch/roll) accuracy 0.5 deg. The
    white noise of one sample is ``density / sqrt(dt)``; each bias is a random
    walk ``b += walk * sqrt(dt) * N(0, 1)`` from zero, whose walk makes the bias
    move by its in-run stability in about 100 s (``walk = stability / 10``).

    Encoders: Cassie's, as in Agility Robotics' MuJoCo simulator (also dairlib's
    ``CassieEncoder``): 8192 counts per motor revolution on the drives (a joint
    step of ``2 pi / (8192 gear)``; the toe drive has 2^18, the coarser count
    is used for all), 2^18 counts per revolution on the joint encoders of the
    spring joints (shin, tarsus). Velocities: white noise of the order of the
    filtered 2 kHz finite difference of those counts.

    Attributes:
        gyro_noise_density_radps_rthz: Gyro white noise, rad/s/sqrt(Hz).
        gyro_bias_walk_radps_rts: Gyro bias random walk, rad/s/sqrt(s).
        accel_noise_density_mps2_rthz: Accelerometer white noise, m/s^2/sqrt(Hz).
        accel_bias_walk_mps2_rts: Accelerometer bias random walk, m/s^2/sqrt(s).
        orientation_noise_rad: White noise of the reported orientation (rotation vector), rad.
        motor_encoder_counts_per_rev: Counts per motor revolution of the actuated joints' encoders.
        joint_encoder_counts_per_rev: Counts per revolution of the unactuated joints' encoders.
        joint_vel_noise_radps: White noise of the joint velocities, rad/s.
        contact_force_noise_N: White noise of the floor normal force the contact switch
            compares with its threshold, N.
    """

    gyro_noise_density_radps_rthz: float = 0.0035 * _DEG
    gyro_bias_walk_radps_rts: float = 10.0 * _DEG / 3600.0 / 10.0
    accel_noise_density_mps2_rthz: float = 0.14e-3 * _G0
    accel_bias_walk_mps2_rts: float = 0.04e-3 * _G0 / 10.0
    orientation_noise_rad: float = 0.5 * _DEG
    motor_encoder_counts_per_rev: float = 8192.0
    joint_encoder_counts_per_rev: float = 262144.0
    joint_vel_noise_radps: float = 0.01
    contact_force_noise_N: float = 5.0

    def __post_init__(self) -> None:
        for f in fields(self):
            value = getattr(self, f.name)
            positive = f.name.endswith("counts_per_rev")
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
                raise InputError(f"SensorSettings.{f.name} must be a finite number, got {value!r}")
            if value <= 0 if positive else value < 0:
                raise InputError(f"SensorSettings.{f.name} must be {'> 0' if positive else '>= 0'}, got {value!r}")


class PlantSensors:
    """The sensors of a :class:`~amlip_qp.sim.world.plant.Plant`, read once per control tick.

    Args:
        plant: The plant (with the IMU of :func:`~amlip_qp.sim.world.imu_site.imu_spec_edit` for the ``robot`` model).
        model: ``"ideal"`` or ``"robot"``.
        dt_s: Sampling period (the control period), s.
        seed: Seed of the ``robot`` model's noise (its own stream: the run's seed).
        settings: Noise of the ``robot`` model.
        contact_threshold_N: The contact switches' force threshold, N.
    """

    def __init__(
        self,
        plant: Plant,
        model: str = "ideal",
        dt_s: float = 0.0005,
        seed: int = 0,
        settings: SensorSettings | None = None,
        contact_threshold_N: float = 20.0,
    ):
        if model not in SENSOR_MODELS:
            raise InputError(f"unknown sensor model {model!r}; known: {', '.join(SENSOR_MODELS)}")
        if not (dt_s > 0 and math.isfinite(dt_s)):
            raise InputError(f"the sensors' sampling period must be a positive number of s, got {dt_s!r}")
        self.plant = plant
        self.model = model
        self.dt_s = float(dt_s)
        self.settings = settings or SensorSettings()
        self.contact_threshold_N = float(contact_threshold_N)
        self.rng = np.random.default_rng([int(seed), 0x5E45])
        m = plant.model
        adr = {}
        for name in (IMU_QUAT_SENSOR, IMU_GYRO_SENSOR, IMU_ACCEL_SENSOR):
            sid = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_SENSOR, name)
            if sid < 0 and model == "robot":
                raise InputError(
                    f"plant {plant.name} has no sensor {name!r}; load it with sim.world.plant_loader.load_plant"
                )
            adr[name] = int(m.sensor_adr[sid]) if sid >= 0 else -1
        q, g, c = adr[IMU_QUAT_SENSOR], adr[IMU_GYRO_SENSOR], adr[IMU_ACCEL_SENSOR]
        #: Whether the plant has the IMU of :func:`imu_spec_edit` (without it, ``ideal`` measurements have none).
        self.has_imu = min(q, g, c) >= 0
        # sensordata indices of (quat xyzw, gyro, accel): one gather per sample (none without the IMU)
        imu_idx = [q + 1, q + 2, q + 3, q, g, g + 1, g + 2, c, c + 1, c + 2] if self.has_imu else []
        self._imu_idx = np.array(imu_idx, dtype=np.intp)
        self._imu_of: Callable[..., ImuReading | None] = ImuReading.of_packed if self.has_imu else _no_imu
        robot = plant.robot
        smap = robot.state_map
        self._enc_q = np.array([smap.joint_pin_q[n] for n in robot.joint_names], dtype=np.intp)
        self._enc_v = np.array([smap.joint_pin_v[n] for n in robot.joint_names], dtype=np.intp)
        gear = dict(zip(robot.actuated.joint_names, np.abs(robot.actuated.gear)))
        s = self.settings
        self._enc_step = np.array(
            [
                2.0 * math.pi / (s.motor_encoder_counts_per_rev * gear[n])
                if n in gear
                else 2.0 * math.pi / s.joint_encoder_counts_per_rev
                for n in robot.joint_names
            ]
        )
        self._base_q, self._base_v = base_indices(robot)
        #: The gyro and accelerometer biases now (``robot`` model), IMU axes.
        self.gyro_bias_radps = np.zeros(3)
        self.accel_bias_mps2 = np.zeros(3)
        self._forces = dict.fromkeys(plant.foot_body_ids, 0.0)

    # ------------------------------------------------------------------ IMU
    def exact_imu(self, data: mujoco.MjData) -> ImuReading | None:
        """The IMU sample without noise (MuJoCo's sensors); ``None`` for a plant without the IMU."""
        return self._imu_of(data.sensordata[self._imu_idx])

    def robot_imu(self, data: mujoco.MjData) -> ImuReading:
        """The IMU sample with white noise and the random-walk biases (advanced by one sample)."""
        exact = ImuReading.of_packed(data.sensordata[self._imu_idx])  # the robot model has the IMU (checked)
        s, rng, dt = self.settings, self.rng, self.dt_s
        rdt = math.sqrt(dt)
        self.gyro_bias_radps += s.gyro_bias_walk_radps_rts * rdt * rng.standard_normal(3)
        self.accel_bias_mps2 += s.accel_bias_walk_mps2_rts * rdt * rng.standard_normal(3)
        gyro = exact.gyro_radps + self.gyro_bias_radps + s.gyro_noise_density_radps_rthz / rdt * rng.standard_normal(3)
        accel = exact.accel_mps2 + self.accel_bias_mps2 + s.accel_noise_density_mps2_rthz / rdt * rng.standard_normal(3)
        quat = quat_mul_small_rotation(exact.quat_xyzw, s.orientation_noise_rad * rng.standard_normal(3))
        return ImuReading(quat_xyzw=quat, gyro_radps=gyro, accel_mps2=accel)

    # -------------------------------------------------------------- contact
    def contact_forces_N(self, data: mujoco.MjData) -> dict[str, float]:
        """Side -> floor normal force on the foot, N (exact)."""
        forces = self._forces
        for side in forces:
            forces[side] = 0.0
        return self.plant.foot_normal_forces_N(data, forces)

    def exact_contact(self, data: mujoco.MjData) -> dict[str, bool]:
        """Contact switches: the exact normal force above the threshold."""
        return {side: f > self.contact_threshold_N for side, f in self.contact_forces_N(data).items()}

    # ------------------------------------------------------------- measure
    def measure(self, data: mujoco.MjData, q: np.ndarray, v: np.ndarray, base_known: bool) -> Measurement:
        """This tick's :class:`Measurement` from the true ``(q, v)`` (controller coordinates; modified in place).

        Args:
            data: The plant's data after the tick's plant steps.
            q, v: The plant's state from :meth:`~amlip_qp.sim.world.plant.Plant.read_state`.
            base_known: Keep the true base state in ``q``/``v`` (``--estimator truth``);
                otherwise the base part is set to NaN and ``base_known`` is False.
        """
        t = float(data.time)
        if self.model == "ideal":
            imu = self.exact_imu(data)
            contact = self.exact_contact(data)
        else:
            imu = self.robot_imu(data)
            s, rng = self.settings, self.rng
            step = self._enc_step
            q[self._enc_q] = np.round(q[self._enc_q] / step) * step
            v[self._enc_v] += s.joint_vel_noise_radps * rng.standard_normal(step.size)
            forces = self.contact_forces_N(data)
            contact = {
                side: f + s.contact_force_noise_N * float(rng.standard_normal()) > self.contact_threshold_N
                for side, f in forces.items()
            }
        if not base_known:
            q[self._base_q] = np.nan
            v[self._base_v] = np.nan
        return Measurement(t_s=t, q=q, v=v, foot_contact=contact, imu=imu, base_known=bool(base_known))

    def bind(self, data: mujoco.MjData, base_known: bool) -> Callable[[float, np.ndarray, np.ndarray], Measurement]:
        """``f(t_s, q, v)``: :meth:`measure` of ``data`` at its time ``t_s``, with ``data``'s arrays bound once.

        The harness's per-tick measurement; the same :class:`Measurement` as :meth:`measure`
        (tested). ``t_s`` must be ``data.time`` (the harness passes its own count of MuJoCo's
        clock, equal to it bit for bit: ``tests/test_sim_harness.py``).
        """
        if self.model != "ideal" or not base_known:
            return lambda t_s, q, v: self.measure(data, q, v, base_known)
        sensordata, imu_idx, plant = data.sensordata, self._imu_idx, self.plant
        switches = plant.contact_switcher(data, self.contact_threshold_N)
        imu_of = self._imu_of
        contacts = contact_sensor_indices(plant.model, plant.foot_body_ids)
        if contacts is None:  # the switches contact by contact

            def measure(t_s: float, q: np.ndarray, v: np.ndarray) -> Measurement:
                # Measurement(t_s, q, v, foot_contact, imu, base_known), positional: its cheapest call
                return Measurement(t_s, q, v, switches(), imu_of(sensordata[imu_idx]), True)

            return measure
        # one gather of the contact sensors' numbers, then the IMU's
        both, at_imu = np.concatenate((contacts, imu_idx)), contacts.size
        switches_of = list_switcher(tuple(plant.foot_body_ids), self.contact_threshold_N, switches)

        def measure_sensors(t_s: float, q: np.ndarray, v: np.ndarray) -> Measurement:
            values = sensordata[both]
            return Measurement(t_s, q, v, switches_of(values.tolist()), imu_of(values, at_imu), True)

        return measure_sensors


def _no_imu(packed: np.ndarray, start: int = 0) -> None:
    """The IMU reading of a plant without the IMU: none."""
    return None


def base_indices(robot) -> tuple[slice | np.ndarray, slice | np.ndarray]:
    """Pinocchio ``q`` and ``v`` indices of the base (the root joints' coordinates; slices for a free flyer)."""
    smap = robot.state_map
    if robot.is_floating:
        pq, pv = smap.joint_pin_q[robot.root_joint_names[0]], smap.joint_pin_v[robot.root_joint_names[0]]
        if not smap.free or smap.free[0][2:] != (pq, pv):  # the state reader's base row is the first free joint's
            raise InputError(f"{robot.name}: the root joint {robot.root_joint_names[0]} is not the first free joint")
        return slice(pq, pq + 7), slice(pv, pv + 6)
    return (
        np.array([smap.joint_pin_q[n] for n in robot.root_joint_names], dtype=np.intp),
        np.array([smap.joint_pin_v[n] for n in robot.root_joint_names], dtype=np.intp),
    )


def quat_mul_small_rotation(quat_xyzw: np.ndarray, rotvec: np.ndarray) -> np.ndarray:
    """Quaternion (xyzw) times the small rotation ``rotvec`` (body frame), normalised."""
    angle = float(np.linalg.norm(rotvec))
    if angle < 1e-15:
        return quat_xyzw
    axis = rotvec / angle
    s = math.sin(0.5 * angle)
    dq = np.array([axis[0] * s, axis[1] * s, axis[2] * s, math.cos(0.5 * angle)])
    x1, y1, z1, w1 = quat_xyzw
    x2, y2, z2, w2 = dq
    out = np.array(
        [
            w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
            w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2,
            w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2,
            w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2,
        ]
    )
    return out / np.linalg.norm(out)
