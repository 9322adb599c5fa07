"""Tests of ``amlip-qp view`` (experiments.view): refused without a display; MuJoCo's viewer on a virtual X server.

The slow tests open the viewer for real on an Xvfb server of their own and drive
it with keys: from a ``--script`` (handed to the same key handler as the
viewer's ``key_callback``) and as real X key presses (``xdotool``), which go
through GLFW and MuJoCo's viewer to the loop. They need ``Xvfb`` and
``xdotool`` (``.ci/run`` installs them) and fail, not skip, without them.
"""

from __future__ import annotations

import contextlib
import json
import os
import select
import shutil
import subprocess
import sys
import time

import pytest

from amlip_qp.cli import main

#: The virtual screen, and what the viewer's process gets beside it: llvmpipe (Mesa's software
#: OpenGL) draws in the drawing thread alone, not on a thread per core beside the simulation.
SCREEN = "1280x720x24"
VIEW_ENV = {"LP_NUM_THREADS": "0"}


def _no_simulation(*args, **kwargs):
    raise AssertionError("view built a simulation although it cannot show it")


def test_view_without_a_display_exits_2_in_one_line_before_anything_runs(monkeypatch, capsys):
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    monkeypatch.setattr("amlip_qp.sim.scenarios.factory.build_simulation", _no_simulation)
    assert main(["view", "--vx", "0.5"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "view opens a window: $DISPLAY is not set" in err and "xvfb-run" in err


def test_view_names_a_display_it_cannot_reach(monkeypatch, capsys):
    monkeypatch.setenv("DISPLAY", ":987")  # no X server there
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    monkeypatch.setattr("amlip_qp.sim.scenarios.factory.build_simulation", _no_simulation)
    assert main(["view"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "view cannot reach the display :987" in err


def test_view_checks_its_options_before_the_display(monkeypatch, capsys, tmp_path):
    monkeypatch.delenv("DISPLAY", raising=False)
    assert main(["view", "--vx", "9"]) == 2
    assert "outside cassie's bounds" in capsys.readouterr().err
    script = tmp_path / "keys.txt"
    script.write_text("1 up\n2 jump\n")
    assert main(["view", "--script", str(script)]) == 2
    assert f"--script {script} line 2: unknown key 'jump'" in capsys.readouterr().err


def _need(tool: str, package: str) -> str:
    path = shutil.which(tool)
    if path is None:
        pytest.fail(f"{tool} is missing: apt-get install {package} (.ci/run installs it)")
    return path


@contextlib.contextmanager
def _xvfb():
    """A virtual X server of this test's own; yields its display name (``:N``)."""
    read_fd, write_fd = os.pipe()
    server = subprocess.Popen(
        [_need("Xvfb", "xvfb"), "-displayfd", str(write_fd), "-screen", "0", SCREEN, "-nolisten", "tcp"],
        pass_fds=(write_fd,),
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    os.close(write_fd)
    try:
        ready, _, _ = select.select([read_fd], [], [], 30.0)
        number = os.read(read_fd, 64).decode().strip() if ready else ""
        assert number.isdigit(), f"Xvfb gave no display number within 30 s (exit status {server.poll()})"
        yield f":{number}"
    finally:
        os.close(read_fd)
        server.terminate()
        server.wait(timeout=30)


def _view(display: str, *options: str) -> subprocess.Popen:
    env = {**os.environ, **VIEW_ENV, "DISPLAY": display}
    env.pop("WAYLAND_DISPLAY", None)
    command = [sys.executable, "-m", "amlip_qp.cli", "view", *options]
    return subprocess.Popen(command, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def _finish(proc: subprocess.Popen, timeout_s: float = 600.0) -> str:
    out, err = proc.communicate(timeout=timeout_s)
    assert proc.returncode == 0, f"view exited {proc.returncode}: {err[-2000:]}"
    return out


@pytest.mark.slow
def test_view_walks_cassie_at_the_command_its_key_script_sets(tmp_path):
    keys = tmp_path / "keys.txt"
    keys.write_text("0.5 up\n0.6 up\n0.7 up\n0.8 up\n0.9 up\n1.5 left\n2.5 right\n3 home\n")
    out = tmp_path / "view.json"
    with _xvfb() as display:
        proc = _view(display, "--robot", "cassie", "--duration", "5", "--script", str(keys), "--json", str(out))
        stdout = _finish(proc)
    s = json.loads(out.read_text())
    assert s["command"] == {"vx_mps": 0.5, "vy_mps": 0.05, "turn_rate_degps": 0.0}
    assert s["shaped_command"]["vx_mps"] == pytest.approx(0.5, abs=1e-12)
    assert (s["keys"], s["resets"], s["falls"], s["fell"]) == (8, 0, 0, False)
    assert s["total_sim_time_s"] == 5.0 and s["sim_time_s"] == pytest.approx(5.0, abs=1e-9)  # --duration: 10000 ticks
    assert 1.2 < s["distance_m"] < 3.0  # 0.5 m/s from about 2 s on, after the ramp
    assert s["steps"] >= 12 and s["frames"] > 10  # it walked, and through the viewer's frames
    assert 0.0 < s["realtime_factor"] <= 1.0 + 1e-6  # never faster than the wall clock
    assert stdout.startswith("cassie/qp up: 5.00 s simulated, command +0.50 +0.05 m/s +0 deg/s")


@pytest.mark.slow
def test_view_takes_real_key_presses_and_mouse_pushes_through_mujocos_viewer(tmp_path):
    xdotool = _need("xdotool", "xdotool")
    out = tmp_path / "view.json"
    with _xvfb() as display:
        env = {**os.environ, "DISPLAY": display}

        def x(*args: str) -> str:
            return subprocess.run(
                [xdotool, *args], env=env, check=True, capture_output=True, text=True, timeout=300
            ).stdout

        proc = _view(display, "--robot", "cassie", "--duration", "8", "--json", str(out))
        try:
            window = x("search", "--sync", "--onlyvisible", "--name", "MuJoCo").split()[0]  # once the loop is built
            x("windowfocus", "--sync", window)
            time.sleep(1.0)  # the window at its size, the loop's tracking camera on the robot
            geometry = dict(line.split("=") for line in x("getwindowgeometry", "--shell", window).split())
            # the tracking camera looks at the pelvis: the window's middle, a little above it its top
            cx, cy = int(geometry["WIDTH"]) // 2, int(geometry["HEIGHT"]) // 2 - 30
            x("mousemove", "--window", window, str(cx), str(cy))
            time.sleep(0.5)
            x("key", "--delay", "150", "Up", "Up", "Up", "Left")
            for _ in range(2):  # select the body under the mouse (twice: the same body, should a frame lag)
                x("click", "--repeat", "2", "--delay", "60", "1")
                time.sleep(0.3)
            x("keydown", "ctrl", "mousedown", "3")  # Ctrl + right-drag: push it
            for _ in range(10):
                x("mousemove_relative", "--", "6", "0")
                time.sleep(0.03)
            time.sleep(0.3)
            x("mouseup", "3", "keyup", "ctrl")
        except BaseException:
            proc.kill()
            raise
        _finish(proc)
    s = json.loads(out.read_text())
    assert s["keys"] == 4 and s["command"] == {"vx_mps": 0.3, "vy_mps": 0.0, "turn_rate_degps": 10.0}
    assert s["push_frames"] > 0 and s["max_push_N"] > 10.0  # the mouse's push reached MjData.xfrc_applied
    assert (s["resets"], s["falls"]) == (0, 0)
    assert s["distance_m"] > 0.5 and s["steps"] >= 12
