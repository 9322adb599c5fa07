"""The per-tick log's layout: the loop's rows become the documented entries, in both modes."""

from __future__ import annotations

import math

import numpy as np
import pytest

from amlip_qp.sim.loop import run_log
from amlip_qp.sim.loop.run_log import SUMMARY_LOG_KEYS


def _rows(n: int, full: bool, n_out: int = 2, nu: int = 3):
    scalar_keys = run_log.SCALAR_KEYS + (run_log.SCALAR_KEYS_FULL if full else ())
    groups = run_log.vector_groups(n_out, nu) + (run_log.VECTOR_GROUPS_FULL if full else ())
    scalars = [tuple(100.0 * k + i for i in range(len(scalar_keys))) for k in range(n)]
    vectors = np.arange(n * sum(w for _, w in groups), dtype=float).reshape(n, -1)
    return scalars, scalar_keys, vectors, groups


def test_the_rows_unpack_into_the_documented_entries_and_the_summary_keeps_its_keys():
    base = np.zeros((4, 13))
    base[:, 6] = 1.0  # identity quaternion (xyzw)
    base[:, 7] = 2.0  # forward body velocity
    logs = {}
    for full in (True, False):
        scalars, skeys, vectors, groups = _rows(4, full)
        logs[full] = run_log.unpack_log(scalars, skeys, vectors, groups, base, base, True, full)
    full, short = logs[True], logs[False]
    assert list(full)[: len(run_log.LOG_ORDER)] == list(run_log.LOG_ORDER)
    assert set(short) == set(SUMMARY_LOG_KEYS)
    assert np.array_equal(full["t"], [0.0, 100.0, 200.0, 300.0])
    assert full["com"].shape == (4, 3) and full["h"].shape == (4, 2) and full["tau"].shape == (4, 3)
    assert np.array_equal(full["com"][1], [37.0, 38.0, 39.0])  # row 1 of 37 columns: com is first
    assert np.array_equal(full["push"][1], [71.0, 72.0, 73.0])  # push is last
    assert np.array_equal(full["base_vel_true"], np.tile([2.0, 0.0, 0.0], (4, 1)))
    assert np.array_equal(full["base_yaw_est"], np.zeros(4))
    for key in run_log.SCALAR_KEYS:  # the summary rows start like the full ones
        assert np.array_equal(short[key], full[key])


def test_world_base_rotates_the_body_velocity_and_gives_the_yaw():
    yaw = 0.7
    rows = np.zeros((1, 13))
    rows[0, :3] = [1.0, 2.0, 3.0]
    rows[0, 3:7] = [0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2)]  # xyzw
    rows[0, 7:10] = [1.0, 0.0, 0.0]
    out = run_log.world_base(rows, "true")
    assert np.allclose(out["base_vel_true"][0], [math.cos(yaw), math.sin(yaw), 0.0])
    assert math.isclose(out["base_yaw_true"][0], yaw, abs_tol=1e-12)
    assert np.array_equal(out["base_pos_true"][0], [1.0, 2.0, 3.0])


def test_row_blocks_keep_every_row_in_order_across_flushes():
    from amlip_qp.sim.loop.run_log import RowBlocks

    rng = np.random.default_rng(0)
    rows = rng.normal(size=(25, 3)).tolist()
    blocks = RowBlocks(3)
    assert blocks.array().shape == (0, 3)
    for k, row in enumerate(rows):
        blocks.rows.extend(tuple(row) if k % 2 else row)
        if k % 7 == 6:
            blocks.flush()
            assert not blocks.rows
    got = blocks.array()
    assert got.dtype == np.float64 and got.tobytes() == np.array(rows).tobytes()
    assert blocks.array().tobytes() == got.tobytes()  # again: the same rows
    blocks.rows.extend((1.0, 2.0))  # not a whole row
    with pytest.raises(ValueError):
        blocks.flush()


def test_row_blocks_of_integers_keep_them_exactly():
    """The harness's clock stamps (ns since boot: beyond float64's exact integers after 104 days)."""
    from amlip_qp.sim.loop.run_log import RowBlocks

    blocks = RowBlocks(2, np.int64)
    assert blocks.array().dtype == np.int64 and blocks.array().shape == (0, 2)
    big = 2**62 + 1
    blocks.rows.extend((big, big + 1))
    blocks.flush()
    blocks.rows.extend((1, 2))
    got = blocks.array()
    assert got.dtype == np.int64 and got.tolist() == [[big, big + 1], [1, 2]]
