"""``amlip-qp bench sweep``: the sweep's throughput with 1 and with 2 worker processes.

The same small sweep (``--cells`` walks of ``--duration`` simulated seconds at
distinct speeds, no output folder) runs on a fresh process pool of 1 worker,
then of 2, ``--repeats`` times interleaved, so a change of the machine's load
affects both alike. Reported: cells per second of each run, the median of the
per-repeat ratios (2 workers / 1), the machine's cores and its load average
before and after (a busy machine lowers the ratio). Timings are machine
dependent: this is a benchmark, never a test.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import time
from typing import Any

from amlip_qp.exceptions import AmlipError
from amlip_qp.output_paths import check_output_path, writing
from amlip_qp.profiles import DEFAULT_ROBOT
from amlip_qp.sweep import backends
from amlip_qp.sweep.cells import Cell
from amlip_qp.sweep.run_cell import check_plants, walk_run


def bench_cells(n: int, duration_s: float, tracker: str) -> list[Cell]:
    """``n`` walks of the default robot of ``duration_s`` s with ``tracker`` at speeds spread over 0..1 m/s."""
    fixed = (("robot", DEFAULT_ROBOT), ("tracker", tracker), ("duration", duration_s))
    return [Cell(i, (("vx", round(i / max(n - 1, 1), 6)),), fixed) for i in range(n)]


def throughput(cells: list[Cell], workers: int) -> float:
    """Cells per second of one run of ``cells`` on a new pool of ``workers`` processes."""
    tasks = [c.task() for c in cells]
    t0 = time.perf_counter()
    backends.run_local(tasks, workers, _require_success)
    return len(tasks) / (time.perf_counter() - t0)


def _require_success(record: dict[str, Any]) -> None:
    """A benchmark cell that failed makes the throughput meaningless: stop with its error."""
    if record.get("error"):
        raise AmlipError(f"bench sweep: cell {record['index']} failed: {record['error']}")


def run_bench(args: argparse.Namespace) -> int:
    """``amlip-qp bench sweep``."""
    if args.json not in (None, "-"):
        check_output_path("--json", args.json)
    cells = bench_cells(args.cells, args.duration, args.tracker)
    check_plants([walk_run(c.params, c.seed) for c in cells])  # loads the robot before the pools fork
    load_before = os.getloadavg()
    rows: list[dict[str, Any]] = []
    for r in range(args.repeats):
        one = throughput(cells, 1)
        two = throughput(cells, 2)
        rows.append({"repeat": r, "cells_per_s_1_worker": one, "cells_per_s_2_workers": two, "ratio": two / one})
        sys.stderr.write(f"repeat {r + 1}/{args.repeats}: {one:.3f} vs {two:.3f} cells/s, ratio {two / one:.2f}\n")
    result = {
        "cells": args.cells,
        "duration_s": args.duration,
        "tracker": args.tracker,
        "cores": backends.default_workers(),
        "load_average_before": list(load_before),
        "load_average_after": list(os.getloadavg()),
        "repeats": rows,
        "median_ratio": statistics.median(r["ratio"] for r in rows),
        "goal_ratio": 1.8,
    }
    text = json.dumps(result, indent=2)
    if args.json == "-":
        sys.stdout.write(text + "\n")
        return 0
    if args.json is not None:
        with writing("--json", args.json), open(args.json, "w") as fh:
            fh.write(text + "\n")
    sys.stdout.write(
        f"sweep throughput, {args.cells} cells of {args.duration:g} s ({args.tracker}), {result['cores']} cores: "
        f"median ratio 2 workers / 1 = {result['median_ratio']:.2f} (goal >= 1.8); load average "
        f"{load_before[0]:.2f} before, {result['load_average_after'][0]:.2f} after\n"
    )
    return 0
