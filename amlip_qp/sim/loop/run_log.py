"""The per-tick log of :meth:`~amlip_qp.sim.loop.harness.Simulation.run`: its entries, their layout, the modes.

The loop keeps each tick's scalars as one tuple (:data:`SCALAR_KEYS`, then
:data:`SCALAR_KEYS_FULL` in the full log) and its vectors as one row of a
preallocated array (:func:`vector_groups`, then :data:`VECTOR_GROUPS_FULL`);
:func:`unpack_log` turns them into the log, name -> array with one row per
tick. ``log="summary"`` keeps only :data:`SUMMARY_LOG_KEYS`.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

#: The log entries :func:`~amlip_qp.sim.reports.summary.summarize` reads: all that a ``log="summary"`` run
#: (:meth:`~amlip_qp.sim.loop.harness.Simulation.run`) records. ``base_vel_*`` and
#: ``base_yaw_*`` exist for a floating base only.
SUMMARY_LOG_KEYS: tuple[str, ...] = (
    "t", "com", "com_vel", "heading", "cmd_vx", "cmd_vy", "base_yaw", "h", "h_d", "tau", "tracker_ok",
    "base_vel_true", "base_vel_est", "base_yaw_true", "base_yaw_est",
)  # fmt: skip

#: The log modes of :meth:`~amlip_qp.sim.loop.harness.Simulation.run`.
LOG_MODES: tuple[str, ...] = ("full", "summary")

#: The order of the log's entries (as documented in :meth:`~amlip_qp.sim.loop.harness.Simulation.run`).
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


class TickLog:
    """The per-tick log of one run, recorded by :attr:`record` (the harness tick's ``record`` hook).

    The log holds, per control tick: ``t``, ``com`` (3), ``com_vel`` (3),
    ``base_pos`` (3), ``base_tilt``, ``base_yaw`` (rad, wrapped to (-pi, pi]),
    ``stance_left`` (1 if left stance), ``phase``, ``t_remaining`` (the
    planner's prediction horizon, s), ``heading``, ``p_st`` (3, CoM minus
    stance contact, m), ``L_meas`` (3), ``L`` (3, filtered),
    ``L_hat`` (2), ``L_des`` (2), ``p_sw_des`` (2), ``swing_target`` (3),
    ``h`` and ``h_d`` (outputs), ``tau`` (joint side, N m),
    ``tracker_ok``, ``push`` (3, N) and the command ``cmd_vx``, ``cmd_vy``,
    ``cmd_turn_rate``. ``base_pos`` and ``base_yaw`` are MuJoCo's body pose of
    the last plant step's start. For a floating-base robot, the base state
    the controller used against the truth at the measurement:
    ``base_pos_true``, ``base_vel_true`` (3, world, m/s), ``base_yaw_true``,
    and ``base_pos_est``, ``base_vel_est``, ``base_yaw_est`` (equal to the
    truth with ``--estimator truth`` and exact sensors).

    Args:
        n_ticks: The run's number of ticks (the vector rows are preallocated).
        n_out: The planner's number of outputs.
        nu: The number of actuated joints.
        full: ``True``: every entry; ``False``: those the summary reads (``log="summary"``).
        floating: The robot has a floating base (its true and estimated base rows are kept).
        base_size: The sizes of the base's ``q`` and ``v`` coordinates.
        est_is_true: The controller's base state is the measured one itself (the true
            base and no noise): its rows are the true rows, not kept twice.
        base_pos: The base body's MuJoCo position (a view into ``MjData.xpos``), read by
            :attr:`record` before the tick's plant steps.
        kin_state: The controller's kinematics' ``state()``: its ``(q, v)`` of the tick.
        base_q: The base's ``q`` indices (a slice with a floating base).
        base_v: The base's ``v`` indices (a slice with a floating base).
    """

    def __init__(
        self,
        n_ticks: int,
        n_out: int,
        nu: int,
        full: bool,
        floating: bool,
        base_size: tuple[int, int],
        est_is_true: bool,
        base_pos: np.ndarray,
        kin_state: Callable[[], tuple[np.ndarray, np.ndarray]],
        base_q,
        base_v,
    ):
        self.full, self.floating = full, floating
        self.scalar_keys = SCALAR_KEYS + (SCALAR_KEYS_FULL if full else ())
        self.vector_keys = vector_groups(n_out, nu) + (VECTOR_GROUPS_FULL if full else ())
        # One row per tick: the Python scalars and the base states go to row blocks (flat lists turned
        # into arrays every BLOCK_ROWS ticks), the vectors to one preallocated row (one np.concatenate).
        self.vectors = vectors = np.zeros((n_ticks, sum(w for _, w in self.vector_keys)))
        self.scalars = RowBlocks(len(self.scalar_keys))
        self.base_true = RowBlocks(sum(base_size))  # the measured base state's (q, v)
        # The controller's: with the true base and no --noise, the measured one itself (the
        # controller's kinematics take the measurement as it is; tested), not logged twice.
        self.base_est = self.base_true if est_is_true else RowBlocks(sum(base_size))
        # each tick extends these flat lists by its row
        scalar_rows, true_rows, est_rows = (
            self.scalars.rows.extend,
            self.base_true.rows.extend,
            self.base_est.rows.extend,
        )
        concatenate, acos, atan2 = np.concatenate, math.acos, math.atan2
        own_est = floating and not est_is_true
        row = iter(vectors)  # the next tick's vector row

        def record(t, cmd, tick, push, root, r00, r10, r22) -> None:
            """Log one tick: its time, command, controller step, push, base row and base orientation."""
            if floating:
                true_rows(root)
                if own_est:
                    q_est, v_est = kin_state()
                    est_rows(q_est.tolist()[base_q] + v_est.tolist()[base_v])
            est, plan = tick.estimate, tick.plan
            ok = 1.0 if tick.tracker_ok else 0.0
            if full:
                tilt = acos(max(-1.0, min(1.0, r22)))
                scalar_rows(
                    (
                        t, cmd.vx_mps, cmd.vy_mps, plan.heading_rad, atan2(r10, r00), ok,
                        tilt, 1.0 if tick.stance == "left" else 0.0, tick.phase, plan.t_remaining_s,
                        cmd.turn_rate_radps,
                    )
                )  # fmt: skip
                concatenate(
                    (
                        est.com_m, est.com_vel_mps, tick.h, plan.h_d, tick.tau_Nm,
                        base_pos, est.p_st_m, est.L_meas_Nms, est.L_Nms, plan.L_hat_Nms, plan.L_des_Nms,
                        plan.p_sw_des_world_m, plan.swing_target_world_m, push,
                    ),
                    out=next(row),
                )  # fmt: skip
            else:
                scalar_rows((t, cmd.vx_mps, cmd.vy_mps, plan.heading_rad, atan2(r10, r00), ok))
                concatenate((est.com_m, est.com_vel_mps, tick.h, plan.h_d, tick.tau_Nm), out=next(row))

        self.record = record

    def flush(self) -> None:
        """Turn the rows so far into array blocks (every :data:`BLOCK_ROWS` ticks)."""
        self.scalars.flush()
        self.base_true.flush()
        self.base_est.flush()

    def log(self, n: int) -> dict[str, np.ndarray]:
        """The log of the first ``n`` ticks (those recorded), name -> array (:func:`unpack_log`)."""
        return unpack_log(
            self.scalars.array(), self.scalar_keys, self.vectors[:n], self.vector_keys,
            self.base_true.array(), self.base_est.array(), self.floating, self.full,
        )  # fmt: skip


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
