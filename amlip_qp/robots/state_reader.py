"""The per-tick state read: MuJoCo ``(qpos, qvel)`` -> Pinocchio ``(q, v)`` for one state map, in plain Python.

:class:`StateReader` is :func:`~amlip_qp.robots.state.mj_to_pin` with its
index maps composed once. It is called every control tick on vectors of a
few dozen numbers, where each NumPy call costs more than the arithmetic, so
it works on Python lists: one ``tolist`` per array in, one ``np.array`` per
array out, Python float arithmetic in between, in the same operation order as
:func:`~amlip_qp.robots.state.mj_to_pin` (whose dot products and 3x3 matrix
products sum left to right without fused multiply-adds), so the two agree bit
for bit (tested). That holds for NumPy's own small dot products, as on this
machine; a NumPy build whose 3-element dot uses fused multiply-adds would
make the two differ in the last bit (the test would say so).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from operator import itemgetter

import numpy as np

from amlip_qp.robots.state import StateMap, mj_to_pin, rotation_entries


def _getter(indices: Sequence[int] | np.ndarray, n_in: int | None = None) -> Callable[[Sequence[float]], list[float]]:
    """``f(seq) -> [seq[i] for i in indices]``: one ``itemgetter`` call, or ``list`` when ``indices`` take all ``n_in``
    items of ``seq`` in order."""
    idx = [int(i) for i in indices]
    if n_in is not None and idx == list(range(n_in)):
        return list
    if len(idx) == 1:
        i = idx[0]
        return lambda seq: [seq[i]]
    get = itemgetter(*idx)
    return lambda seq: list(get(seq))


class StateReader:
    """:func:`~amlip_qp.robots.state.mj_to_pin` for one state map (called every control tick).

    ``reader(qpos, qvel)`` equals ``mj_to_pin(state_map, qpos[qpos_src], qvel[qvel_src])``
    bit for bit (tested); :meth:`lists` is the same on and to Python lists.

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
        n_q, n_v = (m.nq_mj if qpos_src is None else None), (m.nv if qvel_src is None else None)  # the layout read
        self._take_q, self._take_v = _getter(qsrc[gq], n_q), _getter(vsrc[gv], n_v)
        self._quats = tuple(quats)

    def __call__(self, qpos: np.ndarray, qvel: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(q, v)`` (new arrays) of the plant's float64 ``qpos`` and ``qvel`` (read only; ``data.qpos``).

        Unlike :func:`~amlip_qp.robots.state.mj_to_pin` it does not check the arrays' length
        or type: give it the arrays of the layout it was built for.

        Raises:
            InputError: As :func:`~amlip_qp.robots.state.mj_to_pin`: NaN/inf, or a zero quaternion.
        """
        q, v = self.lists(qpos.tolist(), qvel.tolist())
        return np.array(q), np.array(v)

    def lists(self, qpos: list[float], qvel: list[float]) -> tuple[list[float], list[float]]:
        """:meth:`__call__` on ``qpos.tolist()`` and ``qvel.tolist()``, giving ``(q, v)`` as new lists."""
        q, v = self._take_q(qpos), self._take_v(qvel)
        isfinite, sqrt = math.isfinite, math.sqrt
        if not isfinite(sum(q) + sum(v)):  # a finite sum implies finite entries (an overflow: checked too)
            return self._checked(qpos, qvel)  # raises, naming the entries
        for iw, ix, iy, iz, pq, free in self._quats:
            w, x, y, z = qpos[iw], qpos[ix], qpos[iy], qpos[iz]
            n = sqrt(w * w + x * x + y * y + z * z)
            if n < 1e-9:
                return self._checked(qpos, qvel)  # raises
            x, y, z, w = x / n, y / n, z / n, w / n
            q[pq], q[pq + 1], q[pq + 2], q[pq + 3] = x, y, z, w
            if free is None:
                continue
            # the rotation of the (re-normalized) quaternion, as state._quat_wxyz_to_rot; then R^T @ qvel's linear part
            pv, i0, i1, i2 = free
            n = sqrt(w * w + x * x + y * y + z * z)
            r00, r01, r02, r10, r11, r12, r20, r21, r22 = rotation_entries(w / n, x / n, y / n, z / n)
            l0, l1, l2 = qvel[i0], qvel[i1], qvel[i2]
            v[pv] = r00 * l0 + r10 * l1 + r20 * l2
            v[pv + 1] = r01 * l0 + r11 * l1 + r21 * l2
            v[pv + 2] = r02 * l0 + r12 * l1 + r22 * l2
        return q, v

    def _checked(self, qpos: list[float], qvel: list[float]) -> tuple[list[float], list[float]]:
        q, v = mj_to_pin(self.state_map, np.array(qpos)[self._qsrc], np.array(qvel)[self._vsrc])
        return q.tolist(), v.tolist()
