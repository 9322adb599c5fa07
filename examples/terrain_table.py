"""Run the terrain scenarios with both trackers and print the measured table (Markdown).

Usage: ``python examples/terrain_table.py [--trackers pbc,qp] [--scenarios NAME,...] [--jobs 2] [--json PATH]``

Each row is one deterministic run of a terrain scenario of
:data:`amlip_qp.sim.scenarios.named.TERRAIN_SCENARIOS`: terrain,
tracker, mode (blind or terrain-aware), whether the robot fell, the mean
speed over the last 3 s (horizontal, along the heading) against the command,
and the foot placement error RMS (touchdown against the planner's target,
horizontal). The pass/fail thresholds live in ``tests/test_walk_terrain.py``;
this script only measures. About 15 simulated minutes in all; on 2 free
cores about as long in wall time.
"""

from __future__ import annotations

import argparse
import json
from concurrent.futures import ProcessPoolExecutor

from amlip_qp.sim.reports.summary import summarize, to_jsonable
from amlip_qp.sim.scenarios.factory import run_scenario
from amlip_qp.sim.scenarios.named import TERRAIN_SCENARIOS


def _run(job: tuple[str, str]) -> dict:
    name, tracker = job
    return to_jsonable(summarize(run_scenario(TERRAIN_SCENARIOS[name], tracker)))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--trackers", default="pbc,qp", help="comma-separated trackers (default pbc,qp)")
    ap.add_argument("--scenarios", default=None, help="comma-separated terrain scenarios (default: all)")
    ap.add_argument("--jobs", type=int, default=2, help="worker processes (default 2)")
    ap.add_argument("--json", default=None, help="also write the rows as JSON to this path")
    args = ap.parse_args(argv)
    names = args.scenarios.split(",") if args.scenarios else list(TERRAIN_SCENARIOS)
    unknown = [n for n in names if n not in TERRAIN_SCENARIOS]
    if unknown:
        ap.error(f"not terrain scenarios: {', '.join(unknown)}; known: {', '.join(TERRAIN_SCENARIOS)}")
    trackers = args.trackers.split(",")
    jobs = [(name, t) for name in names for t in trackers]
    jobs.sort(key=lambda j: -TERRAIN_SCENARIOS[j[0]].duration_s)  # longest first
    with ProcessPoolExecutor(max_workers=args.jobs) as pool:
        rows = dict(zip(jobs, pool.map(_run, jobs)))
    print(
        "| scenario | terrain | tracker | mode | fell | speed, last 3 s m/s | command m/s"
        " | foot placement error RMS m |"
    )
    print("|---|---|---|---|---|---|---|---|")
    for name in names:
        sc = TERRAIN_SCENARIOS[name]
        mode = "aware" if sc.setting.terrain_aware else "blind"
        for t in trackers:
            r = rows[(name, t)]
            fell = f"yes, {r['fall_time_s']:.1f} s" if r["fell"] else "no"
            print(
                f"| {name} | {sc.setting.terrain} | {t} | {mode} | {fell} | {r['mean_velocity'][0]:.3f} | "
                f"{sc.vx.final_mps:.2f} | {r['foot_placement_error_rms_m']:.3f} |"
            )
    if args.json:
        with open(args.json, "w") as f:
            json.dump({f"{n}/{t}": r for (n, t), r in rows.items()}, f, indent=2)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
