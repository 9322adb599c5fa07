"""Variants of cassie.xml built with ``mujoco.MjSpec``: plants that differ from the controller's model."""

from __future__ import annotations

import mujoco
import numpy as np

from amlip_qp.paths import MODELS_DIR

CASSIE_XML = MODELS_DIR / "cassie.xml"


def write_plant(spec: mujoco.MjSpec, path, insert: tuple[str, str] = ("", "")) -> str:
    """Compile ``spec`` and write its MJCF to ``path``, with ``insert[1]`` put before ``insert[0]``."""
    spec.compile()
    text = spec.to_xml()
    if insert[0]:
        text = text.replace(insert[0], insert[1] + insert[0])
    path.write_text(text)
    return str(path)


def slide_ball_spec() -> mujoco.MjSpec:
    """cassie.xml with the pelvis floated by slide x, y, z and a ball joint (as Agility's own model)."""
    spec = mujoco.MjSpec.from_file(str(CASSIE_XML))
    pelvis = spec.body("cassie-pelvis")
    spec.delete(spec.joint("floating-base"))
    # joints of one body are added in order; MuJoCo wants them before the child bodies' (any order works)
    for name, axis in (("base-x", [1, 0, 0]), ("base-y", [0, 1, 0]), ("base-z", [0, 0, 1])):
        pelvis.add_joint(name=name, type=mujoco.mjtJoint.mjJNT_SLIDE, axis=axis)
    pelvis.add_joint(name="base-rot", type=mujoco.mjtJoint.mjJNT_BALL)
    key = spec.key("stand")
    qpos = np.asarray(key.qpos)
    # free joint (x, y, z, quat) -> slides relative to the body's position, then the ball's quaternion
    pos0 = np.asarray(pelvis.pos)
    key.qpos = np.concatenate([qpos[:3] - pos0, qpos[3:7], qpos[7:]]).tolist()
    return spec


def extra_joint_spec() -> mujoco.MjSpec:
    """cassie.xml with a passive hinge between the left foot and a new toe-tip body."""
    spec = mujoco.MjSpec.from_file(str(CASSIE_XML))
    foot = spec.body("left-foot")
    tip = foot.add_body(name="left-toe-tip", pos=[0.05, 0.0, 0.0], mass=0.01, inertia=[1e-6, 1e-6, 1e-6])
    tip.add_joint(name="left-toe-flex", type=mujoco.mjtJoint.mjJNT_HINGE, axis=[0, 0, 1], stiffness=10.0)
    key = spec.key("stand")
    qpos = list(key.qpos)
    m0 = mujoco.MjModel.from_xml_path(str(CASSIE_XML))
    foot_end = int(m0.jnt_qposadr[mujoco.mj_name2id(m0, mujoco.mjtObj.mjOBJ_JOINT, "left-foot")]) + 1
    key.qpos = qpos[:foot_end] + [0.0] + qpos[foot_end:]
    return spec
