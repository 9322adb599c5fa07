"""A profile's edits of its MJCF file, made through ``MjSpec`` when the robot is loaded.

A robot's MJCF file is used as it comes (a MuJoCo Menagerie folder, say); its
profile (:class:`~amlip_qp.profiles.ModelSpec`, :class:`~amlip_qp.profiles.FootSpec`)
says what the library adds or changes:

- a name for the free joint, if the file leaves it unnamed;
- the timestep;
- a ground plane, if the model has none;
- a ``stand`` keyframe (replacing the file's), from the base pose and the joint angles by name;
- the library's foot sites on the foot bodies: ``{side}-contact`` (the ALIP contact point) and,
  for a two-point foot, ``{side}-toe`` / ``{side}-heel`` (where the contact forces act); for a
  four-point foot its corners ``{side}-toe-left``, ``{side}-toe-right``, ``{side}-heel-left``,
  ``{side}-heel-right`` (where the forces act) and its sole line's ends ``{side}-toe`` /
  ``{side}-heel`` (the midpoints of the toe pair and of the heel pair: the swing foot's pitch);
- position servos turned into torque motors (``servos = "convert"``): gain 1, no bias, the
  control range the joint's force range, so a control is a torque; or refused.

The edited model is written once into the cache (``<cache>/models/``, :func:`amlip_qp.paths.cache_root`),
named by a hash of the source file, the edits and MuJoCo's version, and both MuJoCo and
Pinocchio read that file (:func:`prepared_model_path`). A profile without edits loads its file
as it is, so its models are exactly the file's.
"""

from __future__ import annotations

import hashlib
import os
import tempfile
from pathlib import Path

import mujoco
import numpy as np

from amlip_qp.exceptions import MJCFError
from amlip_qp.paths import cache_root
from amlip_qp.profiles import FORCE_SITE_SUFFIXES, FootSpec, ModelSpec, RobotProfile, sole_line_points

#: The foot sides.
_SIDES = ("left", "right")

#: The ground plane a profile's ``add_floor`` adds: MuJoCo's default contact, friction 1.
FLOOR_GEOM = "floor"


def _one_line(exc: BaseException) -> str:
    lines = [ln.strip() for ln in str(exc).splitlines() if ln.strip()]
    return "; ".join(lines) if lines else type(exc).__name__


def is_servo(actuator) -> bool:
    """Whether an ``MjsActuator`` (or its compiled gain/bias types) is a position or velocity servo,
    not a torque motor: a bias that depends on the joint, or a gain other than a fixed one."""
    return actuator.biastype != mujoco.mjtBias.mjBIAS_NONE or actuator.gaintype != mujoco.mjtGain.mjGAIN_FIXED


def _joint_force_range(spec: mujoco.MjSpec, actuator, path: Path) -> tuple[float, float]:
    """The force range a converted servo gets: its own ``forcerange``, else its joint's ``actuatorfrcrange``."""
    limited = mujoco.mjtLimited.mjLIMITED_TRUE, mujoco.mjtLimited.mjLIMITED_AUTO
    lo, hi = (float(x) for x in actuator.forcerange)
    if actuator.forcelimited in limited and hi > lo:
        return lo, hi
    joint = spec.joint(actuator.target)
    if joint is not None:
        lo, hi = (float(x) for x in joint.actfrcrange)
        if joint.actfrclimited in limited and hi > lo:
            return lo, hi
    raise MJCFError(
        f"{path}: position servo {actuator.name!r} has no force range (forcerange, or its joint's "
        "actuatorfrcrange): the torque motor it would become needs one; add it to the MJCF"
    )


def convert_servos(spec: mujoco.MjSpec, policy: str, path: Path) -> list[str]:
    """Turn every position or velocity servo of ``spec`` into a torque motor, or refuse (``policy``).

    A converted actuator has gain 1 and no bias (force = control), its gear is kept, and its
    control range is its force range divided by the gear (joint torque = gear * control stays
    within the joint's force range). Returns the converted actuators' names.

    Raises:
        MJCFError: ``policy`` is ``"refuse"`` and the model has a servo, or a servo has no force range.
    """
    servos = [a for a in spec.actuators if is_servo(a)]
    if servos and policy != "convert":
        a = servos[0]
        raise MJCFError(
            f"{path}: actuator {a.name!r} (and {len(servos) - 1} more) is a position servo (kp = {a.gainprm[0]:g}): "
            'the controller sends joint torques; set servos = "convert" in the profile\'s [model] table to '
            "turn servos into torque motors over their force ranges"
        )
    for a in servos:
        lo, hi = _joint_force_range(spec, a, path)
        gear = float(a.gear[0]) or 1.0
        a.set_to_motor()
        a.gaintype, a.biastype = mujoco.mjtGain.mjGAIN_FIXED, mujoco.mjtBias.mjBIAS_NONE
        a.gainprm = np.r_[1.0, np.zeros(len(a.gainprm) - 1)]
        a.biasprm = np.zeros(len(a.biasprm))
        a.inheritrange = 0.0
        a.ctrlrange = sorted((lo / gear, hi / gear))
        a.ctrllimited = mujoco.mjtLimited.mjLIMITED_TRUE
    return [a.name for a in servos]


def _add_floor(spec: mujoco.MjSpec) -> None:
    if any(g.type == mujoco.mjtGeom.mjGEOM_PLANE for g in spec.worldbody.geoms):
        return
    spec.worldbody.add_geom(
        name=FLOOR_GEOM, type=mujoco.mjtGeom.mjGEOM_PLANE, size=[0.0, 0.0, 0.05], friction=[1.0, 0.005, 0.0001]
    )


def _name_free_joint(spec: mujoco.MjSpec, name: str) -> None:
    for joint in spec.joints:
        if joint.type == mujoco.mjtJoint.mjJNT_FREE and not joint.name:
            joint.name = name


def _add_foot_sites(spec: mujoco.MjSpec, feet: FootSpec, path: Path) -> None:
    if feet.body is None:
        return
    for side in _SIDES:
        body = spec.body(feet.body.format(side=side))
        if body is None:
            raise MJCFError(f"{path}: the profile's foot body {feet.body.format(side=side)!r} is not in the model")
        body.add_site(name=f"{side}-contact", pos=list(feet.contact_point_m or (0.0, 0.0, 0.0)))
        points = feet.force_points_m
        if len(points) == 4:
            for suffix, point in zip(FORCE_SITE_SUFFIXES[4], points):
                body.add_site(name=f"{side}-{suffix}", pos=list(point))
        if len(points) in (2, 4):
            toe, heel = sole_line_points(points)
            body.add_site(name=f"{side}-toe", pos=list(toe))
            body.add_site(name=f"{side}-heel", pos=list(heel))


def _add_stand_key(spec: mujoco.MjSpec, model: ModelSpec, path: Path) -> None:
    stand = model.stand
    if stand is None:
        return
    compiled = spec.compile()
    qpos = compiled.qpos0.copy()
    free = [j for j in range(compiled.njnt) if int(compiled.jnt_type[j]) == int(mujoco.mjtJoint.mjJNT_FREE)]
    if free:
        adr = int(compiled.jnt_qposadr[free[0]])
        qpos[adr : adr + 3] = stand.base_pos_m
        qpos[adr + 3 : adr + 7] = stand.base_quat_wxyz
    for name, value in stand.joints_rad.items():
        j = mujoco.mj_name2id(compiled, mujoco.mjtObj.mjOBJ_JOINT, name)
        if j < 0 or int(compiled.jnt_type[j]) not in (
            int(mujoco.mjtJoint.mjJNT_HINGE),
            int(mujoco.mjtJoint.mjJNT_SLIDE),
        ):
            raise MJCFError(f"{path}: the profile's stand pose names {name!r}, which is no hinge or slide joint of it")
        qpos[int(compiled.jnt_qposadr[j])] = value
    for key in list(spec.keys):
        if key.name == "stand":
            spec.delete(key)
    spec.add_key(name="stand", qpos=qpos.tolist(), ctrl=np.zeros(compiled.nu).tolist())


def edit_spec(spec: mujoco.MjSpec, profile: RobotProfile) -> None:
    """Apply ``profile``'s edits to ``spec`` in place (see the module doc).

    Raises:
        MJCFError: The profile names a body or joint the model lacks, or a servo cannot be converted.
    """
    model, path = profile.model, profile.model.path
    if model.free_joint_name is not None:
        _name_free_joint(spec, model.free_joint_name)
    if model.timestep_s is not None:
        spec.option.timestep = model.timestep_s
    if model.add_floor:
        _add_floor(spec)
    convert_servos(spec, model.servos, path)
    _add_foot_sites(spec, profile.feet, path)
    _add_stand_key(spec, model, path)


def prepared_model_path(profile: RobotProfile) -> Path:
    """The MJCF file MuJoCo and Pinocchio read for ``profile``'s robot.

    The profile's own file when it has no edits; otherwise the edited copy in the cache, written
    the first time (atomically) and reused while the source file, the edits and MuJoCo's version
    stay the same.

    Raises:
        MJCFError: MuJoCo cannot read or compile the file or the edited model, or an edit fails.
    """
    model = profile.model
    if not model.edits_needed and profile.feet.body is None:
        return model.path
    source = model.path.read_bytes()
    key = hashlib.sha256(source + repr((model, profile.feet)).encode() + mujoco.__version__.encode()).hexdigest()[:16]
    folder = cache_root() / "models"
    target = folder / f"{profile.name}-{key}.xml"
    if target.is_file():
        return target
    try:
        spec = mujoco.MjSpec.from_file(str(model.path))
    except Exception as exc:
        raise MJCFError(f"{model.path}: MuJoCo cannot load the model: {_one_line(exc)}") from exc
    base = model.path.parent
    spec.meshdir = str((base / spec.meshdir).resolve()) if spec.meshdir else str(base)
    spec.texturedir = str((base / spec.texturedir).resolve()) if spec.texturedir else str(base)
    edit_spec(spec, profile)
    try:
        spec.compile()
        xml = spec.to_xml()
    except Exception as exc:
        raise MJCFError(
            f"{model.path}: the profile's edits give a model MuJoCo cannot compile: {_one_line(exc)}"
        ) from exc
    try:
        folder.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=folder, suffix=".xml.tmp")
        with os.fdopen(fd, "w", encoding="utf-8") as f:
            f.write(xml)
        os.replace(tmp, target)
    except OSError as exc:
        raise MJCFError(
            f"cannot write the edited model into {folder}: {exc.strerror or exc}; "
            "set $AMLIP_QP_CACHE_DIR to a writable folder"
        ) from None
    return target
