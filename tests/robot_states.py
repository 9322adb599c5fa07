"""Shared test helpers: the robots under test and random MuJoCo states (not a test module)."""

import mujoco
import numpy as np

#: Every bundled robot; the robots/ tests run on each.
ROBOTS = ["rabbit", "cassie"]


def random_mj_state(robot, rng):
    """Random MuJoCo state: joints within range, random base pose and velocities."""
    m = robot.mj_model
    qpos = m.qpos0.copy()
    for j in range(m.njnt):
        qa, jt = m.jnt_qposadr[j], m.jnt_type[j]
        if jt == mujoco.mjtJoint.mjJNT_FREE:
            qpos[qa : qa + 3] = rng.uniform(-1, 1, 3)
            quat = rng.normal(size=4)
            qpos[qa + 3 : qa + 7] = quat / np.linalg.norm(quat)
        elif m.jnt_limited[j]:
            qpos[qa] = rng.uniform(*m.jnt_range[j])
        else:
            qpos[qa] = rng.uniform(-1, 1)
    return qpos, rng.normal(size=m.nv)
