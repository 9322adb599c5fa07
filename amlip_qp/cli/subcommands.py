"""The ``view``, ``compare``, ``sweep`` and ``check-robot`` subcommands' options (their handlers live in the
modules they name; ``walk``'s and the options it shares with them are in :mod:`amlip_qp.cli.walk_options`)."""

from __future__ import annotations

import argparse

from amlip_qp.cli import bounds as B
from amlip_qp.cli.parsing import float_in, handler, int_in, name_list, positive_float
from amlip_qp.cli.robot_option import robot_list, robot_name_or_path
from amlip_qp.cli.walk_options import (
    SEED,
    SEED_HELP,
    add_command_options,
    add_plant_options,
    add_shaping_options,
    add_walk,
)
from amlip_qp.profiles import DEFAULT_ROBOT, ROBOT_NAMES
from amlip_qp.sim.loop.live_keys import keys_help
from amlip_qp.sim.scenarios.options import ESTIMATORS, PLANNERS, SENSORS, TRACKERS

__all__ = [
    "ESTIMATORS",
    "PLANNERS",
    "SENSORS",
    "TRACKERS",
    "add_check_robot",
    "add_compare",
    "add_sweep",
    "add_view",
    "add_walk",
]

_WORKERS = int_in(1, B.MAX_WORKERS, "number of worker processes")
_WORKERS_HELP = f"1 to {B.MAX_WORKERS} (each holds its own models and log, about 0.17 GB)"


def add_view(sub) -> None:
    p = sub.add_parser(
        "view",
        help="watch and drive the closed loop live in MuJoCo's viewer (keys steer, the mouse pushes)",
        formatter_class=argparse.RawDescriptionHelpFormatter,
        description="Run the closed loop live in MuJoCo's viewer, no faster than real time. The keys\n"
        "change the command (inside the robot's bounds, amlip_qp.profiles.CommandBounds;\n"
        "the controller's command shaping ramps it), the mouse pushes the robot with\n"
        "MuJoCo's own perturbation. The overlay shows the measured speed (heading frame),\n"
        "the command, the step count and the real-time factor. It needs a display.\n\n"
        f"keys:\n{keys_help()}\n\n"
        "Exit status: 0 the window closed (or --duration ran out) with the robot up,\n"
        "1 with it down, 2 bad input or no display ($DISPLAY), before anything runs.",
    )
    p.add_argument(
        "--robot",
        type=robot_name_or_path,
        metavar="NAME|PATH",
        default=None,
        help=f"a bundled robot ({', '.join(ROBOT_NAMES)}) or a robot profile file (.toml); default {DEFAULT_ROBOT}",
    )
    p.add_argument("--tracker", choices=TRACKERS, default="qp", help="tracker (default qp)")
    add_command_options(p, speed_profile=False)
    add_shaping_options(p)
    p.add_argument("--seed", type=SEED, default=0, help=SEED_HELP)
    p.add_argument("--noise", action="store_true", help="add Gaussian sensor noise (default: exact measurements)")
    add_plant_options(p)
    p.add_argument(
        "--duration",
        dest="view_duration_s",
        type=positive_float,
        metavar="S",
        default=None,
        help="close the viewer after S simulated seconds (default: when its window is closed)",
    )
    p.add_argument(
        "--script",
        metavar="PATH",
        default=None,
        help="press keys at simulated times: a text file of 'T KEY' lines (s, a key name above, e.g. '2 up')",
    )
    p.add_argument(
        "--json", metavar="PATH", default=None, help="write the session's summary as JSON to PATH, or '-' for stdout"
    )
    p.set_defaults(func=handler("amlip_qp.experiments.view:run_view"))


def add_compare(sub) -> None:
    p = sub.add_parser(
        "compare",
        help="compare the PBC and QP trackers on the same scenarios and seed",
        description="Run both trackers on the same scenarios with the same seed and print one table row per "
        "robot and tracker (see docs/SUMMARY_SCHEMA.md for the definitions).",
    )
    p.add_argument(
        "--robots",
        type=robot_list,
        default=None,
        metavar="R1,R2",
        help="robots: bundled names or profile files (default: every bundled robot whose profile has "
        "a [compare] table)",
    )
    p.add_argument(
        "--trackers",
        type=name_list(TRACKERS),
        default=list(TRACKERS),
        metavar="T1,T2",
        help="trackers (default pbc,qp)",
    )
    p.add_argument(
        "--planners",
        type=name_list(PLANNERS),
        default=["one-step"],
        metavar="P1,P2",
        help="foot-placement planners, one row per tracker and planner: one-step, mpc (default one-step; "
        "each planner added doubles the run time, docs/COMMANDS.md)",
    )
    p.add_argument(
        "--scenario",
        action="append",
        default=[],
        metavar="NAME",
        help="nominal scenario of a robot (replaces its default; repeatable, one per robot)",
    )
    p.add_argument(
        "--quick",
        action="store_true",
        help="short runs and 1 bisection iteration (a smoke test, a few minutes at most)",
    )
    p.add_argument(
        "--push-iterations",
        type=int_in(0, B.MAX_BISECTION_ITERATIONS, "number of iterations"),
        default=None,
        metavar="N",
        help=f"bisection iterations per push direction, at most {B.MAX_BISECTION_ITERATIONS} "
        "(each halves the interval and is one more walk)",
    )
    p.add_argument("--no-ramp", action="store_true", help="skip the speed-ramp test")
    p.add_argument("--no-push", action="store_true", help="skip the push tests")
    p.add_argument("--seed", type=SEED, default=0, help=SEED_HELP)
    p.add_argument("--noise", action="store_true", help="add Gaussian sensor noise")
    add_plant_options(p)
    p.add_argument(
        "--jobs", type=_WORKERS, default=2, metavar="N", help=f"parallel worker processes, {_WORKERS_HELP} (default 2)"
    )
    p.add_argument("--json", metavar="PATH", default=None, help="write the table as JSON to PATH, or '-' for stdout")
    p.add_argument(
        "--plot",
        metavar="PATH",
        default="out/compare.png",
        help="comparison figure, .png, .pdf or .svg (default out/compare.png; folder created)",
    )
    p.add_argument("--no-plot", action="store_true", help="do not write the figure")
    p.set_defaults(func=handler("amlip_qp.experiments.compare:main"))


def add_sweep(sub) -> None:
    p = sub.add_parser(
        "sweep",
        help="run many walks over a grid or a random sample of walk options (a robustness map)",
        description="Run one deterministic walk per cell of a grid (or random sample) of walk options and "
        "push parameters, locally on a process pool or on Ray; write results.csv, summary.json and figures to "
        "--out. Finished cells in --out are skipped (resume); a cell whose walk raises is recorded in the "
        "error column and run again next time. Exit status: 0 done, 1 some cell failed, 2 bad input (nothing "
        "written).",
    )
    p.add_argument("spec", nargs="?", metavar="SPEC", default=None, help="a TOML sweep spec (see examples/sweeps/)")
    p.add_argument(
        "--grid",
        action="append",
        default=[],
        metavar="NAME=V1,V2",
        help="sweep a walk option (e.g. tracker=pbc,qp, vx=0.5,1.0) or push parameter; repeatable",
    )
    p.add_argument(
        "--set", action="append", default=[], metavar="NAME=V", help="hold a parameter in every cell; repeatable"
    )
    p.add_argument(
        "--duration",
        type=float_in(B.MIN_DURATION_S, B.MAX_DURATION_S, "s", low_open=False),
        metavar="S",
        default=None,
        help=f"simulated time per walk, s, {B.MIN_DURATION_S:g} (a control tick) to {B.MAX_DURATION_S:g} "
        "(the robots' CommandBounds.duration_max_s)",
    )
    p.add_argument("--metrics", metavar="M1,M2", default=None, help="the metric columns (default: the spec's)")
    p.add_argument(
        "--bisect",
        metavar="NAME=LOW:HIGH:N",
        default=None,
        help="per cell, the largest value of NAME survived, by N bisection steps (e.g. push_impulse_Ns=0:60:5)",
    )
    p.add_argument("--out", metavar="DIR", required=True, help="output folder (created; a finished sweep resumes)")
    where = p.add_mutually_exclusive_group()
    where.add_argument(
        "--workers",
        type=_WORKERS,
        default=None,
        metavar="N",
        help=f"local worker processes, {_WORKERS_HELP} (default: one per core)",
    )
    where.add_argument(
        "--ray",
        nargs="?",
        const="",
        default=None,
        metavar="ADDRESS",
        help="run the cells as Ray tasks: on the cluster at ADDRESS (HOST:PORT, ray://HOST:PORT, auto), "
        "or on a new local one without ADDRESS (needs the 'ray' extra)",
    )
    p.add_argument("--no-figures", action="store_true", help="do not draw the figures")
    p.add_argument("--no-progress", action="store_true", help="no progress bar on stderr")
    p.set_defaults(func=handler("amlip_qp.sweep.cli:run_sweep"))


def add_check_robot(sub) -> None:
    p = sub.add_parser(
        "check-robot",
        help="conformance checks of a robot profile: its two models agree, its stand pose, one tick per "
        "tracker, a walk in place",
        description="Check a robot profile, one line per check with its measured number: MuJoCo and Pinocchio "
        "give the same mass and place every site and body alike; the joint roles name joints of the model; "
        "the stand pose puts the feet on the floor; the output Jacobian has full rank at the stand pose; one "
        "QP and one PBC tick at the stand pose solve with torques inside the limits (a tracker the profile "
        "has no configuration for is skipped); a 3 s walk in place with the QP tracker does not fall "
        "(docs/NEW_ROBOT.md). Exit status: 0 no check failed, 1 a check failed (every check still runs), "
        "2 bad input.",
    )
    p.add_argument(
        "robot",
        type=robot_name_or_path,
        metavar="NAME|PATH",
        help=f"a bundled robot ({', '.join(ROBOT_NAMES)}) or a robot profile file (.toml)",
    )
    p.add_argument("--no-walk", action="store_true", help="skip the walk in place (faster)")
    p.add_argument("--json", metavar="FILE", default=None, help="write the checks as JSON to FILE, or '-' for stdout")
    p.set_defaults(func=handler("amlip_qp.experiments.conformance_cli:run_check_robot"))
