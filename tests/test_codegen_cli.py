"""``amlip-qp codegen [--check] [--out DIR]`` exit codes and messages."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys

import casadi
import pytest

from amlip_qp import paths
from amlip_qp.cli import main
from amlip_qp.paths import CODEGEN_DIR, PACKAGE_DIR


def test_check_passes_on_committed_sources_in_a_subprocess(tmp_path):
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(PACKAGE_DIR.parent), os.environ.get("PYTHONPATH", "")]))
    proc = subprocess.run(
        [sys.executable, "-m", "amlip_qp.cli", "codegen", "--check"],
        capture_output=True, text=True, cwd=tmp_path, env=env, timeout=120,
    )  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.startswith("amlip_qp/codegen/generated/ is up to date: amlip_kernels.c, amlip_kernels.h equal")
    assert f"CasADi {casadi.__version__}" in proc.stdout and "installed" not in proc.stdout


def test_check_fails_naming_the_altered_file(tmp_path, capsys):
    copy = tmp_path / "codegen"
    shutil.copytree(CODEGEN_DIR, copy)
    with open(copy / "amlip_kernels.h", "ab") as fh:
        fh.write(b"/* hand edit */\n")
    assert main(["codegen", "--check", "--out", str(copy)]) == 1
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    assert "amlip_kernels.h differs" in err and "amlip_kernels.c" not in err


def test_check_fails_naming_a_missing_file(tmp_path, capsys):
    copy = tmp_path / "codegen"
    shutil.copytree(CODEGEN_DIR, copy)
    (copy / "amlip_kernels.c").unlink()
    assert main(["codegen", "--check", "--out", str(copy)]) == 1
    assert "amlip_kernels.c missing" in capsys.readouterr().err


def test_out_writes_elsewhere_then_check_passes(tmp_path, capsys):
    out = tmp_path / "gen"
    assert main(["codegen", "--out", str(out)]) == 0
    assert "amlip_kernels.c" in capsys.readouterr().out
    for name in ("amlip_kernels.c", "amlip_kernels.h"):
        assert (out / name).read_bytes() == (CODEGEN_DIR / name).read_bytes()
    assert main(["codegen", "--check", "--out", str(out)]) == 0
    assert "up to date" in capsys.readouterr().out


def test_out_onto_a_file_is_bad_input_in_one_line(tmp_path, capsys):
    target = tmp_path / "file.txt"
    target.write_text("x")
    assert main(["codegen", "--out", str(target)]) == 2
    assert capsys.readouterr().err == (
        f"amlip-qp: error: --out {target}: is a file, not a folder; give a folder path\n"
    )
    assert target.read_text() == "x"


def test_an_unwritable_out_is_refused_before_generating(monkeypatch, capsys):
    from amlip_qp.codegen import generate

    monkeypatch.setattr(generate, "generate_files", lambda: pytest.fail("generated although --out is unwritable"))
    assert main(["codegen", "--out", "/proc/x"]) == 2
    assert capsys.readouterr().err == (
        "amlip-qp: error: --out /proc/x: cannot create the folder (No such file or directory); give a writable folder\n"
    )


def test_a_write_that_fails_after_the_check_exits_2_naming_out(tmp_path, monkeypatch, capsys):
    from amlip_qp.codegen import generate

    def disk_full(path, data):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(generate, "atomic_write", disk_full)
    out = tmp_path / "gen"
    assert main(["codegen", "--out", str(out)]) == 2
    assert capsys.readouterr().err == (
        f"amlip-qp: error: --out {out}: writing failed (No space left on device); give a writable path\n"
    )
    assert list(out.iterdir()) == []  # the folder was made by the check; nothing half-written in it


def test_the_source_checkout_is_found():
    assert paths.checkout_root() == PACKAGE_DIR.parent
    assert (paths.checkout_root() / "pyproject.toml").is_file()


def test_installed_package_refuses_to_rewrite_its_data_in_one_line(monkeypatch, capsys):
    monkeypatch.setattr(paths, "checkout_root", lambda: None)
    before = {p.name: p.stat().st_mtime_ns for p in CODEGEN_DIR.iterdir()}
    assert main(["codegen"]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1
    assert "installed package" in err and "not a source checkout" in err and "--out DIR" in err
    assert {p.name: p.stat().st_mtime_ns for p in CODEGEN_DIR.iterdir()} == before


def test_installed_package_writes_where_out_says(monkeypatch, tmp_path, capsys):
    monkeypatch.setattr(paths, "checkout_root", lambda: None)
    out = tmp_path / "gen"
    assert main(["codegen", "--out", str(out)]) == 0
    assert str(out) in capsys.readouterr().out
    for name in ("amlip_kernels.c", "amlip_kernels.h"):
        assert (out / name).read_bytes() == (CODEGEN_DIR / name).read_bytes()


def test_installed_package_with_current_data_checks_up_to_date(monkeypatch, capsys):
    monkeypatch.setattr(paths, "checkout_root", lambda: None)
    assert main(["codegen", "--check"]) == 0
    out = capsys.readouterr().out
    assert out.startswith(f"{CODEGEN_DIR}/ (an installed package, not a source checkout) is up to date")
    assert f"amlip_kernels.c, amlip_kernels.h equal a fresh generation (CasADi {casadi.__version__})" in out


def test_installed_package_with_stale_data_says_so(monkeypatch, tmp_path, capsys):
    copy = tmp_path / "generated"
    shutil.copytree(CODEGEN_DIR, copy)
    with open(copy / "amlip_kernels.c", "ab") as fh:
        fh.write(b"/* generated by another CasADi */\n")
    monkeypatch.setattr(paths, "checkout_root", lambda: None)
    monkeypatch.setattr(paths, "CODEGEN_DIR", copy)
    assert main(["codegen", "--check"]) == 1
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1
    assert f"{copy}/amlip_kernels.c differs" in err and "amlip_kernels.h" not in err
    assert "an installed package, not a source checkout" in err and "run 'amlip-qp codegen'" not in err
