"""How ``amlip-qp`` reports an error: exactly one line on stderr in a real process, and an OS error
while writing (after the run) or anywhere else as exit status 2 naming the path."""

from __future__ import annotations

import subprocess
import sys

import pytest

from amlip_qp.control import registry
from cli_bad_input_support import run_main
from stand_ins import ZeroTracker


@pytest.mark.parametrize(
    "argv, stderr",
    [
        (
            ["walk", "--json", "/proc/x"],
            "amlip-qp: error: --json /proc/x: cannot write there (No such file or directory); give a writable path\n",
        ),
        (
            ["walk", "--duration", "1e12"],
            "amlip-qp: error: duration 1e+12 s is above cassie's bound 600 s "
            "(CommandBounds.duration_max_s in amlip_qp.profiles: the per-tick log is kept in memory)\n",
        ),
    ],
)
def test_bad_input_in_a_subprocess_prints_exactly_one_line(argv, stderr):
    proc = subprocess.run([sys.executable, "-m", "amlip_qp.cli", *argv], capture_output=True, text=True, timeout=120)
    assert (proc.returncode, proc.stderr, proc.stdout) == (2, stderr, "")


@pytest.mark.parametrize("option, name", [("--json", "s.json"), ("--log", "run.npz"), ("--plot", "fig.png")])
def test_an_os_error_while_writing_after_the_run_exits_2(option, name, tmp_path, monkeypatch, capsys):
    """A link to ``/dev/full`` opens, then every write fails (ENOSPC): the early check passes, the write does not."""
    path = tmp_path / name
    path.symlink_to("/dev/full")
    monkeypatch.setattr(registry, "make_tracker", lambda name, robot: ZeroTracker(robot))
    code, out, err = run_main(["walk", "--robot", "rabbit", "--duration", "0.01", option, str(path)], capsys)
    assert code == 2
    assert err == f"amlip-qp: error: {option} {path}: writing failed (No space left on device); give a writable path\n"


def test_any_other_os_error_exits_2_naming_the_path(monkeypatch, capsys):
    from amlip_qp.experiments import walk as sim_cli

    def disk_full(args):
        raise OSError(28, "No space left on device", "/data/run.npz")

    monkeypatch.setattr(sim_cli, "run_walk", disk_full)
    code, out, err = run_main(["walk"], capsys)
    assert code == 2
    assert (
        err
        == "amlip-qp: error: /data/run.npz: No space left on device; check the path, its folder and the free space\n"
    )
