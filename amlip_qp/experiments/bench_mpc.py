"""``amlip-qp bench mpc``: the step-timing MPC's QP per control tick, against the QP tracker's own solve.

:func:`amlip_qp.control.mpc.bench.run_benchmark` walks a pushed point mass with the MPC planner
(its module doc says what each row times). In turns with it, after every
:data:`BLOCK_TICKS` MPC ticks, this module times the next :data:`BLOCK_TICKS` whole-body QPs of
a recorded walk of the default scenario (:func:`amlip_qp.experiments.bench_qp.record_walk`;
the problems the tracker solves by default: the airborne problem while the swing foot is in
the air, the full one otherwise) through the QP tracker's own solver, as the tracker runs it: the robot profile's
``qp_solver`` (hot-started DAQP on Cassie: the tracker's ``DAQPSolver`` on an allocated problem,
``daqp-tracker`` of ``amlip-qp bench qp``; warm-started ProxQP, ``proxsuite-warm``, for a profile
that names ProxQP). Each of those QPs is put in the solver's own format, and written where the
solver reads it, before the timed call. The machine's speed drifts (up to 1.6x within
minutes on the 2-core development machine) then hit both solves alike.

The goal of the MPC's solve (``mpc_solve``): a median at most the QP tracker's warm solve's
(``tracker_solve``), measured so.
"""

from __future__ import annotations

import argparse
import time
import warnings
from typing import Any

import numpy as np

from amlip_qp.control.mpc import bench as mpc_bench
from amlip_qp.exceptions import InputError
from amlip_qp.experiments import qp_solver_list
from amlip_qp.experiments.bench_qp import WARMUP_PROBLEMS, record_walk, solver_settings
from amlip_qp.output_paths import check_output_path, emit_report
from amlip_qp.profiles import DEFAULT_SCENARIO, get_profile
from amlip_qp.sim.scenarios.named import get_scenario

#: MPC ticks per turn, and tracker QPs timed per turn.
BLOCK_TICKS = 50
#: The most tracker QPs recorded (a longer benchmark replays them again from the first).
MAX_PROBLEMS = 8000
#: The shortest walk with a turn of the tracker's solves: two blocks of MPC ticks, s.
MIN_DURATION_S = 2 * BLOCK_TICKS * mpc_bench.DT_S
#: The ``amlip-qp bench qp`` runner of each tracker solver: its warm path, as the tracker runs it.
TRACKER_RUNNERS = {"daqp": "daqp-tracker", "proxqp": "proxsuite-warm"}


def tracker_runner_name(scenario: str = DEFAULT_SCENARIO) -> str:
    """The ``amlip-qp bench qp`` runner of the QP solver the scenario's robot profile names."""
    robot = get_scenario(scenario).robot
    solver = get_profile(robot).tracker_config("qp").qp_solver
    if solver not in TRACKER_RUNNERS:
        raise InputError(f"no warm runner for the QP solver {solver!r} of {robot}; known: {', '.join(TRACKER_RUNNERS)}")
    return TRACKER_RUNNERS[solver]


def check_duration(duration_s: float) -> None:
    """Raise InputError unless the walk lasts at least :data:`MIN_DURATION_S` (one turn of the tracker's solves)."""
    if not duration_s >= MIN_DURATION_S - 1e-12:
        raise InputError(
            f"bench mpc needs --duration of at least {MIN_DURATION_S:g} s (a turn of the QP tracker's solves "
            f"after {BLOCK_TICKS} MPC ticks), got {duration_s:g} s"
        )


def run(duration_s: float = 4.0, scenario: str = DEFAULT_SCENARIO) -> dict[str, Any]:
    """The MPC benchmark of ``duration_s`` simulated s with the QP tracker's solve timed in turns (module doc).

    Returns:
        :func:`amlip_qp.control.mpc.bench.run_benchmark`'s result with ``tracker_solve``
        (``median_us``, ``p99_us``, ``runner``, ``scenario``, ``problems``: the QPs recorded,
        ``solves`` and the solver's ``failures``) and ``goal_met`` (``mpc_solve``'s median at most
        ``tracker_solve``'s).
    """
    check_duration(duration_s)
    name = tracker_runner_name(scenario)
    n_ticks = int(round(duration_s / mpc_bench.DT_S))
    # The problems the default tracker solves: the airborne problem while the swing foot is in the air.
    problems, _, _ = record_walk(min(max(n_ticks, BLOCK_TICKS), MAX_PROBLEMS), scenario, airborne_reduction=True)
    spec = next(s for s in qp_solver_list.SOLVERS if s.name == name)
    runner = spec.make(solver_settings())
    runner.setup(problems)
    for p in problems[:WARMUP_PROBLEMS]:  # untimed: caches and the working set settle
        d = runner.prepare(p)
        runner.load(d)
        runner.solve(d)
    times_us: list[float] = []
    state = {"next": 0}

    def solve_block() -> None:
        start = state["next"]
        chunk = [problems[(start + k) % len(problems)] for k in range(BLOCK_TICKS)]
        state["next"] = (start + BLOCK_TICKS) % len(problems)
        data = [runner.prepare(p) for p in chunk]
        clock = time.perf_counter_ns
        for d in data:
            runner.load(d)
            t0 = clock()
            runner.solve(d)
            times_us.append((clock() - t0) * 1e-3)

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # a backend's conversion notice
        result = mpc_bench.run_benchmark(duration_s=duration_s, between_blocks=solve_block, block_ticks=BLOCK_TICKS)
    a = np.asarray(times_us, dtype=float)
    result["tracker_solve"] = {
        "median_us": float(np.median(a)),
        "p99_us": float(np.percentile(a, 99)),
        "runner": name,
        "scenario": scenario,
        "problems": len(problems),
        "solves": len(a),
        "failures": runner.failures,
    }
    result["goal_met"] = bool(result["mpc_solve"]["median_us"] <= result["tracker_solve"]["median_us"])
    return result


def format_table(result: dict[str, Any]) -> str:
    """The MPC's table (:func:`amlip_qp.control.mpc.bench.format_table`), the tracker's solve and the goal."""
    ts = result["tracker_solve"]
    lines = [
        mpc_bench.format_table(result),
        f"{'tracker_solve':<18}{ts['median_us']:>11.2f}{ts['p99_us']:>11.2f}",
        f"tracker_solve: the QP tracker's own solve ({ts['runner']}) on {ts['problems']} QPs of a recorded "
        f"{ts['scenario']} walk, {ts['solves']} solves in turns of {BLOCK_TICKS} with the MPC's ticks",
        f"goal: mpc_solve median <= tracker_solve median: {'met' if result['goal_met'] else 'NOT met'} "
        f"({result['mpc_solve']['median_us']:.2f} against {ts['median_us']:.2f} µs)",
    ]
    return "\n".join(lines)


def run_bench(args: argparse.Namespace) -> int:
    """The handler of ``amlip-qp bench mpc``: the table, and JSON with ``--json PATH|-``."""
    check_output_path("--json", args.json)
    check_duration(args.duration)
    result = run(duration_s=args.duration)
    emit_report(format_table(result), result, args.json)
    return 0
