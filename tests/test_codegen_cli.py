"""``amlip-qp codegen [--check] [--out DIR]`` exit codes and messages."""

from __future__ import annotations

import shutil
import subprocess
import sys

from amlip_qp.cli import main
from amlip_qp.paths import CODEGEN_DIR, REPO_ROOT


def test_check_passes_on_committed_sources_in_a_subprocess():
    proc = subprocess.run(
        [sys.executable, "-m", "amlip_qp.cli", "codegen", "--check"],
        capture_output=True, text=True, cwd=REPO_ROOT, timeout=120,
    )  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    assert "up to date" in proc.stdout


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


def test_out_onto_a_file_is_a_readable_error(tmp_path, capsys):
    target = tmp_path / "file.txt"
    target.write_text("x")
    assert main(["codegen", "--out", str(target)]) == 1
    assert "not a folder" in capsys.readouterr().err
