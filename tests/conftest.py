"""Fixtures shared by the test modules."""

from __future__ import annotations

import os
from pathlib import Path

import pytest


@pytest.fixture(scope="session")
def shared_cache_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """One cache of compiled generated C for the whole pytest run, shared by its xdist workers.

    The tests that compile into a cache of their own, not the user's, build each library once
    per run here rather than once per module or test. The workers may share it: a library's
    folder is named by the hash of its source, compiler and flags, and each library is written to
    a temporary file and renamed into place (:mod:`amlip_qp.codegen.runtime`).
    """
    base = tmp_path_factory.getbasetemp()
    root = base.parent if os.environ.get("PYTEST_XDIST_WORKER") else base  # the run's folder, above the workers'
    path = root / "amlip_qp_cache"
    path.mkdir(exist_ok=True)
    return path


def _simulated(*args, **kwargs):
    raise AssertionError("a simulation or benchmark ran although the input was bad")


@pytest.fixture
def no_simulation(monkeypatch):
    """Make every way of simulating (walk, compare, the benchmarks) or generating code fail the test."""
    from amlip_qp.codegen import bench as codegen_bench
    from amlip_qp.codegen import generate
    from amlip_qp.experiments import bench_ekf, bench_harness, compare
    from amlip_qp.sim.scenarios import factory
    from amlip_qp.sweep import bench as sweep_bench

    monkeypatch.setattr(factory, "build_simulation", _simulated)
    monkeypatch.setattr(factory, "run_scenario", _simulated)
    monkeypatch.setattr(compare, "run_comparison", _simulated)
    monkeypatch.setattr(codegen_bench, "run_benchmark", _simulated)
    from amlip_qp.control.mpc import bench as mpc_bench

    monkeypatch.setattr(mpc_bench, "run_benchmark", _simulated)
    from amlip_qp.experiments import bench_mpc

    monkeypatch.setattr(bench_mpc, "run", _simulated)
    from amlip_qp.experiments import bench_qp

    monkeypatch.setattr(bench_qp, "run", _simulated)
    monkeypatch.setattr(bench_qp, "format_report", _simulated)
    monkeypatch.setattr(bench_ekf, "build_simulation", _simulated)
    monkeypatch.setattr(bench_harness, "build_simulation", _simulated)
    monkeypatch.setattr(sweep_bench, "bench_cells", _simulated)
    monkeypatch.setattr(generate, "generate_files", _simulated)
    monkeypatch.setattr(generate, "write_files", _simulated)
