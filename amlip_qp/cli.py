"""The ``amlip-qp`` command line.

Subcommands are declared here; their work lives in the modules they name,
imported only when the subcommand runs (so ``amlip-qp --help`` stays fast).

Exit codes: 0 success, 1 a run-time failure (the walker fell, a check found
stale files, ...), 2 bad usage or bad input. Errors print one readable line
to stderr, never a traceback.
"""

from __future__ import annotations

import argparse
import importlib
import math
import re
import sys
from collections.abc import Callable, Sequence
from typing import NoReturn

from amlip_qp.exceptions import AmlipError, InputError, MJCFError, ModelFileError, UnknownRobotError
from amlip_qp.profiles import ROBOT_NAMES

PROG = "amlip-qp"

#: Errors that mean "the user asked for something invalid": exit status 2.
_USAGE_ERRORS = (InputError, UnknownRobotError, ModelFileError, MJCFError)


#: An argument argparse should read as a value, not an option: anything that starts like a
#: negative number. Argparse's own pattern knows only ``-1`` and ``-1.5``; this one also takes
#: exponents (``-1e-1``, ``-5E0``), ``-inf``/``-nan`` and a push at a negative time
#: (``-1:0,0,0:1``), which the value checks then refuse with a clear message. No option of
#: ``amlip-qp`` starts with ``-`` and a digit.
_NEGATIVE_NUMBER = re.compile(r"^-(?:\.?\d|inf|nan)", re.IGNORECASE)


class _Parser(argparse.ArgumentParser):
    """An ArgumentParser whose errors are one line and exit with status 2, and that reads ``-1e-1`` as a number."""

    def __init__(self, *args, **kwargs) -> None:
        super().__init__(*args, **kwargs)
        # argparse consults this (private) matcher to tell negative numbers from options.
        self._negative_number_matcher = _NEGATIVE_NUMBER

    def error(self, message: str) -> NoReturn:
        sys.stderr.write(f"{self.prog}: error: {message} (see '{self.prog} --help')\n")
        raise SystemExit(2)


def _handler(path: str) -> Callable[[argparse.Namespace], int]:
    """Return a lazily-imported handler ``"module:function"``."""

    def run(args: argparse.Namespace) -> int:
        module_name, func_name = path.split(":")
        return getattr(importlib.import_module(module_name), func_name)(args)

    return run


def build_parser() -> argparse.ArgumentParser:
    """Build the full argument parser (all subcommands)."""
    parser = _Parser(
        prog=PROG,
        description="ALIP angular-momentum foot placement with PBC and whole-body QP tracking.",
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    sub.required = True

    # codegen ---------------------------------------------------------------
    p = sub.add_parser("codegen", help="regenerate the CasADi C code in amlip_qp/codegen/generated/ of a checkout")
    p.add_argument(
        "--check",
        action="store_true",
        help="regenerate in memory and fail if the generated C differs (names stale files)",
    )
    p.add_argument(
        "--out", metavar="DIR", default=None, help="output folder (default: amlip_qp/codegen/generated/ of a checkout)"
    )
    p.set_defaults(func=_handler("amlip_qp.codegen.cli:run_codegen"))

    # bench -----------------------------------------------------------------
    p = sub.add_parser("bench", help="benchmarks (timings are machine dependent)")
    bench = p.add_subparsers(dest="bench_target", metavar="TARGET", parser_class=_Parser)
    bench.required = True
    b = bench.add_parser("codegen", help="generated C fast path vs CasADi Function vs numpy")
    b.add_argument("--json", metavar="PATH", default=None, help="write the results as JSON to PATH, or '-' for stdout")
    b.add_argument("--calls", type=_positive_int, default=20000, help="timed calls per path (default 20000)")
    b.set_defaults(func=_handler("amlip_qp.codegen.cli:run_bench"))
    b = bench.add_parser(
        "qp", help="replay recorded Cassie tracker QPs: warm ProxQP vs re-initialised vs qpsolvers backends"
    )
    b.add_argument("--json", metavar="PATH", default=None, help="write the results as JSON to PATH, or '-' for stdout")
    b.add_argument("--ticks", type=_positive_int, default=1200, help="recorded tracker QPs to replay (default 1200)")
    b.add_argument("--scenario", default="cassie-1mps", help="scenario to record from (default cassie-1mps)")
    b.set_defaults(func=_handler("amlip_qp.sim.bench_qp:run_bench"))
    b = bench.add_parser(
        "ekf", help="the invariant EKF's cost inside the closed loop, against the rest of the QP tracker's tick"
    )
    b.add_argument("--json", metavar="PATH", default=None, help="write the results as JSON to PATH, or '-' for stdout")
    b.add_argument(
        "--scenario",
        default="cassie-1mps-cc-ekf",
        help="a scenario with the EKF estimator to walk (default cassie-1mps-cc-ekf)",
    )
    b.add_argument("--duration", type=_positive_float, default=4.0, metavar="S", help="simulated time, s (default 4)")
    b.set_defaults(func=_handler("amlip_qp.sim.bench_ekf:run_bench"))
    b = bench.add_parser(
        "harness",
        help="where a closed-loop tick goes: controller, MuJoCo and the harness's own time, per tracker and log mode",
    )
    b.add_argument("--json", metavar="PATH", default=None, help="write the results as JSON to PATH, or '-' for stdout")
    b.add_argument("--scenario", default="cassie-1mps", help="scenario to walk (default cassie-1mps)")
    b.add_argument(
        "--duration", type=_positive_float, default=3.0, metavar="S", help="simulated time per walk, s (default 3)"
    )
    b.add_argument(
        "--repeats", type=_positive_int, default=3, help="walks per tracker and log mode, interleaved (default 3)"
    )
    b.add_argument("--trackers", default="qp,pbc", metavar="NAMES", help="comma-separated trackers (default qp,pbc)")
    b.set_defaults(func=_handler("amlip_qp.sim.bench_harness:run_bench"))

    b = bench.add_parser(
        "sweep", help="sweep throughput: cells per second with 1 and with 2 worker processes, interleaved"
    )
    b.add_argument("--json", metavar="PATH", default=None, help="write the results as JSON to PATH, or '-' for stdout")
    b.add_argument("--cells", type=_positive_int, default=6, help="cells per sweep (default 6)")
    b.add_argument(
        "--duration", type=_positive_float, default=2.0, metavar="S", help="simulated s per cell (default 2)"
    )
    b.add_argument("--repeats", type=_positive_int, default=3, help="interleaved repeats of each (default 3)")
    b.add_argument("--tracker", choices=_TRACKERS, default="qp", help="tracker (default qp)")
    b.set_defaults(func=_handler("amlip_qp.sweep.bench:run_bench"))

    _add_walk(sub)
    _add_compare(sub)
    _add_sweep(sub)
    return parser


#: Trackers of ``walk`` and ``compare`` (kept here so ``--help`` needs no heavy import; the
#: robots are the profiles' :data:`~amlip_qp.profiles.ROBOT_NAMES`, a light import).
_TRACKERS = ("pbc", "qp")
#: Sensor models and base estimators (the same as ``amlip_qp.sim.sensors.SENSOR_MODELS`` and
#: ``amlip_qp.sim.factory.ESTIMATORS``, checked by the tests).
_SENSORS = ("ideal", "robot")
_ESTIMATORS = ("truth", "ekf")


def _add_plant_options(p: argparse.ArgumentParser) -> None:
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
        choices=_SENSORS,
        default=None,
        help="ideal: the exact state; robot: IMU, encoders and contact switches with noise, no base state "
        "(default: the scenario's, ideal)",
    )
    p.add_argument(
        "--estimator",
        choices=_ESTIMATORS,
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
        "waves:HEIGHT_M:WAVELENGTH_M, hfield:PATH.png:SIZE_X_M:SIZE_Y_M:HEIGHT_M (gray: black 0, white HEIGHT_M); "
        "slopes, stairs and waves start 1 m ahead of the robot",
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
        type=_non_negative_float,
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
        help="scale the mass and inertia of every plant body (0 < S <= 10)",
    )
    m.add_argument(
        "--payload",
        default=None,
        metavar="KG[@X,Y,Z]",
        help="weld a 0.2 x 0.15 x 0.1 m box of KG kg to the base at (X, Y, Z) m in the base frame "
        "(default: at its origin)",
    )
    m.add_argument(
        "--plant-spring-scale", type=float, default=None, metavar="S", help="scale every joint and tendon spring"
    )
    m.add_argument(
        "--friction", type=float, default=None, metavar="MU", help="sliding friction of every foot-floor contact"
    )
    m.add_argument(
        "--actuator-delay",
        type=int,
        default=None,
        metavar="TICKS",
        help="delay the actuator commands by TICKS control ticks (0.5 ms each)",
    )


def _add_walk(sub) -> None:
    p = sub.add_parser(
        "walk",
        help="simulate one walk in MuJoCo and summarise it",
        description="Simulate one walk in MuJoCo with the PBC or QP tracker and print a summary. "
        "Speeds, the turn rate, the duration and pushes must lie inside the robot's physical bounds "
        "(amlip_qp.profiles.CommandBounds); output paths are checked before the run. "
        "Exit status: 0 finished standing, 1 the robot fell (outputs are still written), 2 bad input.",
    )
    p.add_argument("--robot", choices=ROBOT_NAMES, default=None, help="robot (default cassie, or the scenario's)")
    p.add_argument("--tracker", choices=_TRACKERS, default="qp", help="tracker (default qp)")
    p.add_argument(
        "--scenario", metavar="NAME", default=None, help="start from a named scenario (options below override it)"
    )
    speed = p.add_mutually_exclusive_group()
    speed.add_argument(
        "--vx", type=_finite_float, metavar="M/S", default=None, help="constant forward speed, m/s (default 0)"
    )
    speed.add_argument(
        "--speed-profile",
        metavar="T:V,...",
        default=None,
        help="piecewise-linear forward speed, e.g. '0:0,5:2.1' (s:m/s)",
    )
    p.add_argument("--vy", type=_finite_float, metavar="M/S", default=None, help="lateral speed, m/s (left positive)")
    p.add_argument(
        "--turn-rate", type=_finite_float, metavar="DEG/S", default=None, help="turn rate, deg/s (left positive)"
    )
    p.add_argument("--duration", type=_positive_float, metavar="S", default=None, help="simulated time, s (default 10)")
    p.add_argument(
        "--push",
        type=parse_push_spec,
        action="append",
        metavar="T:FX,FY,FZ:DUR",
        default=[],
        help="push the base with a world force (N) from T for DUR seconds; repeatable",
    )
    shaping = p.add_mutually_exclusive_group()
    shaping.add_argument(
        "--accel-limit",
        type=_positive_float,
        metavar="M/S2",
        default=None,
        help="rate limit of the forward and lateral speed commands before the planner, m/s^2 "
        "(default: the robot's, amlip_qp.profiles.CommandShaping)",
    )
    shaping.add_argument(
        "--no-command-shaping",
        action="store_true",
        help="give the planner the raw command (no rate limit, no step-length cap)",
    )
    p.add_argument("--seed", type=_non_negative_int, default=0, help="seed of the sensor noise (default 0)")
    p.add_argument("--noise", action="store_true", help="add Gaussian sensor noise (default: exact measurements)")
    _add_plant_options(p)
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
        "--video-fps", type=_positive_float, default=30.0, metavar="FPS", help="video frames per second (default 30)"
    )
    p.add_argument("--no-progress", action="store_true", help="no progress bar on stderr")
    p.set_defaults(func=_handler("amlip_qp.sim.cli:run_walk"))


def _add_compare(sub) -> None:
    p = sub.add_parser(
        "compare",
        help="compare the PBC and QP trackers on the same scenarios and seed",
        description="Run both trackers on the same scenarios with the same seed and print one table row per "
        "robot and tracker (see docs/SUMMARY_SCHEMA.md for the definitions).",
    )
    p.add_argument(
        "--robots",
        type=_name_list(ROBOT_NAMES),
        default=list(ROBOT_NAMES),
        metavar="R1,R2",
        help=f"robots (default {','.join(ROBOT_NAMES)})",
    )
    p.add_argument(
        "--trackers",
        type=_name_list(_TRACKERS),
        default=list(_TRACKERS),
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
        type=_non_negative_int,
        default=None,
        metavar="N",
        help="bisection iterations per push direction",
    )
    p.add_argument("--no-ramp", action="store_true", help="skip the speed-ramp test")
    p.add_argument("--no-push", action="store_true", help="skip the push tests")
    p.add_argument("--seed", type=_non_negative_int, default=0, help="seed of the sensor noise (default 0)")
    p.add_argument("--noise", action="store_true", help="add Gaussian sensor noise")
    _add_plant_options(p)
    p.add_argument("--jobs", type=_positive_int, default=2, metavar="N", help="parallel worker processes (default 2)")
    p.add_argument("--json", metavar="PATH", default=None, help="write the table as JSON to PATH, or '-' for stdout")
    p.add_argument(
        "--plot",
        metavar="PATH",
        default="out/compare.png",
        help="comparison figure, .png, .pdf or .svg (default out/compare.png; folder created)",
    )
    p.add_argument("--no-plot", action="store_true", help="do not write the figure")
    p.set_defaults(func=_handler("amlip_qp.sim.cli:run_compare"))


def _add_sweep(sub) -> None:
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
    p.add_argument("--duration", type=_positive_float, metavar="S", default=None, help="simulated time per walk, s")
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
        type=_positive_int,
        default=None,
        metavar="N",
        help="local worker processes (default: one per core)",
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
    p.set_defaults(func=_handler("amlip_qp.sweep.cli:run_sweep"))


def parse_push_spec(text: str) -> tuple[float, tuple[float, float, float], float]:
    """Parse ``T:FX,FY,FZ:DUR`` (s : N,N,N : s) into ``(t_s, (fx, fy, fz), duration_s)``."""
    usage = f"expected T:FX,FY,FZ:DUR (s:N,N,N:s), e.g. 6:100,0,0:0.2, got {text!r}"
    parts = text.split(":")
    if len(parts) != 3:
        raise argparse.ArgumentTypeError(usage)
    try:
        t = float(parts[0])
        force = tuple(float(x) for x in parts[1].split(","))
        dur = float(parts[2])
    except ValueError:
        raise argparse.ArgumentTypeError(usage) from None
    if len(force) != 3 or not all(math.isfinite(x) for x in (t, dur, *force)):
        raise argparse.ArgumentTypeError(usage)
    if t < 0 or dur <= 0:
        raise argparse.ArgumentTypeError(f"a push needs T >= 0 s and DUR > 0 s, got {text!r}")
    return t, force, dur


def _finite_float(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"expected a finite number, got {text!r}")
    return value


def _positive_float(text: str) -> float:
    value = _finite_float(text)
    if value <= 0:
        raise argparse.ArgumentTypeError(f"expected a positive number, got {text!r}")
    return value


def _non_negative_float(text: str) -> float:
    value = _finite_float(text)
    if value < 0:
        raise argparse.ArgumentTypeError(f"expected a number >= 0, got {text!r}")
    return value


def _name_list(allowed: tuple[str, ...]):
    """Argparse type: a comma-separated list of names from ``allowed`` (order kept, duplicates dropped)."""

    def parse(text: str) -> list[str]:
        names = list(dict.fromkeys(n.strip() for n in text.split(",") if n.strip()))
        bad = [n for n in names if n not in allowed]
        if not names or bad:
            raise argparse.ArgumentTypeError(f"expected a comma-separated list from {', '.join(allowed)}, got {text!r}")
        return names

    return parse


def _int_at_least(minimum: int, what: str):
    """Argparse type: an integer >= ``minimum`` (``what`` names it in the error)."""

    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected a {what}, got {text!r}") from None
        if value < minimum:
            raise argparse.ArgumentTypeError(f"expected a {what}, got {value}")
        return value

    return parse


_positive_int = _int_at_least(1, "positive integer")
_non_negative_int = _int_at_least(0, "non-negative integer")


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``amlip-qp`` console script."""
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args) or 0)
    except _USAGE_ERRORS as exc:
        sys.stderr.write(f"{PROG}: error: {exc}\n")
        return 2
    except AmlipError as exc:
        sys.stderr.write(f"{PROG}: error: {exc}\n")
        return 1
    except OSError as exc:  # an output that failed after the early checks (disk full, folder removed, ...)
        where = f"{exc.filename}: " if exc.filename else ""
        sys.stderr.write(
            f"{PROG}: error: {where}{exc.strerror or exc}; check the path, its folder and the free space\n"
        )
        return 2
    except KeyboardInterrupt:
        sys.stderr.write(f"{PROG}: interrupted\n")
        return 130


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(main())
