"""Shared pieces of the IMU-mounting tests: profile copies with the IMU elsewhere, test IMU sites
added to a plant, and a walk's exact samples (each tick's state forwarded, with its sensors)."""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

import mujoco
import numpy as np

from amlip_qp.paths import MODELS_DIR
from amlip_qp.sim.loop.harness import TICK_OK

#: G1's file's IMU sites (``unitree_g1/g1.xml``): ``imu_in_pelvis`` and ``imu_in_torso``.
G1_PELVIS_IMU_M = (0.04525, 0.0, -0.08339)
G1_TORSO_IMU_M = (-0.03959, -0.00224, 0.14792)


def profile_copy(tmp_path: Path, robot: str, imu_lines: str, name: str | None = None) -> Path:
    """A copy of bundled ``robot``'s profile (its model file by absolute path) whose ``[imu]`` table
    holds ``imu_lines`` instead; named ``name`` (default: the robot's)."""
    text = (MODELS_DIR / f"{robot}.toml").read_text()
    start = text.index("[imu]\n")
    end = text.index("\n[", start + 1)
    text = text[:start] + "[imu]\n" + imu_lines.strip() + "\n" + text[end:]
    text = re.sub(r'= "([^"/][^"]*\.xml)"', lambda m: f'= "{MODELS_DIR / m.group(1)}"', text)  # model files
    if name is not None:
        text = text.replace(f'name = "{robot}"', f'name = "{name}"', 1)
    path = tmp_path / f"{name or robot}.toml"
    path.write_text(text)
    return path


def imu_site_edit(name: str, body: str, pos_m, quat_wxyz=(1.0, 0.0, 0.0, 0.0)):
    """A plant edit adding site ``name`` on ``body`` with a framequat, a gyro and an accelerometer
    (``{name}-quat``, ``{name}-gyro``, ``{name}-accel``)."""

    def edit(spec: mujoco.MjSpec) -> None:
        site_name = name
        if spec.site(name) is None:
            spec.body(body).add_site(name=name, pos=list(pos_m), quat=list(quat_wxyz), size=[0.01] * 3)
        kinds = (
            ("quat", mujoco.mjtSensor.mjSENS_FRAMEQUAT),
            ("gyro", mujoco.mjtSensor.mjSENS_GYRO),
            ("accel", mujoco.mjtSensor.mjSENS_ACCELEROMETER),
        )
        for suffix, kind in kinds:
            spec.add_sensor(name=f"{name}-{suffix}", type=kind, objtype=mujoco.mjtObj.mjOBJ_SITE, objname=site_name)

    return edit


@dataclass
class Sample:
    """One tick's plant state, forwarded: Pinocchio ``(q, v)``, MuJoCo ``qacc``, the contact switches,
    and the named sensors' values."""

    t_s: float
    q: np.ndarray
    v: np.ndarray
    qacc: np.ndarray
    contact: dict
    sensors: dict


def walk_samples(sim, duration_s: float, sensor_names) -> list[Sample]:
    """Walk ``sim`` for ``duration_s``; after each tick's plant steps, its state forwarded with
    ``mj_forward`` (so that every sensor describes that state), as a :class:`Sample`."""
    m = sim.model
    scratch = mujoco.MjData(m)
    ids = {n: mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_SENSOR, n) for n in sensor_names}
    assert min(ids.values()) >= 0, ids
    adr = {n: (int(m.sensor_adr[i]), int(m.sensor_dim[i])) for n, i in ids.items()}
    out: list[Sample] = []

    def on_tick(t_s, data):
        mujoco.mj_copyData(scratch, m, data)
        mujoco.mj_forward(m, scratch)
        q, v = sim.plant.read_state(scratch)
        values = {n: scratch.sensordata[a : a + d].copy() for n, (a, d) in adr.items()}
        contact = sim.sensors.exact_contact(scratch)
        out.append(Sample(float(t_s), q.copy(), v.copy(), scratch.qacc.copy(), contact, values))

    tick = sim.ticker(on_tick=on_tick)
    t = 0.0
    while t < duration_s:
        status, t, _ = tick()
        assert status == TICK_OK, f"the walk stopped at {t:.3f} s (status {status})"
    return out


def reading(sample: Sample, site: str):
    """The :class:`~amlip_qp.estimation.ImuReading` of test site ``site`` (quaternion made ``x y z w``)."""
    from amlip_qp.messages import ImuReading

    w, x, y, z = sample.sensors[f"{site}-quat"]
    return ImuReading(np.array([x, y, z, w]), sample.sensors[f"{site}-gyro"], sample.sensors[f"{site}-accel"])


def amlip_reading(sample: Sample):
    """The plant's own IMU (``amlip-imu``) in ``sample``."""
    return reading(sample, "amlip-imu")
