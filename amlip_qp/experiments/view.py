"""``amlip-qp view``: the closed loop live in MuJoCo's own viewer, driven by keys and pushed with the mouse.

The viewer glue only: MuJoCo's passive viewer (``mujoco.viewer.launch_passive``)
shows the plant's ``MjData`` and hands its key presses to a
:class:`~amlip_qp.sim.loop.live.LiveLoop`, which does the rest (the command from the
keys, the ticks in real time, the overlay line). Each frame: ``sync`` (the
viewer draws the state and writes the mouse's push, MuJoCo's perturbation of
the selected body, into ``MjData.xfrc_applied``; a reset of its own is seen by
the loop), the loop's :meth:`~amlip_qp.sim.loop.live.LiveLoop.frame`, the overlay
now and then, and a sleep to the next frame.

Exit status: 0 when the window closed (or ``--duration`` ran out) with the
robot up, 1 with the robot down, 2 on bad input or without a display (one
line, before anything is simulated).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import threading
import time
from pathlib import Path

from amlip_qp.exceptions import InputError
from amlip_qp.experiments.walk import check_plant, scenario_from_args
from amlip_qp.output_paths import check_output_path, writing
from amlip_qp.profiles import get_profile
from amlip_qp.sim.loop.live import LiveCommand, LiveLoop
from amlip_qp.sim.loop.live_keys import parse_key_script
from amlip_qp.sim.loop.run_types import SensorNoise
from amlip_qp.sim.scenarios import factory
from amlip_qp.sim.scenarios.scenarios import held_warnings, release_warnings

#: The viewer's frame period, s (the loop steps the ticks of one frame between two syncs).
FRAME_S = 1.0 / 60.0
#: How often the overlay line is handed to the viewer, s (each hand-over may wait for a drawn frame).
OVERLAY_PERIOD_S = 0.25


def check_display() -> None:
    """Refuse, in one line, to open the viewer where no window can be opened.

    Raises:
        InputError: No ``$DISPLAY`` (nor ``$WAYLAND_DISPLAY``), the ``glfw`` package is
            missing, or GLFW cannot reach the display or make an OpenGL window there.
    """
    if not os.environ.get("DISPLAY") and not os.environ.get("WAYLAND_DISPLAY"):
        raise InputError(
            "view opens a window: $DISPLAY is not set (run it on a desktop, over ssh -X, or under xvfb-run)"
        )
    try:
        import glfw
    except ImportError:
        raise InputError("view needs the glfw package for MuJoCo's viewer: pip install glfw") from None
    reporting, glfw.ERROR_REPORTING = glfw.ERROR_REPORTING, "ignore"
    try:
        if not glfw.init():
            raise InputError(f"view cannot reach the display {_display()}: {_glfw_error(glfw)}")
        try:
            glfw.window_hint(glfw.VISIBLE, glfw.FALSE)
            window = glfw.create_window(64, 64, "amlip-qp view", None, None)
            if not window:
                raise InputError(f"view cannot open an OpenGL window on {_display()}: {_glfw_error(glfw)}")
            glfw.destroy_window(window)
            glfw.default_window_hints()
        finally:
            glfw.terminate()
    finally:
        glfw.ERROR_REPORTING = reporting


def _display() -> str:
    return os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY") or "?"


def _glfw_error(glfw) -> str:
    code, description = glfw.get_error()
    text = description.decode() if isinstance(description, bytes) else str(description or "")
    return text or f"GLFW error {code}"


def read_key_script(path: str) -> tuple[tuple[float, int], ...]:
    """The key presses of ``--script PATH`` (:func:`~amlip_qp.sim.loop.live_keys.parse_key_script`).

    Raises:
        InputError: The file cannot be read, or a line is not ``T KEY``.
    """
    try:
        text = Path(path).read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        why = exc.strerror if isinstance(exc, OSError) and exc.strerror else str(exc)
        raise InputError(f"--script {path}: cannot read it ({why}); give a text file of 'T KEY' lines") from None
    return parse_key_script(text, f"--script {path}")


def show(live: LiveLoop, clock=time.perf_counter) -> None:
    """Run ``live`` in MuJoCo's passive viewer until its window closes or the loop has :attr:`~LiveLoop.finished`."""
    import mujoco
    import mujoco.viewer

    sim = live.sim
    before = set(threading.enumerate())
    viewer = mujoco.viewer.launch_passive(
        sim.model, sim.data, key_callback=live.key, show_left_ui=False, show_right_ui=False
    )
    viewer_threads = set(threading.enumerate()) - before
    try:
        with viewer.lock():
            viewer.cam.type = mujoco.mjtCamera.mjCAMERA_TRACKING
            viewer.cam.trackbodyid = sim.plant.base_body_id
            viewer.cam.distance, viewer.cam.azimuth, viewer.cam.elevation = 3.0, 90.0, -15.0
        next_overlay = clock()
        while viewer.is_running():
            frame_start = clock()
            viewer.sync()
            live.notice_plant()
            live.frame(clock())
            if clock() >= next_overlay:
                viewer.set_texts((None, None, live.overlay(), None))
                next_overlay = clock() + OVERLAY_PERIOD_S
            if live.finished:
                break
            time.sleep(max(0.0, frame_start + FRAME_S - clock()))
    finally:
        viewer.close()
        for thread in viewer_threads:  # the viewer's window thread: let it finish before the interpreter does
            thread.join(timeout=10.0)


def run_view(args: argparse.Namespace) -> int:
    """``amlip-qp view``: the options as ``walk``'s, the display checked, then the live viewer and a summary."""
    with held_warnings() as unverified:  # said once the input is known good
        scenario = scenario_from_args(args)
        profile = get_profile(scenario.robot)
        profile.check_supported(args.tracker)
        check_output_path("--json", args.json)
        script = () if args.script is None else read_key_script(args.script)
        check_display()
        check_plant(scenario)
    release_warnings(unverified)
    sim = factory.build_simulation(scenario, args.tracker, seed=args.seed, noise=SensorNoise() if args.noise else None)
    command = LiveCommand(
        scenario.command(0.0), profile.bounds, scenario.vx(0.0), scenario.vy_mps, math.degrees(scenario.turn_rate_radps)
    )
    live = LiveLoop(sim, command, script=script, duration_s=args.view_duration_s)
    show(live)
    summary = live.summary()
    if args.json is not None:
        text = json.dumps(summary, indent=2)
        if args.json == "-":
            sys.stdout.write(text + "\n")
        else:
            with writing("--json", args.json), open(args.json, "w") as fh:
                fh.write(text + "\n")
    if args.json != "-":
        c = summary["command"]
        sys.stdout.write(
            f"{summary['robot']}/{summary['tracker']} {'FELL' if live.fell else 'up'}: "
            f"{summary['total_sim_time_s']:.2f} s simulated, command {c['vx_mps']:+.2f} {c['vy_mps']:+.2f} m/s "
            f"{c['turn_rate_degps']:+.0f} deg/s, {summary['distance_m']:.2f} m from the last start, "
            f"{summary['falls']} falls, {summary['resets']} resets\n"
        )
    return 1 if live.fell else 0
