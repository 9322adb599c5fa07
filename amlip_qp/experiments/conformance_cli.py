"""Handler of ``amlip-qp check-robot`` (parser in :mod:`amlip_qp.cli.subcommands`).

One line per check (status, name, the measured number), as each finishes;
then a count. Exit status: 0 when no check failed (skips are not failures),
1 when one did (every check still runs), 2 for bad input (an unknown robot,
an invalid profile, a model that does not load, an unwritable ``--json``),
with one line on stderr before any check runs.
"""

from __future__ import annotations

import argparse
import json
import sys

from amlip_qp.experiments.conformance import FAIL, PASS, SKIP, CheckResult, conformance_checks
from amlip_qp.output_paths import check_output_path, writing


def report(robot_arg: str, results: list[CheckResult]) -> dict:
    """The JSON report: the robot, whether every check passed or was skipped, and each check."""
    return {
        "robot": robot_arg,
        "passed": not any(r.status == FAIL for r in results),
        "checks": [r.to_json() for r in results],
    }


def run_check_robot(args: argparse.Namespace) -> int:
    """``amlip-qp check-robot NAME|PATH [--no-walk] [--json FILE]``."""
    check_output_path("--json", args.json)
    checks = conformance_checks(args.robot, walk=not args.no_walk)  # loads the robot: bad input raises here
    out = sys.stderr if args.json == "-" else sys.stdout
    results = []
    for res in checks:
        results.append(res)
        out.write(res.line() + "\n")
        out.flush()
    count = {s: sum(r.status == s for r in results) for s in (PASS, FAIL, SKIP)}
    out.write(f"{args.robot}: {count[PASS]} passed, {count[FAIL]} failed, {count[SKIP]} skipped\n")
    if args.json is not None:
        text = json.dumps(report(args.robot, results), indent=2) + "\n"
        if args.json == "-":
            sys.stdout.write(text)
        else:
            with writing("--json", args.json), open(args.json, "w") as fh:
                fh.write(text)
    return 1 if count[FAIL] else 0
