"""A robot's physical command bounds derived from its legs: reach, foot spread and hip-yaw range.

A command outside these bounds asks the legs for something they cannot do at
the robot's CoM height, whatever the controller: it is refused as a typo
(``[bounds]`` of a profile, :class:`~amlip_qp.profiles.CommandBounds`). The
derivation uses the model's kinematic chain and joint limits only, at the
profile's gait (CoM height ``H`` over the contact point) and step time ``T``
(the profile's ``[bounds]`` ``step_time_min_s``, the fastest stepping the
robot is run at; without it the gait's step time):

- **Reach.** The leg's contact point relative to its hip-pitch joint, for the
  knee over its whole range (a joint coupled to the knee by a fixed tendon,
  Cassie's tarsus by its achilles rod, keeps the tendon's stand length; knee
  angles that push it outside its own range are dropped) and the hip pitch
  over its whole range, every other joint at the stand pose, the base upright.
  Of these configurations, those that put the contact point at the hip's height
  above the ground at CoM height ``H`` (hip height ``h = H + z_hip - z_com`` at
  the stand pose, within :data:`HEIGHT_TOL_M`) give the farthest foothold
  ahead of the hip ``r_front`` and behind it ``r_back``.
- **Forward speed.** In one step the stance foot moves at most from
  ``r_front`` ahead of the hip to ``r_back`` behind it, so
  ``|vx| <= (r_front + r_back) / T``.
- **Lateral speed.** A lateral walk alternates a wide step ``W + vy T`` and a
  narrow one ``W - vy T``; the feet cross when the narrow one is below 0, and
  the wide one cannot exceed the widest foot spread ``d_max`` (each leg's
  contact point as far out as its hip roll and knee allow at height ``h``,
  the same sampling with the hip roll in place of the hip pitch). Some step
  width ``W`` satisfies both only while ``2 |vy| T <= d_max``:
  ``|vy| <= d_max / (2 T)``. Planar robots: 0.
- **Turn rate.** The paper's turning rule gives each hip-yaw joint half of a
  step's heading change, so a step turns at most twice the hip yaw's smaller
  excursion ``Y`` from its stand angle: ``|turn rate| <= 2 Y / T``. Planar robots: 0.

:func:`derive_command_bounds` computes them; ``tests/test_robots_reach.py``
holds every bundled profile's ``[bounds]`` to them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import mujoco
import numpy as np

from amlip_qp.exceptions import InputError

if TYPE_CHECKING:  # pragma: no cover - typing only
    from amlip_qp.robots.robot import Robot

#: Samples of the knee over its range.
KNEE_SAMPLES = 241
#: Samples of the hip pitch (or hip roll) over its range.
HIP_SAMPLES = 1441
#: A sampled contact point counts as on the ground when it is this close to the hip height below the hip, m.
HEIGHT_TOL_M = 0.005


@dataclass(frozen=True)
class DerivedBounds:
    """The physical command bounds of a robot's legs (module doc) and the numbers they come from.

    Attributes:
        vx_mps: ``(min, max)`` forward speed, m/s (``-/+ (r_front + r_back) / T``).
        vy_max_mps: Largest lateral speed, m/s (``d_max / (2 T)``; 0 for a planar robot).
        turn_rate_max_degps: Largest turn rate, deg/s (``2 Y / T``; 0 for a planar robot).
        hip_height_m: Hip-pitch joint height over the contact point at the gait's CoM height, m.
        reach_front_m: Farthest foothold ahead of the hip at that height, m.
        reach_back_m: Farthest foothold behind the hip at that height, m.
        spread_max_m: Widest lateral distance between the two contact points, m (0 when planar).
        hip_yaw_max_deg: Smaller excursion of the hip yaw from its stand angle, deg (0 when planar).
        step_time_s: The gait's step time ``T``, s.
    """

    vx_mps: tuple[float, float]
    vy_max_mps: float
    turn_rate_max_degps: float
    hip_height_m: float
    reach_front_m: float
    reach_back_m: float
    spread_max_m: float
    hip_yaw_max_deg: float
    step_time_s: float


def _joint_id(robot: Robot, name: str) -> int:
    return int(mujoco.mj_name2id(robot.mj_model, mujoco.mjtObj.mjOBJ_JOINT, name))


def _hip_pitch(robot: Robot, side: str, data: mujoco.MjData) -> int:
    """The hip-pitch joint: its role, else the leg's first hinge about the lateral (y) axis."""
    name = robot.role_joint("hip_pitch", side)
    if name is not None:
        return _joint_id(robot, name)
    for joint in robot.leg_joint_names[side]:
        jid = _joint_id(robot, joint)
        if abs(float(data.xaxis[jid][1])) > 0.99:
            return jid
    raise InputError(f"{robot.name}: no hip-pitch joint on the {side} leg (name it in [roles] hip_pitch)")


def _range(robot: Robot, jid: int) -> tuple[float, float]:
    m = robot.mj_model
    if not m.jnt_limited[jid]:
        raise InputError(f"{robot.name}: joint {m.joint(jid).name} has no range; the reach needs its limits")
    return float(m.jnt_range[jid][0]), float(m.jnt_range[jid][1])


def _knee_legs(robot: Robot, side: str) -> list[np.ndarray]:
    """The qpos of the knee samples (coupled joints following, others at the stand pose) within every range."""
    m = robot.mj_model
    knee_name = robot.role_joint("knee", side)
    if knee_name is None:
        raise InputError(f"{robot.name}: no knee joint on the {side} leg (name it in [roles] knee)")
    knee = _joint_id(robot, knee_name)
    followers = []
    for c in robot.couplings:
        if knee_name in c.joint_names and len(c.joint_names) == 2:
            i = c.joint_names.index(knee_name)
            ck, co = float(c.coefficients[i]), float(c.coefficients[1 - i])
            followers.append((_joint_id(robot, c.joint_names[1 - i]), ck, co))
    q_stand = robot.qpos_stand
    adr = m.jnt_qposadr
    out = []
    for qk in np.linspace(*_range(robot, knee), KNEE_SAMPLES):
        qpos = q_stand.copy()
        qpos[adr[knee]] = qk
        ok = True
        for jid, ck, co in followers:
            length = ck * q_stand[adr[knee]] + co * q_stand[adr[jid]]
            qj = (length - ck * qk) / co
            lo, hi = _range(robot, jid) if m.jnt_limited[jid] else (-math.inf, math.inf)
            ok = ok and lo <= qj <= hi
            qpos[adr[jid]] = qj
        if ok:
            out.append(qpos)
    return out


def _rotated(v: np.ndarray, axis: np.ndarray, angles: np.ndarray) -> np.ndarray:
    """``v`` (3,) rotated about the unit ``axis`` by each of ``angles`` (Rodrigues), shape (n, 3)."""
    c, s = np.cos(angles)[:, None], np.sin(angles)[:, None]
    return v * c + np.cross(axis, v) * s + axis * float(axis @ v) * (1.0 - c)


def _on_ground(robot: Robot, side: str, hip: int, hip_height_m: float, data: mujoco.MjData) -> np.ndarray:
    """Contact points (relative to the hip joint's anchor, world axes) with the hip ``hip`` over its range
    and the knee over its range, of those at ``hip_height_m`` below the anchor; shape (n, 3)."""
    m = robot.mj_model
    site = robot.contact_site_ids[side]
    lo, hi = _range(robot, hip)
    q0 = float(robot.qpos_stand[m.jnt_qposadr[hip]])
    angles = np.linspace(lo - q0, hi - q0, HIP_SAMPLES)
    points = []
    for qpos in _knee_legs(robot, side):
        data.qpos[:] = qpos
        mujoco.mj_kinematics(m, data)
        anchor, axis = data.xanchor[hip].copy(), data.xaxis[hip].copy()
        p = _rotated(data.site_xpos[site] - anchor, axis / np.linalg.norm(axis), angles)
        points.append(p[np.abs(-p[:, 2] - hip_height_m) <= HEIGHT_TOL_M])
    return np.concatenate(points) if points else np.zeros((0, 3))


def derive_command_bounds(robot: Robot) -> DerivedBounds:
    """The physical command bounds of ``robot``'s legs at its profile's gait (module doc).

    Raises:
        InputError: The robot has no profile, a leg joint the derivation needs
            (knee, hip pitch; hip roll and hip yaw unless planar) or its range, or
            no configuration reaches the ground at the gait's CoM height.
    """
    if robot.profile is None:
        raise InputError(f"{robot.name}: the bounds are derived at the gait of a robot profile; load it by profile")
    gait = robot.profile.gait
    T = robot.profile.bounds.step_time_min_s or gait.step_time_s
    m = robot.mj_model
    data = mujoco.MjData(m)
    data.qpos[:] = robot.qpos_stand
    mujoco.mj_kinematics(m, data)
    mujoco.mj_comPos(m, data)
    com_z = float(data.subtree_com[0][2])
    base = int(mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, robot.base_body))
    base_y = float(data.xpos[base][1])
    side = robot.foot_sides[0]
    hip = _hip_pitch(robot, side, data)
    hip_height = gait.com_height_m + float(data.xanchor[hip][2]) - com_z
    ahead = _on_ground(robot, side, hip, hip_height, data)
    if len(ahead) == 0:
        raise InputError(f"{robot.name}: no leg configuration reaches the ground {hip_height:.3f} m below the hip")
    r_front, r_back = float(np.max(ahead[:, 0])), float(-np.min(ahead[:, 0]))
    vx = (r_front + r_back) / T
    spread, yaw_deg, vy, turn = 0.0, 0.0, 0.0, 0.0
    if not robot.is_planar:
        for s in robot.foot_sides:
            roll_name = robot.role_joint("hip_roll", s)
            if roll_name is None:
                raise InputError(f"{robot.name}: no hip-roll joint on the {s} leg (name it in [roles] hip_roll)")
            roll = _joint_id(robot, roll_name)
            data.qpos[:] = robot.qpos_stand
            mujoco.mj_kinematics(m, data)
            anchor_y = float(data.xanchor[roll][1])
            drop = hip_height + float(data.xanchor[roll][2] - data.xanchor[hip][2])  # below the roll joint
            side_pts = _on_ground(robot, s, roll, drop, data)
            outward = 1.0 if anchor_y > base_y else -1.0
            spread += float(np.max(outward * (side_pts[:, 1] + anchor_y - base_y)))
        yaw_name = robot.role_joint("hip_yaw", side)
        if yaw_name is None:
            raise InputError(f"{robot.name}: no hip-yaw joint on the {side} leg (name it in [roles] hip_yaw)")
        yaw = _joint_id(robot, yaw_name)
        lo, hi = _range(robot, yaw)
        q0 = float(robot.qpos_stand[m.jnt_qposadr[yaw]])
        yaw_deg = math.degrees(min(hi - q0, q0 - lo))
        vy = spread / (2.0 * T)
        turn = 2.0 * yaw_deg / T
    return DerivedBounds(
        vx_mps=(-vx, vx),
        vy_max_mps=vy,
        turn_rate_max_degps=turn,
        hip_height_m=hip_height,
        reach_front_m=r_front,
        reach_back_m=r_back,
        spread_max_m=spread,
        hip_yaw_max_deg=yaw_deg,
        step_time_s=T,
    )
