"""Handler of ``amlip-qp check-robot`` (parser in :mod:`amlip_qp.cli.subcommands`).

One line per check (status, name, the measured number), as each finishes;
then a count. Exit status: 0 when no check failed (skips are not failures),
1 when one did (every check still runs), 2 for bad input (an unknown robot,
an invalid profile, a model that does not load, an unwritable ``--json``),
with one line on stderr before any check runs.

:func:`conformance_checks` loads the robot (bad input raises before any
check runs) and returns the checks' results one by one; a check that raises
is a failed check whose detail is the exception's one-line message.
"""

from __future__ import annotations

import argparse
import functools
import json
import sys
from collections.abc import Callable, Iterator

from amlip_qp.experiments import conformance_control as control
from amlip_qp.experiments.conformance import FAIL, MODEL_CHECKS, PASS, SKIP, CheckResult, one_line
from amlip_qp.output_paths import check_output_path, writing
from amlip_qp.sim.scenarios import factory


def _guarded(name: str, run: Callable[[], CheckResult]) -> CheckResult:
    """``run()``, or a failure of ``name`` with the one-line reason if it raises."""
    try:
        return run()
    except Exception as exc:  # a check that raises is a failed check, and the others still run
        return CheckResult(name, FAIL, None, "", f"raised {type(exc).__name__}: {one_line(exc)}")


def conformance_checks(robot_arg: str, walk: bool = True) -> Iterator[CheckResult]:
    """The checks of the robot ``robot_arg`` (a bundled name or a profile path), run one by one.

    The robot is loaded and its profile's tracker tables are read first, so bad input raises
    here, before any check runs; the results are then produced as the checks finish (the walk
    takes the longest).

    Args:
        robot_arg: A bundled robot's name or a robot profile file's path.
        walk: Run the walk in place (:func:`~amlip_qp.experiments.conformance_control.check_walk`).

    Raises:
        UnknownRobotError, ProfileError, ModelFileError, MJCFError: The robot cannot be loaded.
        InputError: A ``[trackers.NAME]`` table of its profile is invalid.
    """
    robot = factory.load(robot_arg)
    if robot.profile is not None:
        for tracker in robot.profile.tracker_configs:  # an invalid [trackers.NAME] table is bad input too
            robot.profile.tracker_config(tracker)

    def run() -> Iterator[CheckResult]:
        for name, check in MODEL_CHECKS:
            yield _guarded(name, functools.partial(check, robot))
        for tracker in control.TICK_TRACKERS:
            yield _guarded(control.tick_name(tracker), functools.partial(control.check_tick, robot, tracker))
        if walk:
            yield _guarded(control.WALK_NAME, functools.partial(control.check_walk, robot_arg, robot))

    return run()


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
