"""The per-tick log of :meth:`~amlip_qp.sim.harness.Simulation.run`: its entries, their layout in the loop, the modes.

The loop keeps each tick's scalars as one tuple (:data:`SCALAR_KEYS`, then
:data:`SCALAR_KEYS_FULL` in the full log) and its vectors as one row of a
preallocated array (:func:`vector_groups`, then :data:`VECTOR_GROUPS_FULL`);
:func:`unpack_log` turns them into the log, name -> array with one row per
tick. ``log="summary"`` keeps only :data:`~amlip_qp.sim.summary.SUMMARY_LOG_KEYS`.
"""

from __future__ import annotations

import numpy as np

from amlip_qp.sim.summary import SUMMARY_LOG_KEYS

#: The log modes of :meth:`~amlip_qp.sim.harness.Simulation.run`.
LOG_MODES: tuple[str, ...] = ("full", "summary")

#: The order of the log's entries (as documented in :meth:`~amlip_qp.sim.harness.Simulation.run`).
LOG_ORDER = (
    "t", "com", "com_vel", "base_pos", "base_tilt", "base_yaw", "stance_left", "phase", "t_remaining", "heading",
    "p_st", "L_meas", "L", "L_hat", "L_des", "p_sw_des", "swing_target", "h", "h_d", "tau", "tracker_ok", "push",
    "cmd_vx", "cmd_vy", "cmd_turn_rate",
)  # fmt: skip
#: The scalar log entries, in the order of the loop's tuples: those the summary reads, then the rest.
SCALAR_KEYS = ("t", "cmd_vx", "cmd_vy", "heading", "base_yaw", "tracker_ok")
SCALAR_KEYS_FULL = ("base_tilt", "stance_left", "phase", "t_remaining", "cmd_turn_rate")
#: The vector log entries after those of :func:`vector_groups` (full log only), ``(key, width)``.
VECTOR_GROUPS_FULL = (
    ("base_pos", 3),
    ("p_st", 3),
    ("L_meas", 3),
    ("L", 3),
    ("L_hat", 2),
    ("L_des", 2),
    ("p_sw_des", 2),
    ("swing_target", 3),
    ("push", 3),
)


class RowBlocks:
    """Rows of ``width`` numbers, each extending the flat list :attr:`rows`, kept as arrays of ``dtype``.

    The loop extends :attr:`rows` by each tick's row (a list extend: about the cheapest per
    tick) and calls :meth:`flush` now and then (every :data:`BLOCK_ROWS` ticks), which turns the
    numbers so far into one array block and empties the list: the memory stays that of the
    numbers. (A flat list converts several times faster than a list of rows.)
    """

    def __init__(self, width: int, dtype: type = float):
        self.width = int(width)
        self.dtype = dtype
        self.rows: list = []
        self._blocks: list[np.ndarray] = []

    def flush(self) -> None:
        """Move the rows appended so far into an array block.

        Raises:
            ValueError: The numbers so far are not whole rows.
        """
        rows = self.rows
        if rows:
            self._blocks.append(np.fromiter(rows, self.dtype, len(rows)).reshape(-1, self.width))
            rows.clear()

    def array(self) -> np.ndarray:
        """All rows, shape ``(n, width)``."""
        self.flush()
        return np.concatenate(self._blocks) if self._blocks else np.zeros((0, self.width), dtype=self.dtype)


#: How many rows the loop adds between :meth:`RowBlocks.flush` calls.
BLOCK_ROWS = 4096


def vector_groups(n_out: int, nu: int) -> tuple[tuple[str, int], ...]:
    """The vector log entries the summary reads, in the order of the loop's rows, ``(key, width)``."""
    return (("com", 3), ("com_vel", 3), ("h", n_out), ("h_d", n_out), ("tau", nu))


def unpack_log(
    scalars, scalar_keys, vectors, vector_keys, base_true, base_est, floating, full
) -> dict[str, np.ndarray]:
    """The log as name -> array (one row per tick) from the loop's scalar rows and vector rows."""
    n = vectors.shape[0]
    table = np.asarray(scalars, dtype=float).reshape(n, len(scalar_keys))
    columns = {key: table[:, i].copy() for i, key in enumerate(scalar_keys)}
    col = 0
    for key, width in vector_keys:
        columns[key] = vectors[:, col : col + width].copy()
        col += width
    out = {key: columns[key] for key in LOG_ORDER if key in columns}
    if floating:
        out.update(world_base(base_true, "true"))
        out.update(world_base(base_est, "est"))
    return out if full else {key: value for key, value in out.items() if key in SUMMARY_LOG_KEYS}


def world_base(rows: np.ndarray, suffix: str) -> dict[str, np.ndarray]:
    """``base_pos_*``, ``base_vel_*`` (world) and ``base_yaw_*`` from free-flyer rows ``(q[:7], v[:6])``."""
    pos, quat, vel_body = rows[:, :3], rows[:, 3:7], rows[:, 7:10]
    u, w = quat[:, :3], quat[:, 3:4]
    uv = np.cross(u, vel_body)
    vel_world = vel_body + 2.0 * w * uv + 2.0 * np.cross(u, uv)  # R(quat) @ v for unit quaternions
    x, y, z, qw = quat.T
    yaw = np.arctan2(2.0 * (qw * z + x * y), 1.0 - 2.0 * (y * y + z * z))
    return {f"base_pos_{suffix}": pos.copy(), f"base_vel_{suffix}": vel_world, f"base_yaw_{suffix}": yaw}
