"""Run the paper's claims, and past them, on the hardware-like setting and print the measured table (Markdown).

Usage: ``python examples/paper_claims.py [--seeds 0,1,2,3] [--jobs 2] [--json PATH]``

Cassie, QP tracker, on the ``cc-ekf`` setting (closed-chain plant, the
robot's sensors with noise, the invariant EKF), one row per run
(``run_scenario(scenario, "qp", seed=S)``):

- the four named scenarios judged by ``tests/test_walk_paper_claims.py``:
  ``cassie-3mps-cc-ekf`` (ramp to 3 m/s), ``cassie-diagonal-1mps-cc-ekf``
  (1 m/s forward and 1 m/s sideways), ``cassie-turn-90-1mps-cc-ekf`` (90 deg
  at 45 deg/s at 1 m/s) and ``cassie-waves-60cm-valley-cc-ekf`` (along the
  valley between 60 cm ridges), each with the noise seeds ``--seeds``;
- the valley scenario turned across the ridges (``waves:0.6:2.25``), seeds 0-7;
  with seed 0 also terrain-aware, with a 0.35 m clearance and with ideal
  sensors on the robot's own model; and across lower ridges (45 and 30 cm).

Columns: whether the robot fell and when, the mean velocity over the last 3 s in the heading
frame (the CoM's, simulator truth), the range of the 1-s means of the forward
speed from the row's ``from`` time on (the command reached), the base yaw at
the end, the CoM's farthest point along the path and its range sideways
(the valley's floor line is y = 0), across the ridges how many crests the
CoM passed (the first is at x = 2.125 m) and,
for the diagonal walk, how far apart the feet land over the last 5 s
(lateral, stance to swing foot; negative: crossed). The pass/fail thresholds
live in the test; this script only measures. About 5 simulated minutes with
the default seeds; on 2 free cores about 11 minutes of wall time with one
worker.
"""

from __future__ import annotations

import argparse
import json
import math
from concurrent.futures import ProcessPoolExecutor
from dataclasses import replace

import numpy as np

from amlip_qp.sim.scenarios.factory import run_scenario
from amlip_qp.sim.scenarios.named import SCENARIOS
from amlip_qp.sim.world.terrain import parse_terrain

VALLEY = "cassie-waves-60cm-valley-cc-ekf"
ACROSS = "waves:0.6:2.25"
#: The named walks and the time (s) from which their 1-s means are reported (the command reached).
NAMED = {
    "cassie-3mps-cc-ekf": 15.0,
    "cassie-diagonal-1mps-cc-ekf": 3.0,
    "cassie-turn-90-1mps-cc-ekf": 3.0,
    VALLEY: 3.0,
}
#: Variants of the valley scenario across the ridges, seed 0: label -> changes to its plant setting.
ACROSS_VARIANTS: dict[str, dict] = {
    "terrain-aware": {"terrain": ACROSS, "terrain_aware": True},
    "clearance 0.35 m": {"terrain": ACROSS, "clearance_m": 0.35},
    "ideal sensors, own model": {"terrain": ACROSS, "plant": None, "sensors": "ideal", "estimator": "truth"},
    "45 cm ridges (flanks 32°)": {"terrain": "waves:0.45:2.25"},
    "30 cm ridges (flanks 23°)": {"terrain": "waves:0.3:2.25"},
}


def _crests_passed(terrain: str, x_max_m: float) -> int:
    """How many crests of ``terrain`` lie along the path (y = 0) between x = 0 and ``x_max_m``."""
    if not terrain.startswith("waves:"):
        return 0
    spec = parse_terrain(terrain)
    x = np.arange(0.0, max(x_max_m, 0.0) + 1e-3, 0.005)
    z = np.array([spec.height_m(float(xi), 0.0) for xi in x])
    return int(np.sum((z[1:-1] > z[:-2]) & (z[1:-1] >= z[2:]) & (z[1:-1] > 1e-6)))


def _run(job: tuple[str, str, int]) -> dict:
    """One run's numbers (picklable): job = (scenario, variant label or "", seed)."""
    name, variant, seed = job
    sc = SCENARIOS[name]
    if variant == "across":
        sc = replace(sc, setting=replace(sc.setting, terrain=ACROSS))
    elif variant:
        sc = replace(sc, setting=replace(sc.setting, **ACROSS_VARIANTS[variant]))
    res = run_scenario(sc, "qp", seed=seed)
    log = res.log
    t, heading, vel, com = log["t"], log["heading"], log["com_vel"], log["com"]
    vx = vel[:, 0] * np.cos(heading) + vel[:, 1] * np.sin(heading)
    vy = -vel[:, 0] * np.sin(heading) + vel[:, 1] * np.cos(heading)
    last = t > t[-1] - 3.0
    v_from = NAMED.get(name, 0.0) if not variant else 0.0
    per_s = [float(np.mean(vx[(t >= k) & (t < k + 1)])) for k in range(int(v_from), int(math.floor(t[-1])))]
    gaps = []
    for prev, step in zip(res.steps[:-1], res.steps[1:]):
        if step.t_start_s < sc.duration_s - 5.0:
            continue
        d = np.asarray(prev.swing_actual_m[:2]) - np.asarray(step.swing_actual_m[:2])
        lateral = -d[0] * math.sin(step.heading_rad) + d[1] * math.cos(step.heading_rad)
        gaps.append(float(lateral if step.stance == "left" else -lateral))
    x_max = float(np.max(com[:, 0]))
    return {
        "scenario": name,
        "variant": variant,
        "seed": seed,
        "terrain": sc.setting.terrain,
        "fell": bool(res.fell),
        "sim_time_s": float(res.sim_time_s),
        "vx_mps": float(np.mean(vx[last])),
        "vy_mps": float(np.mean(vy[last])),
        "v_from_s": v_from,
        "vx_per_s": per_s,
        "yaw_end_deg": float(np.degrees(np.unwrap(log["base_yaw"])[-1])),
        "com_x_max_m": x_max,
        "com_y_m": [float(np.min(com[:, 1])), float(np.max(com[:, 1]))],
        "crests_passed": _crests_passed(sc.setting.terrain, x_max),
        "foot_gap_m": [min(gaps), max(gaps)] if gaps and "diagonal" in name else None,
    }


def _label(r: dict) -> str:
    if not r["variant"]:
        return f"`{r['scenario']}`"
    if r["variant"] == "across":
        return f"across the ridges (`{ACROSS}`)"
    return f"across: {r['variant']} (`{r['terrain']}`)" if "ridges" in r["variant"] else f"across: {r['variant']}"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", default="0,1,2,3", help="noise seeds of the named walks (default 0,1,2,3)")
    ap.add_argument("--across-seeds", default="0,1,2,3,4,5,6,7", help="noise seeds across the ridges (default 0-7)")
    ap.add_argument("--jobs", type=int, default=2, help="worker processes (default 2)")
    ap.add_argument("--json", default=None, help="also write the rows as JSON to this path")
    args = ap.parse_args(argv)
    if not 1 <= args.jobs <= 64:
        ap.error(f"--jobs must be 1 to 64, got {args.jobs}")
    try:
        seeds = [int(s) for s in args.seeds.split(",")]
        across_seeds = [int(s) for s in args.across_seeds.split(",")]
    except ValueError:
        ap.error(
            f"--seeds and --across-seeds take comma-separated integers, got {args.seeds!r} and {args.across_seeds!r}"
        )
    if min(seeds + across_seeds) < 0 or len(seeds) + len(across_seeds) > 64:
        ap.error("seeds must be integers >= 0, at most 64 of them in all")
    jobs = [(name, "", s) for name in NAMED for s in seeds]
    jobs += [(VALLEY, "across", s) for s in across_seeds]
    jobs += [(VALLEY, v, 0) for v in ACROSS_VARIANTS]
    order = sorted(jobs, key=lambda j: -SCENARIOS[j[0]].duration_s if not j[1] else 0.0)  # longest first
    with ProcessPoolExecutor(max_workers=args.jobs) as pool:
        rows = dict(zip(order, pool.map(_run, order)))
    print(
        "| run | seed | result | mean v (x, y), last 3 s m/s | 1-s means of v_x m/s (from) | yaw at end deg"
        " | CoM x farthest m | CoM y range m | crests passed | feet apart, last 5 s m |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|")
    for job in jobs:
        r = rows[job]
        result = f"**fell at {r['sim_time_s']:.2f} s**" if r["fell"] else "walked"
        per_s = r["vx_per_s"]
        means = f"{min(per_s):.3f}–{max(per_s):.3f} ({r['v_from_s']:.0f} s)" if per_s and not r["fell"] else ""
        crests = str(r["crests_passed"]) if r["variant"] else ""
        gap = "" if r["foot_gap_m"] is None else f"{r['foot_gap_m'][0]:.3f}–{r['foot_gap_m'][1]:.3f}"
        print(
            f"| {_label(r)} | {r['seed']} | {result} | {r['vx_mps']:.3f}, {r['vy_mps']:.3f} | {means} | "
            f"{r['yaw_end_deg']:.1f} | {r['com_x_max_m']:.2f} | {r['com_y_m'][0]:.2f} / {r['com_y_m'][1]:.2f} | "
            f"{crests} | {gap} |"
        )
    if args.json:
        with open(args.json, "w") as f:
            json.dump([rows[j] for j in jobs], f, indent=2)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
