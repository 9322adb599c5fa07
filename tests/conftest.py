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
