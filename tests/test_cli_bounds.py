"""amlip_qp/cli/bounds.py: the command line's bounds equal the library's, and the options use them."""

from __future__ import annotations

import mujoco

from amlip_qp.cli import bounds as B
from amlip_qp.cli import build_parser
from amlip_qp.experiments import robustness
from amlip_qp.profiles import CommandBounds, get_profile
from amlip_qp.sim.loop import run_types
from amlip_qp.sim.reports import video
from amlip_qp.sim.world.plant_modifiers import MIN_FRICTION


def test_the_bounds_repeated_for_a_light_help_equal_the_librarys():
    assert B.MAX_BISECTION_ITERATIONS == robustness.MAX_BISECTION_ITERATIONS == 20
    assert B.MAX_VIDEO_FPS == video.MAX_VIDEO_FPS == 240.0 and video.MAX_GIF_FPS == 100.0
    assert B.MIN_DURATION_S == run_types.CONTROL_DT_S == 0.0005
    assert B.MAX_DURATION_S == CommandBounds.duration_max_s == 600.0
    for robot in ("cassie", "rabbit"):
        assert get_profile(robot).bounds.duration_max_s == B.MAX_DURATION_S
    assert MIN_FRICTION == mujoco.mjMINMU == 1e-5


def test_the_help_states_each_bound():
    parser = build_parser()
    helps = {
        ("walk",): [
            "at most 100",
            "0 < FPS <= 240",
            "<= 100 for a .gif",
            "0 to 4294967295",
            "0.1 <= S <= 10",
            "0 <= S <= 10",
            "1e-05 <= MU <= 10",
            "0 <= TICKS <= 100",
        ],
        ("compare",): ["at most 20", "1 to 64"],
        ("sweep",): ["0.0005 (a control tick) to 600", "1 to 64"],
        ("bench", "codegen"): ["at most 1000000"],
        ("bench", "qp"): ["at most 20000"],
        ("bench", "ekf"): ["0.0005 (a control tick) to 600"],
        ("bench", "harness"): ["0.0005 (a control tick) to 600", "at most 20"],
        ("bench", "sweep"): ["at most 1000", "0.0005 (a control tick) to 600", "at most 20"],
    }
    import contextlib
    import io

    for command, pieces in helps.items():
        out = io.StringIO()
        with contextlib.redirect_stdout(out), contextlib.suppress(SystemExit):
            parser.parse_args([*command, "--help"])
        text = " ".join(out.getvalue().split())
        for piece in pieces:
            assert piece in text, (command, piece)
