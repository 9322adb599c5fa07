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
import sys
from typing import Callable, Sequence

from amlip_qp.exceptions import AmlipError, InputError, ModelFileError, MJCFError, UnknownRobotError

PROG = "amlip-qp"

#: Errors that mean "the user asked for something invalid": exit status 2.
_USAGE_ERRORS = (InputError, UnknownRobotError, ModelFileError, MJCFError)


class _Parser(argparse.ArgumentParser):
    """An ArgumentParser whose errors are one line and exit with status 2."""

    def error(self, message: str) -> None:  # noqa: D401 (argparse API)
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
    p = sub.add_parser("codegen", help="regenerate the CasADi C code in codegen/")
    p.add_argument(
        "--check",
        action="store_true",
        help="regenerate into a temporary folder and fail if codegen/ differs (names stale files)",
    )
    p.add_argument("--out", metavar="DIR", default=None, help="output folder (default: the repository's codegen/)")
    p.set_defaults(func=_handler("amlip_qp.codegen.cli:run_codegen"))

    # bench -----------------------------------------------------------------
    p = sub.add_parser("bench", help="benchmarks (timings are machine dependent)")
    bench = p.add_subparsers(dest="bench_target", metavar="TARGET", parser_class=_Parser)
    bench.required = True
    b = bench.add_parser("codegen", help="generated C fast path vs CasADi Function vs numpy")
    b.add_argument("--json", metavar="PATH", default=None, help="write the results as JSON to PATH, or '-' for stdout")
    b.add_argument("--calls", type=_positive_int, default=20000, help="timed calls per path (default 20000)")
    b.set_defaults(func=_handler("amlip_qp.codegen.cli:run_bench"))

    return parser


def _positive_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {text!r}") from None
    if value <= 0:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {value}")
    return value


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
    except KeyboardInterrupt:
        sys.stderr.write(f"{PROG}: interrupted\n")
        return 130


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(main())
