"""``amlip-qp walk``'s options, and those it shares with ``view`` and ``compare`` (the command, its
shaping, the plant).

Each option of a walk is a field of :class:`~amlip_qp.sim.scenarios.options.WalkOptions`
under its destination name (``--turn-rate`` is ``turn_rate``), and its value
type is that field's check, so a value the command line takes a sweep cell
takes too, with the same one-line error. ``walk``'s handler makes the parsed
options a ``WalkOptions`` (``amlip_qp.experiments.walk.options_from_args``);
the options ``walk`` has beyond them are its outputs (``--json``, ``--log``,
``--plot``, ``--video``, ``--video-fps``, ``--no-progress``).
"""

from __future__ import annotations

import argparse
from collections.abc import Callable
from typing import Any

from amlip_qp.cli import bounds as B
from amlip_qp.cli.parsing import float_in, handler, parse_push_spec, value_type
from amlip_qp.profiles import DEFAULT_ROBOT, ROBOT_NAMES
from amlip_qp.sim.scenarios.options import ESTIMATORS, PLANNERS, SENSORS, TRACKERS, WalkOptions

#: The walk options' defaults (``walk``'s where it has its own default).
_DEFAULTS = WalkOptions()


def _type(name: str) -> Callable[[str], Any]:
    """The argparse type of the walk option ``name``: its :class:`WalkOptions` value check."""
    return value_type(WalkOptions.value_check(name))


#: ``--seed`` of ``walk``, ``view`` and ``compare``.
SEED = _type("seed")
SEED_HELP = f"seed of the sensor noise, 0 to {B.MAX_SEED} (32 bits) (default 0)"


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
        type=_type("clearance"),
        metavar="M",
        default=None,
        help="swing-foot clearance at mid-step, m (default: the robot's [gait] clearance_m, or the scenario's)",
    )
    m = p.add_argument_group("plant modifiers (model mismatch; the controller keeps its own model)")
    m.add_argument(
        "--plant-mass-scale",
        type=_type("plant_mass_scale"),
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
        type=_type("plant_spring_scale"),
        default=None,
        metavar="S",
        help="scale every joint and tendon spring (0 <= S <= 10: 0 removes them; at 10 Cassie's springs are "
        "near rigid, and MuJoCo's explicit springs diverge from 200 x at the 0.5 ms step)",
    )
    m.add_argument(
        "--friction",
        type=_type("friction"),
        default=None,
        metavar="MU",
        help="sliding friction of every foot-floor contact (1e-05 <= MU <= 10: MuJoCo raises smaller "
        "coefficients to its mjMINMU = 1e-5)",
    )
    m.add_argument(
        "--limb-collisions",
        action="store_true",
        help="the limbs (the base body's child subtrees) collide with each other, so the legs cannot pass "
        "through each other (by default they collide as the model says)",
    )
    m.add_argument(
        "--actuator-delay",
        type=_type("actuator_delay"),
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
        type=_type("vx"),
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
        "--vy", type=_type("vy"), metavar="M/S", default=None, help=f"{what}lateral speed, m/s (left positive)"
    )
    p.add_argument(
        "--turn-rate",
        type=_type("turn_rate"),
        metavar="DEG/S",
        default=None,
        help=f"{what}turn rate, deg/s (left positive)",
    )


def add_shaping_options(p: argparse.ArgumentParser) -> None:
    """``--accel-limit`` or ``--no-command-shaping``: the rate limit of the command before the planner."""
    shaping = p.add_mutually_exclusive_group()
    shaping.add_argument(
        "--accel-limit",
        type=_type("accel_limit"),
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
        type=_type("robot"),
        metavar="NAME|PATH",
        default=None,
        help=f"a bundled robot ({', '.join(ROBOT_NAMES)}) or a robot profile file (.toml); "
        f"default {DEFAULT_ROBOT}, or the scenario's",
    )
    p.add_argument("--tracker", choices=TRACKERS, default=_DEFAULTS.tracker, help="tracker (default qp)")
    p.add_argument(
        "--planner",
        choices=PLANNERS,
        default=_DEFAULTS.planner,
        help="foot placement: one-step (the paper's deadbeat law, fixed step time) or mpc (footholds four steps "
        "ahead and the step's duration, docs/ALIP_MPC.md) (default one-step)",
    )
    p.add_argument(
        "--scenario", metavar="NAME", default=None, help="start from a named scenario (options below override it)"
    )
    add_command_options(p, speed_profile=True)
    p.add_argument(
        "--duration", type=_type("duration"), metavar="S", default=None, help="simulated time, s (default 10)"
    )
    p.add_argument(
        "--push",
        type=parse_push_spec,
        action="append",
        metavar="T:FX,FY,FZ:DUR",
        default=[],
        help="push the base with a world force (N) from T for DUR seconds; repeatable",
    )
    add_shaping_options(p)
    p.add_argument("--seed", type=SEED, default=_DEFAULTS.seed, help=SEED_HELP)
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
