"""The backends' checks before any work: Ray addresses, an unreachable cluster, the default worker count."""

from __future__ import annotations

import os
import socket
import time

import pytest

from amlip_qp.exceptions import InputError
from amlip_qp.sweep import backends


def test_ray_addresses_are_parsed():
    assert backends.ray_host_port("10.0.0.5:6379") == ("10.0.0.5", 6379)
    assert backends.ray_host_port("ray://head.local:10001") == ("head.local", 10001)
    assert backends.ray_host_port("[::1]:6379") == ("::1", 6379)
    assert backends.ray_host_port("auto") is None
    with pytest.raises(InputError, match="put SPEC before --ray"):
        backends.ray_host_port("push_map.toml")


def test_a_closed_port_is_refused_at_once():
    with socket.socket() as s:  # a free port, closed again: nothing listens there
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    with pytest.raises(InputError, match=rf"--ray 127.0.0.1:{port}: the Ray cluster does not answer"):
        backends.connect_ray(f"127.0.0.1:{port}")


def test_one_worker_per_usable_core():
    assert backends.default_workers() == len(os.sched_getaffinity(0))


def _dies_on_cell_2(task: dict) -> dict:
    """A worker's task function: the process dies outright on cell 2 (as a segfault would)."""
    if task["index"] == 2:
        os._exit(1)
    return {**task, "metrics": {"x": task["index"] * 10}, "error": None, "wall_s": 0.0}


def test_a_dying_worker_fails_its_own_cell_only_and_the_sweep_goes_on():
    """Cell 2 kills its worker process every time. With 2 workers its neighbour in flight is
    rerun (not blamed) and every other cell finishes once; cell 2 is recorded as failed."""
    tasks = [{"index": k} for k in range(6)]
    records: list[dict] = []
    backends.run_local(tasks, 2, records.append, fn=_dies_on_cell_2)
    by_index = {r["index"]: r for r in records}
    assert sorted(r["index"] for r in records) == list(range(6))  # each cell reported exactly once
    assert by_index[2]["metrics"] == {} and by_index[2]["error"].startswith("WorkerDied: ")
    for k in (0, 1, 3, 4, 5):
        assert by_index[k]["error"] is None and by_index[k]["metrics"] == {"x": 10 * k}


def test_without_deaths_every_cell_runs_once_in_order_of_submission():
    records: list[dict] = []
    backends.run_local([{"index": k} for k in range(5)], 1, records.append, fn=_identity)
    assert [r["index"] for r in records] == list(range(5))


def _identity(task: dict) -> dict:
    return {**task, "metrics": {}, "error": None, "wall_s": 0.0}


@pytest.mark.slow
def test_on_ray_a_dying_worker_fails_its_own_cell_only():
    """The same on a local Ray cluster: Ray reruns cell 2 once, its worker dies again, and the
    cell is recorded as failed while the others finish."""
    import ray

    def dies_on_cell_2(task: dict) -> dict:  # nested: Ray's workers get it by value
        if task["index"] == 2:
            os._exit(1)
        return {**task, "metrics": {"x": task["index"] * 10}, "error": None, "wall_s": 0.0}

    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False, _node_ip_address="127.0.0.1")
    try:
        records: list[dict] = []
        backends.run_ray(ray, [{"index": k} for k in range(4)], records.append, fn=dies_on_cell_2)
    finally:
        ray.shutdown()
    by_index = {r["index"]: r for r in records}
    assert sorted(by_index) == [0, 1, 2, 3] and len(records) == 4
    assert by_index[2]["metrics"] == {} and by_index[2]["error"].startswith("WorkerDied: ")
    assert all(by_index[k]["metrics"] == {"x": 10 * k} for k in (0, 1, 3))


def _dies_late_on_cell_1(task: dict) -> dict:
    """Cell 1's worker dies after 0.3 s; the others return at once."""
    if task["index"] == 1:
        time.sleep(0.3)
        os._exit(1)
    return _identity(task)


def test_a_death_while_a_record_is_written_loses_no_cell():
    """The worker of cell 1 dies while the parent is busy in on_record (a slow write): the next
    submit meets a broken pool. Every cell is still reported once, cell 1 as failed."""
    records: list[dict] = []

    def slow_record(record: dict) -> None:
        records.append(record)
        time.sleep(1.0)

    backends.run_local([{"index": k} for k in range(4)], 2, slow_record, fn=_dies_late_on_cell_1)
    by_index = {r["index"]: r for r in records}
    assert sorted(r["index"] for r in records) == [0, 1, 2, 3]
    assert by_index[1]["error"].startswith("WorkerDied: ")
    assert all(by_index[k]["error"] is None for k in (0, 2, 3))
