"""The IMU added to every plant: a site where the robot's profile puts it, with three MuJoCo sensors.

The site ``amlip-imu`` sits where the robot's profile puts the IMU
(:attr:`~amlip_qp.robots.robot.Robot.imu_mount`: any body, a position and axes
in its frame; by default the base body's origin and axes), with MuJoCo sensors
``amlip-imu-quat`` (framequat), ``amlip-imu-gyro`` and ``amlip-imu-accel``, in
the site's own axes; :func:`imu_spec_edit` adds them to a plant's model
(:func:`~amlip_qp.sim.world.plant_loader.load_plant` does, for every plant). The
readings are :mod:`amlip_qp.sim.sensing.sensors`'s.
"""

from __future__ import annotations

from collections.abc import Callable

import mujoco

from amlip_qp.exceptions import InputError
from amlip_qp.profiles import ImuMount

IMU_SITE = "amlip-imu"
IMU_QUAT_SENSOR = "amlip-imu-quat"
IMU_GYRO_SENSOR = "amlip-imu-gyro"
IMU_ACCEL_SENSOR = "amlip-imu-accel"


def imu_spec_edit(spec: mujoco.MjSpec, body: str, pos_m, quat_wxyz=(1.0, 0.0, 0.0, 0.0)) -> None:
    """Add the IMU site on ``body`` at ``pos_m`` with axes ``quat_wxyz`` (both in ``body``'s frame)
    and its three sensors, which report in the site's axes.

    Nothing is added that the model already has (a site or sensor of the same name).
    """
    if spec.site(IMU_SITE) is None:
        spec.body(body).add_site(
            name=IMU_SITE, pos=[float(x) for x in pos_m], quat=[float(x) for x in quat_wxyz], size=[0.01, 0.01, 0.01]
        )
    kinds = (
        (IMU_QUAT_SENSOR, mujoco.mjtSensor.mjSENS_FRAMEQUAT),
        (IMU_GYRO_SENSOR, mujoco.mjtSensor.mjSENS_GYRO),
        (IMU_ACCEL_SENSOR, mujoco.mjtSensor.mjSENS_ACCELEROMETER),
    )
    for name, kind in kinds:
        if spec.sensor(name) is None:
            spec.add_sensor(name=name, type=kind, objtype=mujoco.mjtObj.mjOBJ_SITE, objname=IMU_SITE)


def imu_mount_edit(mount: ImuMount, base_body: str) -> Callable[[mujoco.MjSpec], None]:
    """A plant edit: :func:`imu_spec_edit` where ``mount`` puts the IMU (``mount.body`` ``None``: ``base_body``).

    The edit raises :class:`InputError` for a plant without that body.
    """
    body = base_body if mount.body is None else mount.body

    def edit(spec: mujoco.MjSpec) -> None:
        if spec.body(body) is None:
            raise InputError(f"the plant has no body {body!r} for the IMU")
        imu_spec_edit(spec, body, mount.pos_m, mount.quat_wxyz)

    return edit
