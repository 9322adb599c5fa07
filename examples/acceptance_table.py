"""Run every acceptance scenario with both trackers and print the measured table (Markdown).

Usage: ``python examples/acceptance_table.py [--set ideal|cc-ekf|all] [--robots cassie,g1] [--trackers pbc,qp]
[--estimator-columns] [--jobs 2] [--json PATH]``

Each row is one deterministic run (seed 0) of a named scenario of
:data:`amlip_qp.sim.scenarios.named.SCENARIOS`: by default the ideal ones (each
robot's own model, exact sensors, the true base state); ``--set cc-ekf`` the
hardware-like ones (closed-chain plant, robot sensors, invariant EKF, and the
model mismatches; the terrain scenarios have their own table,
``examples/terrain_table.py``); the numbers are the
run summary's (``docs/SUMMARY_SCHEMA.md``): whether the robot fell, the
mean velocity over the last 3 s in the heading frame, the CoM drift (in
place), the yaw change (turn), and the controller tick time; with
``--estimator-columns`` also the foot placement error RMS, the base velocity
estimate's error RMS against the truth, the yaw estimate's error at the end
and the ticks in safe mode (for the ``cc-ekf`` set). The
pass/fail thresholds live in ``tests/test_walk_pbc.py`` and
``tests/test_walk_qp.py``; this script only measures. About 2.5 minutes on
2 cores.
"""

from __future__ import annotations

import argparse
import json
from concurrent.futures import ProcessPoolExecutor

import numpy as np

from amlip_qp.sim.reports.summary import summarize, to_jsonable
from amlip_qp.sim.scenarios.factory import run_scenario
from amlip_qp.sim.scenarios.named import SCENARIOS, TERRAIN_SCENARIOS, ideal_scenarios


def _run(job: tuple[str, str]) -> dict:
    name, tracker = job
    result = run_scenario(SCENARIOS[name], tracker)
    row = summarize(result)
    com = result.log["com"]
    row["drift_m"] = float(np.linalg.norm(com[-1, :2] - com[0, :2]))
    return to_jsonable(row)


def _number(value: float | None, digits: int) -> str:
    """``value`` with ``digits`` decimals; ``-`` where the summary has none (a planar robot's yaw)."""
    return "-" if value is None else f"{value:.{digits}f}"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--trackers", default="pbc,qp", help="comma-separated trackers (default pbc,qp)")
    ap.add_argument("--jobs", type=int, default=2, help="worker processes (default 2)")
    ap.add_argument("--json", default=None, help="also write the rows as JSON to this path")
    ap.add_argument(
        "--set",
        choices=("ideal", "cc-ekf", "all"),
        default="ideal",
        help="which scenarios: ideal (default), cc-ekf (closed-chain plant, robot sensors, EKF) or all",
    )
    ap.add_argument("--robots", default=None, help="comma-separated robots (default: every robot's scenarios)")
    ap.add_argument(
        "--estimator-columns",
        action="store_true",
        help="add the foot placement error, the base estimate's velocity and yaw errors and the safe-mode ticks",
    )
    args = ap.parse_args(argv)
    ideal = ideal_scenarios()
    names = {
        "ideal": ideal,
        "cc-ekf": [n for n in SCENARIOS if n not in ideal and n not in TERRAIN_SCENARIOS],
        "all": list(SCENARIOS),
    }[args.set]
    if args.robots is not None:
        robots = args.robots.split(",")
        unknown = sorted(set(robots) - {SCENARIOS[n].robot for n in SCENARIOS})
        if unknown:
            ap.error(f"no scenarios for robot {unknown[0]!r}")
        names = [n for n in names if SCENARIOS[n].robot in robots]
    jobs = [(name, t) for name in names for t in args.trackers.split(",")]
    jobs.sort(key=lambda j: -SCENARIOS[j[0]].duration_s)  # longest first
    with ProcessPoolExecutor(max_workers=args.jobs) as pool:
        rows = dict(zip(jobs, pool.map(_run, jobs)))
    extra = args.estimator_columns
    print(
        "| scenario | tracker | fell | mean v (x, y) m/s | command m/s | drift m | yaw change deg "
        + ("| foot err m | EKF v err m/s | EKF yaw err deg | safe-mode ticks " if extra else "")
        + "| tick median / p99 µs |"
    )
    print("|---|---|---|---|---|---|---|---|" + ("---|---|---|---|" if extra else ""))
    for name in names:
        for t in args.trackers.split(","):
            r = rows[(name, t)]
            fell = f"yes, {r['fall_time_s']:.1f} s" if r["fell"] else "no"
            vx, vy = r["mean_velocity"]
            cx, cy = r["commanded_velocity"]
            estimate = (
                f"{r['foot_placement_error_rms_m']:.3f} | {_number(r['base_velocity_error_rms_mps'], 4)} | "
                f"{_number(r['yaw_estimate_error_deg'], 2)} | {r['safe_mode_ticks']} | "
                if extra
                else ""
            )
            print(
                f"| {name} | {t} | {fell} | {vx:.3f}, {vy:.3f} | {cx:.2f}, {cy:.2f} | {r['drift_m']:.3f} | "
                f"{r['heading_change_deg']:.1f} | {estimate}"
                f"{r['tick_time_us']['median']:.0f} / {r['tick_time_us']['p99']:.0f} |"
            )
    if args.json:
        with open(args.json, "w") as f:
            json.dump({f"{n}/{t}": r for (n, t), r in rows.items()}, f, indent=2)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
