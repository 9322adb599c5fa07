"""The ``walk``, ``view``, ``compare``, ``sweep`` and ``check-robot`` subcommands' options (their handlers
live in the modules they name)."""

from __future__ import annotations

import argparse

from amlip_qp.cli import bounds as B
from amlip_qp.cli.parsing import (
    finite_float,
    float_in,
    handler,
    int_in,
    name_list,
    non_negative_float,
    parse_push_spec,
    positive_float,
)
from amlip_qp.cli.robot_option import robot_list, robot_name_or_path
from amlip_qp.profiles import ROBOT_NAMES
from amlip_qp.sim.loop.live_keys import keys_help

#: Trackers of ``walk`` and ``compare`` (kept here so ``--help`` needs no heavy import; the
#: robots are the profiles' :data:`~amlip_qp.profiles.ROBOT_NAMES`, a light import).
TRACKERS = ("pbc", "qp")
#: ``walk --planner``: amlip_qp.control.walking.planners.PLANNERS (the CLI stays light; tested equal).
PLANNERS = ("one-step", "mpc")
#: Sensor models and base estimators (the same as ``amlip_qp.sim.sensing.sensors.SENSOR_MODELS`` and
#: ``amlip_qp.sim.scenarios.factory.ESTIMATORS``, checked by the tests).
SENSORS = ("ideal", "robot")
ESTIMATORS = ("truth", "ekf")

_SEED = int_in(0, B.MAX_SEED, "seed")
_SEED_HELP = f"seed of the sensor noise, 0 to {B.MAX_SEED} (32 bits) (default 0)"
_WORKERS = int_in(1, B.MAX_WORKERS, "number of worker processes")
_WORKERS_HELP = f"1 to {B.MAX_WORKERS} (each holds its own models and log, about 0.17 GB)"


def add_plant_options(p: argparse.ArgumentParser) -> None:
    """``--plant``, ``--sensors``, ``--estimator``, ``--terrain`` and plant modifiers of ``walk`` and ``compare``."""
    p.add_argument(
        "--plant",
        metavar="NAME|PATH",
        default=None,
        help="the MuJoCo plant: a plant name of the robot (e.g. cassie-closed-chain) or an MJCF file with the "
        "robot's actuators, measured joints and base body (default: the robot's own model)",
    )
    p.add_argument(
        "--sensors",
        choices=SENSORS,
        default=None,
        help="ideal: the exact state; robot: IMU, encoders and contact switches with noise, no base state "
        "(default: the scenario's, ideal)",
    )
    p.add_argument(
        "--estimator",
        choices=ESTIMATORS,
        default=None,
        help="base state: truth (the simulator's) or ekf (contact-aided invariant EKF) "
        "(default: the scenario's, truth)",
    )
    p.add_argument(
        "--terrain",
        metavar="SPEC",
        default=None,
        help="ground in the plant: flat (default), slope:DEG (|DEG| < 45, up for DEG > 0), "
        "stairs:RISE_M:RUN_M[:N] (N steps up, a landing, N down; N=4), rough:AMPLITUDE_M[:SEED], "
        "waves:HEIGHT_M:WAVELENGTH_M[:HEADING_DEG] (ridges at HEADING_DEG to the path, default 0: across it; "
        "90: along it, the robot in a valley), hfield:PATH.png:SIZE_X_M:SIZE_Y_M:HEIGHT_M (gray: black 0, "
        "white HEIGHT_M); slopes, stairs and waves at heading 0 start 1 m ahead of the robot",
    )
    p.add_argument(
        "--terrain-aware",
        action=argparse.BooleanOptionalAction,
        default=None,
        help="give the controller the terrain's height function (swing target height and the placement law's "
        "height difference from it); --no-terrain-aware: blind, the ground is felt by contact (default: the "
        "scenario's, else blind)",
    )
    p.add_argument(
        "--clearance",
        type=non_negative_float,
        metavar="M",
        default=None,
        help="swing-foot clearance at mid-step, m (default: the scenario's gait's, Cassie 0.10)",
    )
    m = p.add_argument_group("plant modifiers (model mismatch; the controller keeps its own model)")
    m.add_argument(
        "--plant-mass-scale",
        type=float,
        default=None,
        metavar="S",
        help="scale the mass and inertia of every plant body (0.1 <= S <= 10: at 0.01 the closed-chain "
        "plant's simulation diverges)",
    )
    m.add_argument(
        "--payload",
        default=None,
        metavar="KG[@X,Y,Z]",
        help="weld a 0.2 x 0.15 x 0.1 m box of KG kg to the base at (X, Y, Z) m in the base frame "
        "(default: at its origin)",
    )
    m.add_argument(
        "--plant-spring-scale",
        type=float,
        default=None,
        metavar="S",
        help="scale every joint and tendon spring (0 <= S <= 10: 0 removes them; at 10 Cassie's springs are "
        "near rigid, and MuJoCo's explicit springs diverge from 200 x at the 0.5 ms step)",
    )
    m.add_argument(
        "--friction",
        type=float,
        default=None,
        metavar="MU",
        help="sliding friction of every foot-floor contact (1e-05 <= MU <= 10: MuJoCo raises smaller "
        "coefficients to its mjMINMU = 1e-5)",
    )
    m.add_argument(
        "--actuator-delay",
        type=int,
        default=None,
        metavar="TICKS",
        help="delay the actuator commands by TICKS control ticks (0.5 ms each; 0 <= TICKS <= 100)",
    )


def add_command_options(p: argparse.ArgumentParser, speed_profile: bool) -> None:
    """``--vx`` (or ``--speed-profile`` instead, with ``speed_profile``; without, the starting command), ``--vy``,
    ``--turn-rate``."""
    speed = p.add_mutually_exclusive_group() if speed_profile else p
    what = "" if speed_profile else "starting "
    speed.add_argument(
        "--vx",
        type=finite_float,
        metavar="M/S",
        default=None,
        help=f"{'constant' if speed_profile else 'starting'} forward speed, m/s (default 0)",
    )
    if speed_profile:
        speed.add_argument(
            "--speed-profile",
            metavar="T:V,...",
            default=None,
            help="piecewise-linear forward speed, e.g. '0:0,5:2.1' (s:m/s)",
        )
    p.add_argument(
        "--vy", type=finite_float, metavar="M/S", default=None, help=f"{what}lateral speed, m/s (left positive)"
    )
    p.add_argument(
        "--turn-rate", type=finite_float, metavar="DEG/S", default=None, help=f"{what}turn rate, deg/s (left positive)"
    )


def add_shaping_options(p: argparse.ArgumentParser) -> None:
    """``--accel-limit`` or ``--no-command-shaping``: the rate limit of the command before the planner."""
    shaping = p.add_mutually_exclusive_group()
    shaping.add_argument(
        "--accel-limit",
        type=float_in(0.0, B.MAX_ACCEL_LIMIT_MPS2, "m/s^2"),
        metavar="M/S2",
        default=None,
        help="rate limit of the forward and lateral speed commands before the planner, m/s^2, at most "
        f"{B.MAX_ACCEL_LIMIT_MPS2:g} (faster is no limit: --no-command-shaping) "
        "(default: the robot's, amlip_qp.profiles.CommandShaping)",
    )
    shaping.add_argument(
        "--no-command-shaping",
        action="store_true",
        help="give the planner the raw command (no rate limit, no step-length cap)",
    )


def add_walk(sub) -> None:
    p = sub.add_parser(
        "walk",
        help="simulate one walk in MuJoCo and summarise it",
        description="Simulate one walk in MuJoCo with the PBC or QP tracker and print a summary. "
        "Speeds, the turn rate, the duration and pushes must lie inside the robot's physical bounds "
        "(amlip_qp.profiles.CommandBounds); output paths are checked before the run. "
        "Exit status: 0 finished standing, 1 the robot fell (outputs are still written), 2 bad input.",
    )
    p.add_argument(
        "--robot",
        type=robot_name_or_path,
        metavar="NAME|PATH",
        default=None,
        help=f"a bundled robot ({', '.join(ROBOT_NAMES)}) or a robot profile file (.toml); "
        "default cassie, or the scenario's",
    )
    p.add_argument("--tracker", choices=TRACKERS, default="qp", help="tracker (default qp)")
    p.add_argument(
        "--planner",
        choices=PLANNERS,
        default="one-step",
        help="foot placement: one-step (the paper's deadbeat law, fixed step time) or mpc (footholds four steps "
        "ahead and the step's duration, docs/ALIP_MPC.md) (default one-step)",
    )
    p.add_argument(
        "--scenario", metavar="NAME", default=None, help="start from a named scenario (options below override it)"
    )
    add_command_options(p, speed_profile=True)
    p.add_argument("--duration", type=positive_float, metavar="S", default=None, help="simulated time, s (default 10)")
    p.add_argument(
        "--push",
        type=parse_push_spec,
        action="append",
        metavar="T:FX,FY,FZ:DUR",
        default=[],
        help="push the base with a world force (N) from T for DUR seconds; repeatable",
    )
    add_shaping_options(p)
    p.add_argument("--seed", type=_SEED, default=0, help=_SEED_HELP)
    p.add_argument("--noise", action="store_true", help="add Gaussian sensor noise (default: exact measurements)")
    add_plant_options(p)
    p.add_argument("--json", metavar="PATH", default=None, help="write the JSON summary to PATH, or '-' for stdout")
    p.add_argument(
        "--log",
        metavar="summary|full|PATH",
        default=None,
        help="'summary': record only what the JSON summary needs (faster, less memory; no --plot); "
        "'full' (the default): record every per-tick signal; PATH: record them all and write them to PATH (.npz)",
    )
    p.add_argument(
        "--plot",
        metavar="PATH",
        default=None,
        help="write a figure, .png, .pdf or .svg (speed, L, foot placement, tracking)",
    )
    p.add_argument("--video", metavar="PATH", default=None, help="record the 'track' camera to PATH (.mp4 or .gif)")
    p.add_argument(
        "--video-fps",
        type=float_in(0.0, B.MAX_VIDEO_FPS, "frames/s"),
        default=30.0,
        metavar="FPS",
        help=f"video frames per simulated second, played in real time: 0 < FPS <= {B.MAX_VIDEO_FPS:g} "
        "(the fastest displays' refresh rate), <= 100 for a .gif (whole hundredths of a second a frame) "
        "(default 30)",
    )
    p.add_argument("--no-progress", action="store_true", help="no progress bar on stderr")
    p.set_defaults(func=handler("amlip_qp.experiments.walk:run_walk", offscreen_gl=True))


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
        help=f"a bundled robot ({', '.join(ROBOT_NAMES)}) or a robot profile file (.toml); default cassie",
    )
    p.add_argument("--tracker", choices=TRACKERS, default="qp", help="tracker (default qp)")
    add_command_options(p, speed_profile=False)
    add_shaping_options(p)
    p.add_argument("--seed", type=_SEED, default=0, help=_SEED_HELP)
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
    # what walk's scenario builder reads and view does not take
    p.set_defaults(scenario=None, speed_profile=None, duration=None, push=[])
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
    p.add_argument("--seed", type=_SEED, default=0, help=_SEED_HELP)
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
