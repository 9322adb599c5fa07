"""MuJoCo (qpos, qvel) <-> Pinocchio (q, v): the ONE place that converts states.

Conventions handled here:

- Joint order: the two models may order joints differently; index maps are
  built by joint (and body) name, never assumed.
- Free joint: MuJoCo ``qpos = (p_world, quat_wxyz)``,
  ``qvel = (v_world, w_body)``; Pinocchio ``q = (p_world, quat_xyzw)``,
  ``v = (v_body, w_body)`` with ``v_body = R^T v_world``.
- Ball joints: quaternion order as above; angular velocity in the child
  frame in both.
- Hinge and slide joints: identical coordinates (Pinocchio applies MJCF's
  ``ref`` the way MuJoCo does). Several joints on one MuJoCo body become one
  Pinocchio composite joint (Rabbit's planar root); its components follow
  the MuJoCo joint order of that body.

The velocity map ``T(q)`` with ``qvel = T v`` (:func:`velocity_map`) gives
the other conversions: generalized forces ``f_pin = T^T f_mj``, mass
matrices ``M_pin = T^T M_mj T`` and, for bias forces,
``h_pin = T^T (b_mj + M_mj Tdot v)`` (:func:`bias_mj_to_pin`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from amlip_qp.exceptions import InputError, MJCFError

_FREE, _BALL, _SLIDE, _HINGE = 0, 1, 2, 3  # mujoco.mjtJoint values


@dataclass(frozen=True)
class StateMap:
    """Index maps between MuJoCo's and Pinocchio's coordinates.

    Attributes:
        nq_mj: MuJoCo nq.
        nq_pin: Pinocchio nq.
        nv: Number of velocity coordinates (equal in both).
        scalar_mj_q: MuJoCo qpos indices of all hinge/slide joints.
        scalar_pin_q: Matching Pinocchio q indices.
        scalar_mj_v: MuJoCo dof indices of all hinge/slide joints.
        scalar_pin_v: Matching Pinocchio v indices.
        free: ``(mj_qpos_adr, mj_dof_adr, pin_q_idx, pin_v_idx)`` per free joint.
        ball: The same for ball joints.
        joint_pin_q: MuJoCo joint name -> Pinocchio q index (first coordinate).
        joint_pin_v: MuJoCo joint name -> Pinocchio v index (first coordinate).
    """

    nq_mj: int
    nq_pin: int
    nv: int
    scalar_mj_q: np.ndarray
    scalar_pin_q: np.ndarray
    scalar_mj_v: np.ndarray
    scalar_pin_v: np.ndarray
    free: tuple[tuple[int, int, int, int], ...]
    ball: tuple[tuple[int, int, int, int], ...]
    joint_pin_q: dict[str, int]
    joint_pin_v: dict[str, int]


def build_state_map(mj_model, pin_model, source: str = "model") -> StateMap:
    """Match every MuJoCo joint to its Pinocchio coordinates, by body and joint name.

    Args:
        mj_model: Compiled ``mujoco.MjModel``.
        pin_model: ``pinocchio.Model`` built from the same MJCF file.
        source: Name used in error messages (the file path).

    Raises:
        MJCFError: If the two models do not have the same joints.
    """
    import mujoco
    import pinocchio as pin

    if mj_model.nv != pin_model.nv:
        raise MJCFError(
            f"{source}: Pinocchio built nv={pin_model.nv} but MuJoCo nv={mj_model.nv}; "
            "Pinocchio's MJCF parser reads only the first body tree under <worldbody>, "
            "so put the whole robot under one root body"
        )
    # MuJoCo joints grouped by body, in MuJoCo order.
    by_body: dict[int, list[int]] = {}
    for j in range(mj_model.njnt):
        by_body.setdefault(int(mj_model.jnt_bodyid[j]), []).append(j)

    nq_of = {_FREE: 7, _BALL: 4, _SLIDE: 1, _HINGE: 1}
    nv_of = {_FREE: 6, _BALL: 3, _SLIDE: 1, _HINGE: 1}
    sq_mj, sq_pin, sv_mj, sv_pin = [], [], [], []
    free, ball = [], []
    joint_pin_q: dict[str, int] = {}
    joint_pin_v: dict[str, int] = {}
    for body_id, joints in by_body.items():
        body_name = mujoco.mj_id2name(mj_model, mujoco.mjtObj.mjOBJ_BODY, body_id)
        if body_name is None or not pin_model.existFrame(body_name, pin.BODY):
            raise MJCFError(
                f"{source}: body {body_name or body_id} (with joints) has no Pinocchio "
                "frame; give every body with joints a unique name"
            )
        pin_joint = pin_model.frames[pin_model.getFrameId(body_name, pin.BODY)].parentJoint
        jm = pin_model.joints[pin_joint]
        need_q = sum(nq_of[int(mj_model.jnt_type[j])] for j in joints)
        need_v = sum(nv_of[int(mj_model.jnt_type[j])] for j in joints)
        if jm.nq != need_q or jm.nv != need_v:
            raise MJCFError(
                f"{source}: body {body_name}: Pinocchio joint {pin_model.names[pin_joint]} has "
                f"nq={jm.nq}, nv={jm.nv} but MuJoCo's joints need nq={need_q}, nv={need_v}"
            )
        oq, ov = jm.idx_q, jm.idx_v
        for j in joints:
            jtype = int(mj_model.jnt_type[j])
            name = mujoco.mj_id2name(mj_model, mujoco.mjtObj.mjOBJ_JOINT, j) or f"joint{j}"
            qa, da = int(mj_model.jnt_qposadr[j]), int(mj_model.jnt_dofadr[j])
            joint_pin_q[name], joint_pin_v[name] = oq, ov
            if jtype in (_SLIDE, _HINGE):
                sq_mj.append(qa)
                sq_pin.append(oq)
                sv_mj.append(da)
                sv_pin.append(ov)
            elif jtype == _FREE:
                if len(joints) != 1:
                    raise MJCFError(f"{source}: body {body_name}: a free joint must be alone")
                free.append((qa, da, oq, ov))
            else:
                if len(joints) != 1:
                    raise MJCFError(f"{source}: body {body_name}: a ball joint must be alone")
                ball.append((qa, da, oq, ov))
            oq += nq_of[jtype]
            ov += nv_of[jtype]
    as_idx = lambda x: np.asarray(x, dtype=np.intp)  # noqa: E731
    return StateMap(
        nq_mj=int(mj_model.nq),
        nq_pin=int(pin_model.nq),
        nv=int(mj_model.nv),
        scalar_mj_q=as_idx(sq_mj),
        scalar_pin_q=as_idx(sq_pin),
        scalar_mj_v=as_idx(sv_mj),
        scalar_pin_v=as_idx(sv_pin),
        free=tuple(free),
        ball=tuple(ball),
        joint_pin_q=joint_pin_q,
        joint_pin_v=joint_pin_v,
    )


class HasStateMap(Protocol):
    """Anything with a :class:`StateMap`, e.g. a :class:`~amlip_qp.robots.robot.Robot`."""

    @property
    def state_map(self) -> StateMap: ...


def _smap(robot_or_map: HasStateMap | StateMap) -> StateMap:
    return robot_or_map if isinstance(robot_or_map, StateMap) else robot_or_map.state_map


def _check(x, n: int, what: str) -> np.ndarray:
    arr = np.asarray(x, dtype=float)
    if arr.shape != (n,):
        raise InputError(f"{what} must have shape ({n},), got {arr.shape}")
    # Cheap test first (called every tick): a finite sum implies finite entries.
    if not math.isfinite(sum(arr.tolist())) and not np.isfinite(arr).all():
        raise InputError(f"{what} contains NaN or inf at indices {np.flatnonzero(~np.isfinite(arr)).tolist()}")
    return arr


#: A quaternion whose norm is below this is a zero quaternion (refused); every state read uses it.
ZERO_QUATERNION_NORM = 1e-9


def _norm(x: np.ndarray) -> float:
    """Euclidean norm of a 1-D array, ``sqrt(x0 x0 + x1 x1 + ...)`` summed left to right.

    Written out rather than ``x.dot(x)``: NumPy's dot goes to its BLAS, whose kernel (and so
    its summation order and fused multiply-adds) depends on the CPU, and the per-tick
    :class:`~amlip_qp.robots.state_reader.StateReader` must give the same numbers on any machine.
    """
    total = 0.0  # not sum(): from Python 3.12 it sums floats with compensation
    for t in x.tolist():
        total += t * t
    return math.sqrt(total)


def _transposed_times(R: np.ndarray, u: np.ndarray) -> list[float]:
    """``R^T u`` of a 3x3 ``R`` and a 3-vector, each entry summed left to right (no BLAS: see :func:`_norm`)."""
    (r00, r01, r02), (r10, r11, r12), (r20, r21, r22) = R.tolist()
    l0, l1, l2 = u.tolist()
    return [r00 * l0 + r10 * l1 + r20 * l2, r01 * l0 + r11 * l1 + r21 * l2, r02 * l0 + r12 * l1 + r22 * l2]


def rotation_entries(w: float, x: float, y: float, z: float) -> tuple[float, ...]:
    """The rotation matrix of the unit quaternion ``(w, x, y, z)``, row by row (9 floats).

    The one formula of the quaternion's rotation: :func:`_quat_wxyz_to_rot`, the per-tick
    :class:`~amlip_qp.robots.state_reader.StateReader` (its one-free-joint path has it written
    out, the same operations) and the harness's generated C (:mod:`amlip_qp.sim.world.compiled_io`,
    on CasADi symbols) use it; tested bit for bit.
    """
    return (
        1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y),
        2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x),
        2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y),
    )  # fmt: skip


def _quat_wxyz_to_rot(qw: np.ndarray) -> np.ndarray:
    """Rotation matrix of a (normalized here) quaternion in w, x, y, z order."""
    e = rotation_entries(*(qw / _norm(qw)).tolist())
    return np.array([e[0:3], e[3:6], e[6:9]])


def _normalized(quat: np.ndarray, what: str) -> np.ndarray:
    n = _norm(quat)
    if n < ZERO_QUATERNION_NORM:
        raise InputError(f"{what}: zero quaternion")
    return quat / n


def qpos_to_q(robot: HasStateMap | StateMap, qpos) -> np.ndarray:
    """MuJoCo ``qpos`` -> Pinocchio ``q`` (quaternions normalized, reordered to xyzw)."""
    m = _smap(robot)
    qpos = _check(qpos, m.nq_mj, "qpos")
    q = np.zeros(m.nq_pin)
    q[m.scalar_pin_q] = qpos[m.scalar_mj_q]
    for qa, _, pq, _ in m.free:
        q[pq : pq + 3] = qpos[qa : qa + 3]
        wxyz = _normalized(qpos[qa + 3 : qa + 7], "qpos free-joint quaternion")
        q[pq + 3 : pq + 6], q[pq + 6] = wxyz[1:], wxyz[0]  # xyzw
    for qa, _, pq, _ in m.ball:
        wxyz = _normalized(qpos[qa : qa + 4], "qpos ball-joint quaternion")
        q[pq : pq + 3], q[pq + 3] = wxyz[1:], wxyz[0]
    return q


def q_to_qpos(robot: HasStateMap | StateMap, q) -> np.ndarray:
    """Pinocchio ``q`` -> MuJoCo ``qpos`` (quaternions normalized, reordered to wxyz)."""
    m = _smap(robot)
    q = _check(q, m.nq_pin, "q")
    qpos = np.zeros(m.nq_mj)
    qpos[m.scalar_mj_q] = q[m.scalar_pin_q]
    for qa, _, pq, _ in m.free:
        qpos[qa : qa + 3] = q[pq : pq + 3]
        xyzw = _normalized(q[pq + 3 : pq + 7], "q free-flyer quaternion")
        qpos[qa + 3], qpos[qa + 4 : qa + 7] = xyzw[3], xyzw[:3]  # wxyz
    for qa, _, pq, _ in m.ball:
        xyzw = _normalized(q[pq : pq + 4], "q spherical-joint quaternion")
        qpos[qa], qpos[qa + 1 : qa + 4] = xyzw[3], xyzw[:3]
    return qpos


def velocity_map(robot: HasStateMap | StateMap, q) -> np.ndarray:
    """The matrix ``T(q)`` (nv x nv) with MuJoCo ``qvel = T @ v`` (Pinocchio ``v``).

    It is a permutation except for each free joint's linear block, which is
    the base rotation ``R`` (body -> world).
    """
    m = _smap(robot)
    q = _check(q, m.nq_pin, "q")
    T = np.zeros((m.nv, m.nv))
    T[m.scalar_mj_v, m.scalar_pin_v] = 1.0
    for _, da, pq, pv in m.free:
        T[da : da + 3, pv : pv + 3] = _quat_wxyz_to_rot(_wxyz(q[pq + 3 : pq + 7]))
        T[da + 3 : da + 6, pv + 3 : pv + 6] = np.eye(3)
    for _, da, _, pv in m.ball:
        T[da : da + 3, pv : pv + 3] = np.eye(3)
    return T


def velocity_map_dot_v(robot: HasStateMap | StateMap, q, v) -> np.ndarray:
    """``Tdot(q, v) @ v`` in MuJoCo dof order: the world-frame base-velocity drift.

    For each free joint: ``d/dt(R) v_body = R (w_body x v_body)``; zero elsewhere.
    """
    m = _smap(robot)
    q = _check(q, m.nq_pin, "q")
    v = _check(v, m.nv, "v")
    out = np.zeros(m.nv)
    for _, da, pq, pv in m.free:
        R = _quat_wxyz_to_rot(_wxyz(q[pq + 3 : pq + 7]))
        out[da : da + 3] = R @ np.cross(v[pv + 3 : pv + 6], v[pv : pv + 3])
    return out


def qvel_to_v(robot: HasStateMap | StateMap, q, qvel) -> np.ndarray:
    """MuJoCo ``qvel`` -> Pinocchio ``v`` at Pinocchio configuration ``q``."""
    m = _smap(robot)
    return _qvel_to_v(m, _check(q, m.nq_pin, "q"), _check(qvel, m.nv, "qvel"))


def _wxyz(xyzw: np.ndarray) -> np.ndarray:
    """A Pinocchio ``xyzw`` quaternion reordered to ``wxyz`` (new array)."""
    wxyz = np.empty(4)
    wxyz[0], wxyz[1:] = xyzw[3], xyzw[:3]
    return wxyz


def _qvel_to_v(m: StateMap, q: np.ndarray, qvel: np.ndarray) -> np.ndarray:
    """:func:`qvel_to_v` on checked float arrays."""
    v = np.zeros(m.nv)
    v[m.scalar_pin_v] = qvel[m.scalar_mj_v]
    for _, da, pq, pv in m.free:
        R = _quat_wxyz_to_rot(_wxyz(q[pq + 3 : pq + 7]))
        v[pv : pv + 3] = _transposed_times(R, qvel[da : da + 3])
        v[pv + 3 : pv + 6] = qvel[da + 3 : da + 6]
    for _, da, _, pv in m.ball:
        v[pv : pv + 3] = qvel[da : da + 3]
    return v


def v_to_qvel(robot: HasStateMap | StateMap, q, v) -> np.ndarray:
    """Pinocchio ``v`` -> MuJoCo ``qvel`` at Pinocchio configuration ``q``."""
    m = _smap(robot)
    q = _check(q, m.nq_pin, "q")
    v = _check(v, m.nv, "v")
    qvel = np.zeros(m.nv)
    qvel[m.scalar_mj_v] = v[m.scalar_pin_v]
    for _, da, pq, pv in m.free:
        R = _quat_wxyz_to_rot(_wxyz(q[pq + 3 : pq + 7]))
        qvel[da : da + 3] = R @ v[pv : pv + 3]
        qvel[da + 3 : da + 6] = v[pv + 3 : pv + 6]
    for _, da, _, pv in m.ball:
        qvel[da : da + 3] = v[pv : pv + 3]
    return qvel


def mj_to_pin(robot: HasStateMap | StateMap, qpos, qvel) -> tuple[np.ndarray, np.ndarray]:
    """MuJoCo ``(qpos, qvel)`` -> Pinocchio ``(q, v)``.

    Args:
        robot: A :class:`~amlip_qp.robots.Robot` (or its ``state_map``).
        qpos: MuJoCo positions, shape (nq_mj,).
        qvel: MuJoCo velocities, shape (nv,).

    Raises:
        InputError: Wrong shape, NaN/inf, or a zero quaternion.
    """
    m = _smap(robot)
    q = qpos_to_q(m, qpos)  # checked; its output is finite with unit quaternions
    return q, _qvel_to_v(m, q, _check(qvel, m.nv, "qvel"))


def pin_to_mj(robot: HasStateMap | StateMap, q, v) -> tuple[np.ndarray, np.ndarray]:
    """Pinocchio ``(q, v)`` -> MuJoCo ``(qpos, qvel)`` (inverse of :func:`mj_to_pin`).

    Raises:
        InputError: Wrong shape, NaN/inf, or a zero quaternion.
    """
    return q_to_qpos(robot, q), v_to_qvel(robot, q, v)


def force_mj_to_pin(robot: HasStateMap | StateMap, q, f_mj) -> np.ndarray:
    """Generalized force in MuJoCo dof coordinates -> Pinocchio's: ``f_pin = T^T f_mj``."""
    m = _smap(robot)
    f_mj = _check(f_mj, m.nv, "f_mj")
    return velocity_map(robot, q).T @ f_mj


def force_pin_to_mj(robot: HasStateMap | StateMap, q, f_pin) -> np.ndarray:
    """Generalized force in Pinocchio coordinates -> MuJoCo's: ``f_mj = T^-T f_pin``.

    ``T`` is orthogonal (a permutation with rotation blocks), so ``T^-T = T``.
    """
    m = _smap(robot)
    f_pin = _check(f_pin, m.nv, "f_pin")
    return velocity_map(robot, q) @ f_pin


def mass_matrix_mj_to_pin(robot: HasStateMap | StateMap, q, M_mj) -> np.ndarray:
    """MuJoCo's joint-space inertia matrix -> Pinocchio's: ``T^T M_mj T``."""
    T = velocity_map(robot, q)
    return T.T @ np.asarray(M_mj, dtype=float) @ T


def bias_mj_to_pin(robot: HasStateMap | StateMap, q, v, bias_mj, M_mj) -> np.ndarray:
    """MuJoCo bias forces (``qfrc_bias``) -> Pinocchio's nonlinear effects.

    From ``qvel = T v``: ``qacc = T vdot + Tdot v``; multiplying MuJoCo's
    ``M_mj qacc + b_mj = tau_mj`` by ``T^T`` gives
    ``M_pin vdot + T^T (b_mj + M_mj Tdot v) = tau_pin``.

    Args:
        robot: The robot (or its state map).
        q, v: Pinocchio state.
        bias_mj: MuJoCo ``qfrc_bias`` at the same state, shape (nv,).
        M_mj: MuJoCo's full mass matrix at that state, shape (nv, nv).
    """
    T = velocity_map(robot, q)
    return T.T @ (np.asarray(bias_mj, dtype=float) + np.asarray(M_mj) @ velocity_map_dot_v(robot, q, v))
