"""A built wheel installs into a fresh virtual environment and works from any folder.

The package data (robot models, generated C) must travel in the wheel and be
found with importlib.resources; the installed package must know it is not a
source checkout (``amlip-qp codegen``); and a walk from the installed package
must be the same walk as from this checkout.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import zipfile
from collections.abc import Iterator
from pathlib import Path

import pytest

from amlip_qp.cli import main
from amlip_qp.sim.reports import summary

REPO = Path(__file__).resolve().parents[1]
#: Summary fields that measure the machine, not the walk.
TIMING_FIELDS = set(summary.TIMING_FIELDS)
#: Never copied into the build folder: version control, environments, build and run outputs.
NOT_SOURCES = (".git", ".venv*", "venv", "build", "dist", "out", "*.egg-info", "__pycache__", ".pytest_cache", "*.so")
WALK = ["walk", "--robot", "cassie", "--duration", "1", "--no-progress"]


def _run(cmd: list[str], cwd: Path, env: dict[str, str], timeout_s: float) -> subprocess.CompletedProcess:
    proc = subprocess.run(cmd, cwd=cwd, env=env, capture_output=True, text=True, timeout=timeout_s)
    assert proc.returncode in (0, 1, 2), f"{cmd}: exit {proc.returncode}\n{proc.stderr[-3000:]}"
    return proc


@pytest.fixture(scope="module")
def installed(tmp_path_factory) -> Iterator[tuple[Path, Path, dict[str, str]]]:
    """Build the wheel from a copy of the sources, install it into a fresh venv; yield (venv bin, cwd, env).

    The venv (about 1 GB with its dependencies) is deleted afterwards."""
    base = tmp_path_factory.mktemp("install")
    src = base / "src"
    shutil.copytree(REPO, src, ignore=shutil.ignore_patterns(*NOT_SOURCES))
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PYTHONHOME", "VIRTUAL_ENV")}
    wheels = base / "wheels"
    pip_wheel = [sys.executable, "-m", "pip", "wheel", "--no-deps", "--wheel-dir", str(wheels), str(src)]
    proc = _run(pip_wheel, base, env, 600)
    assert proc.returncode == 0, proc.stderr[-3000:]
    (wheel,) = wheels.glob("amlip_qp-*.whl")
    with zipfile.ZipFile(wheel) as zf:
        names = set(zf.namelist())
    data = {"amlip_qp/models/cassie.xml", "amlip_qp/models/rabbit.xml",
            "amlip_qp/codegen/generated/amlip_kernels.c", "amlip_qp/codegen/generated/amlip_kernels.h"}  # fmt: skip
    for folder in ("unitree_h1", "unitree_g1"):  # every file of the Unitree folders (MJCF, meshes, licence, credits)
        data |= {f"amlip_qp/models/{p.relative_to(REPO / 'amlip_qp' / 'models').as_posix()}"
                 for p in (REPO / "amlip_qp" / "models" / folder).rglob("*") if p.is_file()}  # fmt: skip
    assert data <= names, f"package data missing from the wheel: {sorted(data - names)}"
    venv = base / "venv"
    proc = _run([sys.executable, "-m", "venv", str(venv)], base, env, 300)
    assert proc.returncode == 0, proc.stderr
    bin_dir = venv / ("Scripts" if os.name == "nt" else "bin")
    # Dependencies come from pip's configured index (or its cache); --no-compile skips
    # byte-compiling about 1 GB of them, which was most of the install time.
    install = [str(bin_dir / "python"), "-m", "pip", "install", "--quiet", "--no-compile", str(wheel)]
    proc = _run(install, base, env, 900)
    assert proc.returncode == 0, proc.stderr[-3000:]
    elsewhere = base / "elsewhere"
    elsewhere.mkdir()
    yield bin_dir, elsewhere, env
    shutil.rmtree(base, ignore_errors=True)


@pytest.mark.slow
def test_the_installed_package_is_not_the_checkout(installed):
    bin_dir, cwd, env = installed
    code = "import amlip_qp.paths as p; print(p.PACKAGE_DIR); print(p.checkout_root()); print(p.MODELS_DIR.is_dir())"
    proc = _run([str(bin_dir / "python"), "-c", code], cwd, env, 120)
    package_dir, checkout, models = proc.stdout.split("\n")[:3]
    assert "site-packages" in package_dir and Path(package_dir).resolve().is_relative_to(bin_dir.parent.resolve())
    assert checkout == "None" and models == "True"


@pytest.mark.slow
def test_installed_codegen_checks_its_data_and_will_not_rewrite_it(installed):
    bin_dir, cwd, env = installed
    check = _run([str(bin_dir / "amlip-qp"), "codegen", "--check"], cwd, env, 300)
    assert check.returncode == 0, check.stderr
    assert "(an installed package, not a source checkout) is up to date" in check.stdout
    assert "site-packages" in check.stdout
    write = _run([str(bin_dir / "amlip-qp"), "codegen"], cwd, env, 300)
    assert write.returncode == 2
    assert len(write.stderr.strip().splitlines()) == 1 and "--out DIR" in write.stderr
    assert "Traceback" not in write.stderr


@pytest.mark.slow
def test_installed_walk_from_another_folder_is_the_checkout_walk(installed, tmp_path):
    bin_dir, cwd, env = installed
    proc = _run([str(bin_dir / "amlip-qp"), *WALK, "--json", "-"], cwd, env, 900)
    assert proc.returncode == 0, proc.stderr[-3000:]
    summary = json.loads(proc.stdout)
    assert summary["robot"] == "cassie" and summary["tracker"] == "qp" and summary["fell"] is False
    assert summary["sim_time_s"] == pytest.approx(1.0, abs=1e-3) and summary["steps"] >= 2
    assert max(abs(v) for v in summary["mean_velocity"]) < 0.5  # commanded 0 m/s: stepping in place
    here = tmp_path / "checkout.json"
    assert main([*WALK, "--json", str(here)]) == 0
    reference = json.loads(here.read_text())
    for key in TIMING_FIELDS:
        summary.pop(key), reference.pop(key)
    assert summary == reference
