"""The per-tick state read: MuJoCo ``(qpos, qvel)`` -> Pinocchio ``(q, v)`` for one state map, in plain Python.

:class:`StateReader` is :func:`~amlip_qp.robots.state.mj_to_pin` with its
index maps composed once. It is called every control tick on vectors of a
few dozen numbers, where each NumPy call costs more than the arithmetic, so
it does one NumPy gather per array and the rest on Python floats (one
``tolist`` per array in): the quaternions and the free joints' linear
velocities are computed in plain Python and written in, in the same operation order as
:func:`~amlip_qp.robots.state.mj_to_pin` (whose dot products and 3x3 matrix
products sum left to right without fused multiply-adds), so the two agree bit
for bit (tested). That holds for NumPy's own small dot products, as on this
machine; a NumPy build whose 3-element dot uses fused multiply-adds would
make the two differ in the last bit (the test would say so).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from functools import partial
from typing import NamedTuple

import numpy as np

from amlip_qp.robots.state import ZERO_QUATERNION_NORM, StateMap, mj_to_pin, rotation_entries


class FreeJointPlan(NamedTuple):
    """Where :meth:`StateReader.arrays` of one free joint (and no ball joint) takes each number.

    For another implementation of the same read (the harness's generated C,
    :mod:`amlip_qp.sim.world.compiled_io`), which must give the same numbers: ``q`` is
    ``qpos[gather_q]`` and ``v`` is ``qvel[gather_v]``, then the quaternion
    ``qpos[quat_wxyz]``, normalized, is written to ``q[pq:pq + 4]`` (x y z w) and the
    linear velocity ``qvel[lin_xyz]`` rotated into the base frame to ``v[pv:pv + 3]``;
    the root row is ``qpos[root_pos]``, the quaternion, ``v[pv:pv + 3]`` and
    ``qvel[root_ang]`` (plant indices).
    """

    gather_q: tuple[int, ...]
    gather_v: tuple[int, ...]
    quat_wxyz: tuple[int, int, int, int]
    pq: int
    pv: int
    lin_xyz: tuple[int, int, int]
    root_pos: tuple[int, int, int]
    root_ang: tuple[int, int, int]


class StateReader:
    """:func:`~amlip_qp.robots.state.mj_to_pin` for one state map (called every control tick).

    ``reader(qpos, qvel)`` equals ``mj_to_pin(state_map, qpos[qpos_src], qvel[qvel_src])``
    bit for bit (tested); :meth:`arrays` is the same, given ``qpos.tolist()`` too.

    Args:
        state_map: The controller's :class:`~amlip_qp.robots.state.StateMap`.
        qpos_src: Where each of the map's MuJoCo ``qpos`` coordinates lies in the
            arrays read (a plant with more joints); ``None``: the same layout.
        qvel_src: The same for ``qvel``.
    """

    def __init__(self, state_map: StateMap, qpos_src: np.ndarray | None = None, qvel_src: np.ndarray | None = None):
        m = state_map
        qsrc = np.arange(m.nq_mj) if qpos_src is None else np.asarray(qpos_src, dtype=np.intp)
        vsrc = np.arange(m.nv) if qvel_src is None else np.asarray(qvel_src, dtype=np.intp)
        gq = np.empty(m.nq_pin, dtype=np.intp)
        gv = np.empty(m.nv, dtype=np.intp)
        gq[m.scalar_pin_q], gv[m.scalar_pin_v] = m.scalar_mj_q, m.scalar_mj_v
        # Per quaternion: the plant indices of its w, x, y, z; its first Pinocchio q index (x y z w
        # order); for a free joint, its linear velocity's first index in v and its indices in qvel.
        quats: list[tuple] = []
        for qa, da, pq, pv in m.free:
            gq[pq : pq + 3], gq[pq + 3 : pq + 7] = range(qa, qa + 3), (qa + 4, qa + 5, qa + 6, qa + 3)
            gv[pv : pv + 6] = range(da, da + 6)
            quats.append((*qsrc[qa + 3 : qa + 7].tolist(), pq + 3, (pv, *vsrc[da : da + 3].tolist())))
        for qa, da, pq, pv in m.ball:
            gq[pq : pq + 4] = (qa + 1, qa + 2, qa + 3, qa)
            gv[pv : pv + 3] = range(da, da + 3)
            quats.append((*qsrc[qa : qa + 4].tolist(), pq, None))
        self.state_map = m
        self._qsrc, self._vsrc = qsrc, vsrc
        self._quats = tuple(quats)
        # one NumPy gather per array, a copy (cheaper) when it takes the plant's array as it is (the
        # quaternions, written in after it, from anywhere)
        gather_q, gather_v = qsrc[gq], vsrc[gv]
        as_is = gather_q.copy()
        for _, _, pq, _ in m.free:
            as_is[pq + 3 : pq + 7] = range(pq + 3, pq + 7)
        for _, _, pq, _ in m.ball:
            as_is[pq : pq + 4] = range(pq, pq + 4)
        self._gather_q = None if qpos_src is None and np.array_equal(as_is, np.arange(m.nq_mj)) else gather_q
        self._gather_v = None if qvel_src is None and np.array_equal(gather_v, np.arange(m.nv)) else gather_v
        # the first free joint's row of arrays(): its position's qpos and its angular velocity's qvel indices
        self._root: tuple | None = None
        if m.free:
            qa, da, _, _ = m.free[0]
            self._root = (*qsrc[qa : qa + 3].tolist(), *vsrc[da + 3 : da + 6].tolist())
        #: arrays() of one free joint and no ball joint (a floating-base robot), in straight lines; else None
        self._fast = _one_free_joint_arrays(
            self._quats, self._root, self._gather_q, self._gather_v, self._checked_arrays
        )
        #: The fast read's indices (:class:`FreeJointPlan`); ``None`` unless one free joint and no ball joint.
        self.free_joint_plan: FreeJointPlan | None = None
        if self._fast is not None:
            iw, ix, iy, iz, pq, (pv, i0, i1, i2) = self._quats[0]
            assert self._root is not None
            self.free_joint_plan = FreeJointPlan(
                tuple(gather_q.tolist()), tuple(gather_v.tolist()), (iw, ix, iy, iz), pq, pv, (i0, i1, i2),
                self._root[:3], self._root[3:],
            )  # fmt: skip

    def __call__(self, qpos: np.ndarray, qvel: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(q, v)`` (new arrays) of the plant's float64 ``qpos`` and ``qvel`` (read only; ``data.qpos``).

        Unlike :func:`~amlip_qp.robots.state.mj_to_pin` it does not check the arrays' length
        or type: give it the arrays of the layout it was built for.

        Raises:
            InputError: As :func:`~amlip_qp.robots.state.mj_to_pin`: NaN/inf, or a zero quaternion.
        """
        q, v, _ = self.arrays(qpos, qvel, qpos.tolist())
        return q, v

    def arrays(
        self, qpos: np.ndarray, qvel: np.ndarray, qpos_list: list[float], qpos_sum: float | None = None
    ) -> tuple[np.ndarray, np.ndarray, list[float]]:
        """:meth:`__call__` (bit for bit) given ``qpos.tolist()`` too, and the first free joint's row.

        The harness's per-tick read: ``q`` and ``v`` are NumPy gathers of ``qpos`` and ``qvel``
        with the quaternions and the free joints' linear velocities written in.

        Args:
            qpos, qvel: The plant's float64 arrays (read only).
            qpos_list: ``qpos.tolist()``.
            qpos_sum: ``sum(qpos_list)`` if the caller has it (``None``: summed here).

        Returns:
            ``(q, v, root)``: new arrays, and ``q[pq:pq + 7] + v[pv:pv + 6]`` of the first free
            joint (at ``pq``, ``pv``) as a list of 13 floats (``[]`` without a free joint).

        Raises:
            InputError: As :meth:`__call__`.
        """
        if self._fast is not None:
            return self._fast(qpos, qvel, qpos_list, qpos_sum)
        qvel_list = qvel.tolist()
        if not math.isfinite((sum(qpos_list) if qpos_sum is None else qpos_sum) + sum(qvel_list)):
            return self._checked_arrays(qpos_list, qvel_list)  # a finite sum implies finite entries
        gather_q, gather_v = self._gather_q, self._gather_v
        q = qpos.copy() if gather_q is None else qpos[gather_q]
        v = qvel.copy() if gather_v is None else qvel[gather_v]
        root = _write_quaternions(q, v, qpos_list, qvel_list, self._quats, self._root)
        if root is None:
            return self._checked_arrays(qpos_list, qvel_list)  # raises: a zero quaternion
        return q, v, root

    def bind(self, qpos: np.ndarray, qvel: np.ndarray) -> Callable[..., tuple[np.ndarray, np.ndarray, list[float]]]:
        """``f(qpos_list, qpos_sum=None)``: :meth:`arrays` of ``qpos`` and ``qvel`` (bound once; e.g. ``data.qpos``)."""
        return partial(self.arrays if self._fast is None else self._fast, qpos, qvel)

    def _checked_arrays(self, qpos: list[float], qvel: list[float]) -> tuple[np.ndarray, np.ndarray, list[float]]:
        """:meth:`arrays` through :func:`~amlip_qp.robots.state.mj_to_pin` (which raises naming the bad entries)."""
        q, v = mj_to_pin(self.state_map, np.array(qpos)[self._qsrc], np.array(qvel)[self._vsrc])
        root: list[float] = []
        if self.state_map.free:
            _, _, pq, pv = self.state_map.free[0]
            root = q[pq : pq + 7].tolist() + v[pv : pv + 6].tolist()
        return q, v, root


def _one_free_joint_arrays(quats: tuple, root_at: tuple | None, gather_q, gather_v, checked) -> Callable | None:
    """:meth:`StateReader.arrays` when the map has one free joint and no ball joint (else ``None``).

    One function of that joint alone, in straight lines: the same numbers as the general
    path (tested). ``checked``: :meth:`StateReader._checked_arrays` (NaN, inf, a zero quaternion).
    """
    if len(quats) != 1 or quats[0][5] is None:
        return None
    iw, ix, iy, iz, pq, (pv, i0, i1, i2) = quats[0]
    p0, p1, p2, a0, a1, a2 = root_at  # type: ignore[misc]
    q1, q2, q3, v1, v2, sqrt, isfinite = pq + 1, pq + 2, pq + 3, pv + 1, pv + 2, math.sqrt, math.isfinite

    def arrays(qpos_a: np.ndarray, qvel_a: np.ndarray, qpos: list[float], qpos_sum: float | None = None):
        qvel = qvel_a.tolist()
        if not isfinite((sum(qpos) if qpos_sum is None else qpos_sum) + sum(qvel)):
            return checked(qpos, qvel)  # a finite sum implies finite entries
        q = qpos_a.copy() if gather_q is None else qpos_a[gather_q]
        v = qvel_a.copy() if gather_v is None else qvel_a[gather_v]
        w, x, y, z = qpos[iw], qpos[ix], qpos[iy], qpos[iz]
        n = sqrt(w * w + x * x + y * y + z * z)
        if n < ZERO_QUATERNION_NORM:
            return checked(qpos, qvel)  # raises: a zero quaternion
        x, y, z, w = x / n, y / n, z / n, w / n
        q[pq] = x
        q[q1] = y
        q[q2] = z
        q[q3] = w
        n = sqrt(w * w + x * x + y * y + z * z)
        if n == 1.0:  # u / 1.0 is u
            rw, rx, ry, rz = w, x, y, z
        else:
            rw, rx, ry, rz = w / n, x / n, y / n, z / n
        # rotation_entries(rw, rx, ry, rz), its formula written out, each product computed once (the
        # same operands: the same numbers); then R^T @ qvel's linear part
        xx, yy, zz = rx * rx, ry * ry, rz * rz
        xy, xz, yz = rx * ry, rx * rz, ry * rz
        wx, wy, wz = rw * rx, rw * ry, rw * rz
        r00, r01, r02 = 1 - 2 * (yy + zz), 2 * (xy - wz), 2 * (xz + wy)
        r10, r11, r12 = 2 * (xy + wz), 1 - 2 * (xx + zz), 2 * (yz - wx)
        r20, r21, r22 = 2 * (xz - wy), 2 * (yz + wx), 1 - 2 * (xx + yy)
        l0, l1, l2 = qvel[i0], qvel[i1], qvel[i2]
        a = r00 * l0 + r10 * l1 + r20 * l2
        b = r01 * l0 + r11 * l1 + r21 * l2
        c = r02 * l0 + r12 * l1 + r22 * l2
        v[pv] = a
        v[v1] = b
        v[v2] = c
        return q, v, [qpos[p0], qpos[p1], qpos[p2], x, y, z, w, a, b, c, qvel[a0], qvel[a1], qvel[a2]]

    return arrays


def _write_quaternions(q, v, qpos, qvel, quats, root_at) -> list[float] | None:
    """Write the normalized quaternions and the free joints' linear velocities into ``q`` and ``v``.

    ``qpos`` and ``qvel`` are lists holding the plant's coordinates at the indices of ``quats``
    (:class:`StateReader`'s table) and ``root_at`` (the first free joint's position and angular
    velocity). Returns the first free joint's row (``[]`` without one), ``None`` at a zero quaternion.
    """
    root: list[float] = []
    sqrt = math.sqrt
    for iw, ix, iy, iz, pq, free in quats:
        w, x, y, z = qpos[iw], qpos[ix], qpos[iy], qpos[iz]
        n = sqrt(w * w + x * x + y * y + z * z)
        if n < ZERO_QUATERNION_NORM:
            return None
        x, y, z, w = x / n, y / n, z / n, w / n
        q[pq] = x
        q[pq + 1] = y
        q[pq + 2] = z
        q[pq + 3] = w
        if free is None:
            continue
        # the rotation of the (re-normalized) quaternion, as state._quat_wxyz_to_rot; then R^T @ qvel's linear part
        pv, i0, i1, i2 = free
        n = sqrt(w * w + x * x + y * y + z * z)
        r00, r01, r02, r10, r11, r12, r20, r21, r22 = rotation_entries(w / n, x / n, y / n, z / n)
        l0, l1, l2 = qvel[i0], qvel[i1], qvel[i2]
        a = r00 * l0 + r10 * l1 + r20 * l2
        b = r01 * l0 + r11 * l1 + r21 * l2
        c = r02 * l0 + r12 * l1 + r22 * l2
        v[pv] = a
        v[pv + 1] = b
        v[pv + 2] = c
        if not root:
            p0, p1, p2, a0, a1, a2 = root_at
            root = [qpos[p0], qpos[p1], qpos[p2], x, y, z, w, a, b, c, qvel[a0], qvel[a1], qvel[a2]]
    return root
