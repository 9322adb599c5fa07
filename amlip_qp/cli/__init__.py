"""The ``amlip-qp`` command line.

The parser is built here (``codegen`` and ``bench`` here; ``walk``, ``view``,
``compare``, ``sweep`` and ``check-robot`` in :mod:`~amlip_qp.cli.subcommands`; the parser
class and the value types in :mod:`~amlip_qp.cli.parsing`). Each
subcommand's work lives in the module it names, imported only when the
subcommand runs (so ``amlip-qp --help`` stays fast).

Exit codes: 0 success, 1 a run-time failure (the walker fell, a check found
stale files, ...), 2 bad usage or bad input. Errors print one readable line
to stderr, never a traceback.
"""

from __future__ import annotations

import argparse
import sys
import warnings
from collections.abc import Sequence
from typing import TextIO

from amlip_qp.cli import bounds as B
from amlip_qp.cli.parsing import Parser, float_in, handler, int_in
from amlip_qp.cli.subcommands import TRACKERS, add_check_robot, add_compare, add_sweep, add_view, add_walk
from amlip_qp.exceptions import (
    AmlipError,
    InputError,
    MJCFError,
    ModelFileError,
    UnknownRobotError,
    UnverifiedCommandWarning,
)
from amlip_qp.profiles import DEFAULT_EKF_SCENARIO, DEFAULT_SCENARIO

PROG = "amlip-qp"

_DURATION = float_in(B.MIN_DURATION_S, B.MAX_DURATION_S, "s", low_open=False)
_DURATION_HELP = (
    f"{B.MIN_DURATION_S:g} (a control tick) to {B.MAX_DURATION_S:g} (the robots' CommandBounds.duration_max_s)"
)
_REPEATS = int_in(1, B.MAX_BENCH_REPEATS, "number of repeats")
_REPEATS_HELP = f"at most {B.MAX_BENCH_REPEATS}"

#: Errors that mean "the user asked for something invalid": exit status 2.
_USAGE_ERRORS = (InputError, UnknownRobotError, ModelFileError, MJCFError)


def build_parser() -> argparse.ArgumentParser:
    """Build the full argument parser (all subcommands)."""
    parser = Parser(
        prog=PROG,
        description="ALIP angular-momentum foot placement with PBC and whole-body QP tracking.",
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=Parser)
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
    p.set_defaults(func=handler("amlip_qp.codegen.cli:run_codegen"))

    # bench -----------------------------------------------------------------
    p = sub.add_parser("bench", help="benchmarks (timings are machine dependent)")
    bench = p.add_subparsers(dest="bench_target", metavar="TARGET", parser_class=Parser)
    bench.required = True
    b = bench.add_parser("codegen", help="generated C fast path vs CasADi Function vs numpy")
    b.add_argument("--json", metavar="PATH", default=None, help="write the results as JSON to PATH, or '-' for stdout")
    b.add_argument(
        "--calls",
        type=int_in(1, B.MAX_BENCH_CALLS, "number of calls"),
        default=20000,
        help=f"timed calls per path, at most {B.MAX_BENCH_CALLS} (about 7 min) (default 20000)",
    )
    b.set_defaults(func=handler("amlip_qp.codegen.cli:run_bench"))
    b = bench.add_parser(
        "qp", help="replay recorded Cassie tracker QPs through every installed QP solver, against the tracker's ProxQP"
    )
    b.add_argument("--json", metavar="PATH", default=None, help="write the results as JSON to PATH, or '-' for stdout")
    b.add_argument(
        "--ticks",
        type=int_in(1, B.MAX_BENCH_TICKS, "number of ticks"),
        default=1200,
        help=f"recorded tracker QPs to replay, at most {B.MAX_BENCH_TICKS} (10 s of walking; each kept in memory, "
        "about 20 kB) (default 1200)",
    )
    b.add_argument("--scenario", default=DEFAULT_SCENARIO, help=f"scenario to record from (default {DEFAULT_SCENARIO})")
    b.add_argument(
        "--solvers",
        default=None,
        metavar="NAMES",
        help="comma-separated solvers to compare with the tracker's warm ProxQP (default: every one installed)",
    )
    b.set_defaults(func=handler("amlip_qp.experiments.bench_qp:run_bench"))
    b = bench.add_parser(
        "mpc",
        help="the step-timing MPC's QP per control tick (matrices and solve) on a pushed point-mass walk, "
        "against the QP tracker's own solve timed in turns with it",
    )
    b.add_argument("--json", metavar="PATH", default=None, help="write the results as JSON to PATH, or '-' for stdout")
    b.add_argument(
        "--duration",
        type=_DURATION,
        default=4.0,
        metavar="S",
        help=f"simulated time, s, {_DURATION_HELP}, at least 0.05 (a turn of the tracker's solves; default 4)",
    )
    b.set_defaults(func=handler("amlip_qp.experiments.bench_mpc:run_bench"))
    b = bench.add_parser(
        "ekf", help="the invariant EKF's cost inside the closed loop, against the rest of the QP tracker's tick"
    )
    b.add_argument("--json", metavar="PATH", default=None, help="write the results as JSON to PATH, or '-' for stdout")
    b.add_argument(
        "--scenario",
        default=DEFAULT_EKF_SCENARIO,
        help=f"a scenario with the EKF estimator to walk (default {DEFAULT_EKF_SCENARIO})",
    )
    b.add_argument(
        "--duration", type=_DURATION, default=4.0, metavar="S", help=f"simulated time, s, {_DURATION_HELP} (default 4)"
    )
    b.set_defaults(func=handler("amlip_qp.experiments.bench_ekf:run_bench"))
    b = bench.add_parser(
        "harness",
        help="where a closed-loop tick goes: controller, MuJoCo and the harness's own time, per tracker and log mode",
    )
    b.add_argument("--json", metavar="PATH", default=None, help="write the results as JSON to PATH, or '-' for stdout")
    b.add_argument(
        "--scenario",
        default=DEFAULT_SCENARIO,
        metavar="NAMES",
        help="comma-separated scenarios to walk, one table each; 'robots': each bundled robot's nominal walk "
        f"(default {DEFAULT_SCENARIO})",
    )
    b.add_argument(
        "--duration",
        type=_DURATION,
        default=3.0,
        metavar="S",
        help=f"simulated time per walk, s, {_DURATION_HELP} (default 3)",
    )
    b.add_argument(
        "--repeats",
        type=_REPEATS,
        default=3,
        help=f"walks per tracker and log mode, interleaved, {_REPEATS_HELP} (default 3)",
    )
    b.add_argument(
        "--trackers",
        default="qp,pbc",
        metavar="NAMES",
        help="comma-separated trackers: qp (with the profile's QP solver), pbc, qp-gathered (the QP with the "
        "compiled build that gathers its inputs in Python), qp-daqp and qp-proxqp (the QP with that solver), "
        "qp-full (the QP solving the full problem in every tick, the airborne swing foot's forces included) "
        "(default qp,pbc)",
    )
    b.set_defaults(func=handler("amlip_qp.experiments.bench_harness:run_bench"))

    b = bench.add_parser(
        "sweep", help="sweep throughput: cells per second with 1 and with 2 worker processes, interleaved"
    )
    b.add_argument("--json", metavar="PATH", default=None, help="write the results as JSON to PATH, or '-' for stdout")
    b.add_argument(
        "--cells",
        type=int_in(1, B.MAX_BENCH_CELLS, "number of cells"),
        default=6,
        help=f"cells per sweep, at most {B.MAX_BENCH_CELLS} (default 6)",
    )
    b.add_argument(
        "--duration",
        type=_DURATION,
        default=2.0,
        metavar="S",
        help=f"simulated s per cell, {_DURATION_HELP} (default 2)",
    )
    b.add_argument(
        "--repeats", type=_REPEATS, default=3, help=f"interleaved repeats of each, {_REPEATS_HELP} (default 3)"
    )
    b.add_argument("--tracker", choices=TRACKERS, default="qp", help="tracker (default qp)")
    b.set_defaults(func=handler("amlip_qp.sweep.bench:run_bench"))

    add_walk(sub)
    add_view(sub)
    add_compare(sub)
    add_sweep(sub)
    add_check_robot(sub)
    return parser


def _show_warning(
    message: Warning | str,
    category: type[Warning],
    filename: str,
    lineno: int,
    file: TextIO | None = None,
    line: str | None = None,
) -> None:
    """An :class:`UnverifiedCommandWarning` as one line on stderr; any other warning as Python shows it."""
    if issubclass(category, UnverifiedCommandWarning):
        sys.stderr.write(f"{PROG}: warning: {message}\n")
    else:
        _SHOW_WARNING(message, category, filename, lineno, file, line)


#: Python's own warning display (the CLI replaces it while a subcommand runs).
_SHOW_WARNING = warnings.showwarning


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``amlip-qp`` console script."""
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        with warnings.catch_warnings():
            warnings.showwarning = _show_warning
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
