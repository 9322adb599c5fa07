"""Load a plant: an MJCF file made a :class:`~amlip_qp.sim.world.plant.Plant` for a controller's robot.

The file (a plant name of the robot or a path, :mod:`~amlip_qp.sim.world.plant_files`)
is read with ``mujoco.MjSpec``; a model without a ``stand`` keyframe gets one
(:mod:`~amlip_qp.sim.world.plant_start`); the caller's edits (modifiers,
terrain) are applied, then the IMU (:mod:`~amlip_qp.sim.world.imu_site`) and
the feet's contact sensors (:mod:`~amlip_qp.sim.world.contact_sensors`) are
added, and the model is compiled and mapped by name.
"""

from __future__ import annotations

import os
from collections.abc import Sequence

import mujoco

from amlip_qp.exceptions import MJCFError
from amlip_qp.robots.robot import Robot
from amlip_qp.sim.world.contact_sensors import contact_spec_edit
from amlip_qp.sim.world.imu_site import imu_spec_edit
from amlip_qp.sim.world.plant import Plant, SpecEdit
from amlip_qp.sim.world.plant_files import resolve_plant_source
from amlip_qp.sim.world.plant_start import STAND_KEYFRAME, stand_qpos


def load_plant(source: str | os.PathLike, robot: Robot, edits: Sequence[SpecEdit] = ()) -> Plant:
    """Load the plant ``source`` (a plant name of ``robot`` or an MJCF path) for ``robot``'s controller.

    The model is read with ``mujoco.MjSpec.from_file``. A model without a
    ``stand`` keyframe gets one first: the controller's stand pose mapped by
    joint name, with its loop closures closed (:func:`amlip_qp.sim.world.plant_start.stand_qpos`).
    Then every edit of ``edits`` is applied in order, then the IMU
    (:func:`amlip_qp.sim.world.imu_site.imu_spec_edit`) and the feet's contact sensors
    (:func:`amlip_qp.sim.world.contact_sensors.contact_spec_edit`), then it is compiled.

    Raises:
        InputError: An unknown plant name, or a plant without a ``stand``
            keyframe whose start pose cannot be inferred (the message says why).
        ModelFileError: The file does not exist.
        MJCFError: MuJoCo cannot load or compile it.
        PlantMismatchError: It lacks joints, actuators or bodies of the controller's model.
    """
    name, path = resolve_plant_source(source, robot)
    try:
        spec = mujoco.MjSpec.from_file(str(path))
    except Exception as exc:  # MuJoCo raises ValueError for XML errors
        raise MJCFError(f"{path}: MuJoCo cannot load the plant: {_one_line(exc)}") from exc
    if spec.key(STAND_KEYFRAME) is None:
        try:
            bare = spec.copy().compile()
        except Exception as exc:
            raise MJCFError(f"{path}: MuJoCo cannot compile the plant: {_one_line(exc)}") from exc
        spec.add_key(name=STAND_KEYFRAME, qpos=stand_qpos(Plant(bare, robot, name)).tolist())
    for edit in edits:
        edit(spec)
    mount = robot.imu_mount
    imu_body = mount.body if mount.body is not None else robot.base_body
    if spec.body(imu_body) is not None:
        imu_spec_edit(spec, imu_body, mount.pos_m, mount.quat_wxyz)
    feet = {side: Plant.body_name_of_site(robot, side) for side in robot.foot_sides}
    if all(spec.body(body) is not None for body in feet.values()):
        contact_spec_edit(spec, feet)
    try:
        model = spec.compile()
    except Exception as exc:
        raise MJCFError(f"{path}: MuJoCo cannot compile the plant: {_one_line(exc)}") from exc
    return Plant(model, robot, name)


def _one_line(exc: BaseException) -> str:
    lines = [ln.strip() for ln in str(exc).splitlines() if ln.strip()]
    return "; ".join(lines) if lines else type(exc).__name__
