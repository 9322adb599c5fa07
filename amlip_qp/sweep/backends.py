"""Where the cells run: a local process pool (``--workers N``) or Ray tasks (``--ray [ADDRESS]``).

Both hand each cell's task to :func:`amlip_qp.sweep.run_cell.run_cell` and
report the records as they finish (in any order; the table is sorted by cell
afterwards). The pool is :class:`concurrent.futures.ProcessPoolExecutor`; on a
cluster, Ray schedules the tasks. Nothing here schedules by itself.
"""

from __future__ import annotations

import contextlib
import logging
import os
import socket
import sys
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from typing import Any

from amlip_qp.exceptions import InputError

#: Seconds to wait for a Ray cluster's address to answer before refusing it.
RAY_CONNECT_TIMEOUT_S = 3.0

Task = dict[str, Any]
OnRecord = Callable[[dict[str, Any]], None]


def default_workers() -> int:
    """One worker per core this process may run on."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - not on Linux
        return max(1, os.cpu_count() or 1)


def run_local(
    tasks: Sequence[Task], workers: int, on_record: OnRecord, fn: Callable[[Task], dict] | None = None
) -> None:
    """Run ``tasks`` on a pool of ``workers`` processes; ``on_record`` gets each record as it finishes.

    At most ``workers`` tasks are in flight, so when a worker process dies (a
    crash in native code, the out-of-memory killer) the cells it may have been
    running are known. The pool is then replaced, and each of those cells runs
    again alone: if its worker dies again it is recorded as failed
    (:func:`~amlip_qp.sweep.run_cell.crashed_record`) and the sweep goes on.
    Running them one at a time leaves the other workers idle meanwhile (a death
    costs up to ``workers`` cell times), but it tells the culprit apart.
    On an error in ``on_record`` or an interrupt the tasks not yet started are
    cancelled (the finished ones have been reported).

    Args:
        tasks: The cells' tasks.
        workers: Worker processes (>= 1).
        on_record: Called with each record, in the parent process.
        fn: The function a worker runs on a task (default
            :func:`~amlip_qp.sweep.run_cell.run_cell`; picklable).
    """
    from amlip_qp.sweep.run_cell import crashed_record, run_cell

    run = fn or run_cell
    queue = list(range(len(tasks) - 1, -1, -1))  # task positions; pop() takes them in order
    while queue:
        lost = _run_pool(run, tasks, queue, min(workers, len(queue)), on_record)
        for k in lost:  # alone now: a death is its own
            if _run_pool(run, tasks, [k], 1, on_record):
                on_record(crashed_record(tasks[k], deaths=2))


def _run_pool(
    run: Callable[[Task], dict], tasks: Sequence[Task], queue: list[int], n: int, on_record: OnRecord
) -> list[int]:
    """Run the tasks at the positions of ``queue`` (taken from its end) on one pool of ``n`` processes,
    at most ``n`` in flight. Returns the positions in flight when a worker died (``[]`` if none did);
    the tasks not yet started stay in ``queue``. Every record that finished is reported, also
    those that finish together with the death."""
    pool = ProcessPoolExecutor(max_workers=n)
    in_flight: dict[Future, int] = {}
    try:
        while queue or in_flight:
            while queue and len(in_flight) < n:
                k = queue.pop()
                try:
                    in_flight[pool.submit(run, tasks[k])] = k
                except BrokenProcessPool:  # a worker died since the last wait
                    queue.append(k)
                    break
            done, _ = wait(in_flight, return_when=FIRST_COMPLETED)
            broken = False
            for fut in done:
                try:
                    record = fut.result()
                except BrokenProcessPool:
                    broken = True
                    continue
                del in_flight[fut]
                on_record(record)
            if broken:
                return sorted(in_flight.values())
        return []
    finally:
        pool.shutdown(wait=True, cancel_futures=True)


def ray_host_port(address: str) -> tuple[str, int] | None:
    """``(host, port)`` of ``HOST:PORT`` or ``ray://HOST:PORT``; ``None`` for ``auto``."""
    if address == "auto":
        return None
    body = address.removeprefix("ray://")
    host, sep, port = body.rpartition(":")
    if not sep or not host or not port.isdigit():
        raise InputError(f"--ray expects HOST:PORT, ray://HOST:PORT or auto, got {address!r} (put SPEC before --ray)")
    return host.strip("[]"), int(port)


def connect_ray(address: str | None) -> tuple[Any, bool]:
    """Connect to Ray (``None``: a Ray session already started in this process, else a new local one).

    Returns ``(ray module, whether this call started the session)``.

    Raises:
        InputError: Ray is not installed, or the address does not answer within
            :data:`RAY_CONNECT_TIMEOUT_S` seconds, or Ray refuses to connect.
    """
    try:
        import ray
    except ImportError:
        raise InputError("--ray needs Ray: pip install 'amlip_qp[ray]'") from None
    if ray.is_initialized():
        return ray, False
    if address is not None:
        hp = ray_host_port(address)
        if hp is not None:
            try:
                socket.create_connection(hp, timeout=RAY_CONNECT_TIMEOUT_S).close()
            except OSError as exc:
                raise InputError(
                    f"--ray {address}: the Ray cluster does not answer ({exc.strerror or exc}); "
                    "start it with 'ray start --head' or check the address"
                ) from None
    # Connecting to a cluster: give up after a few seconds (Ray's retries wait about 1 s each), and keep
    # Ray's per-retry messages (its C++ core writes them to file descriptor 2) off stderr.
    wait_key = "RAY_gcs_server_port_wait_time_s"
    saved = os.environ.get(wait_key)
    if address is not None and saved is None:
        os.environ[wait_key] = str(int(RAY_CONNECT_TIMEOUT_S))
    try:
        with _silenced_fd2(address is not None):
            ray.init(address=address, include_dashboard=False, log_to_driver=False, logging_level=logging.ERROR)
    except (ConnectionError, RuntimeError, ValueError) as exc:
        raise InputError(f"--ray {address or ''}: cannot connect to Ray: {str(exc).splitlines()[0]}") from None
    finally:
        if saved is None:
            os.environ.pop(wait_key, None)
    return ray, True


@contextlib.contextmanager
def _silenced_fd2(silence: bool) -> Iterator[None]:
    """Point file descriptor 2 (stderr, also for C++ code) at /dev/null while active (if ``silence``)."""
    if not silence:
        yield
        return
    sys.stderr.flush()
    saved, devnull = os.dup(2), os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, 2)
    try:
        yield
    finally:
        os.dup2(saved, 2)
        os.close(saved)
        os.close(devnull)


def ray_cpus(ray: Any) -> int:
    """CPUs of the connected Ray cluster (one task each)."""
    return int(ray.cluster_resources().get("CPU", 1))


def run_ray(ray: Any, tasks: Sequence[Task], on_record: OnRecord, fn: Callable[[Task], dict] | None = None) -> None:
    """Run ``tasks`` as Ray tasks (one CPU each) on the connected cluster; ``on_record`` and ``fn`` as in
    :func:`run_local`.

    Each task runs in a worker of its own, so a dying worker takes only its own
    cell with it: Ray runs that cell once more (``max_retries=1``, which retries
    only system failures), and if its worker dies again the cell is recorded as
    failed (:func:`~amlip_qp.sweep.run_cell.crashed_record`) and the sweep goes on.
    A task that Ray's own memory monitor kills is retried as the cluster's
    ``task_oom_retries`` setting says, then recorded the same way.
    """
    from amlip_qp.sweep.run_cell import crashed_record, run_cell

    died = (ray.exceptions.WorkerCrashedError, ray.exceptions.OutOfMemoryError)
    remote = ray.remote(num_cpus=1, max_retries=1)(fn or run_cell)
    pending = [remote.remote(t) for t in tasks]
    task_of = dict(zip(pending, tasks, strict=True))
    try:
        while pending:
            done, pending = ray.wait(pending, num_returns=1)
            for ref in done:
                task = task_of.pop(ref)
                try:
                    record = ray.get(ref)
                except died:
                    record = crashed_record(task, deaths=2)
                on_record(record)
    finally:
        for ref in pending:
            ray.cancel(ref, force=True)
