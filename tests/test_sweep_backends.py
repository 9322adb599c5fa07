"""The backends' checks before any work: Ray addresses, an unreachable cluster, the default worker count."""

from __future__ import annotations

import os
import socket

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
