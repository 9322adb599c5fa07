"""Walk a named scenario from 16 starts that differ in the last bits: how robust is a pass?

Usage: ``python examples/raised_starts.py [--scenario cassie-stairs-10cm] [--tracker qp]
[--planner one-step|mpc|one-step,mpc] [--starts 16] [--forward M] [--duration S] [--jobs 1]``

Start ``k`` (``k = 0 .. starts - 1``) raises the base by ``k`` x 1e-12 m before
the first tick: the walks are the same to rounding, so which of them fall shows
whether the scenario passes by a margin or by luck of the bits. With
``--forward M`` start ``k`` instead moves the robot forward (world x) by ``k`` x
``M`` m: on stairs, how the gait meets the edges (16 starts 0.02 m apart
cover a 0.3 m tread). Prints a Markdown table, one row per start and two
columns per planner (fell, with the fall time, and the forward speed over the
last 3 s in the heading frame), then for each planner the count that walked.
Deterministic: the same arguments give the same table.
"""

from __future__ import annotations

import argparse
from concurrent.futures import ProcessPoolExecutor

from amlip_qp.sim.reports.summary import mean_velocity_heading
from amlip_qp.sim.scenarios.factory import build_simulation
from amlip_qp.sim.scenarios.named import SCENARIOS
from amlip_qp.sim.scenarios.options import PLANNERS

#: How far start k raises the base, per k, m.
RAISE_M = 1e-12


def walk_from(job: tuple) -> tuple[int, bool, float, float]:
    """``(k, fell, fall time s (NaN if it walked), forward speed over the last 3 s m/s)`` of the job
    ``(scenario, tracker, planner, duration s or None, k[, forward m])``: the start raised by ``k`` x
    :data:`RAISE_M`, or, with a forward step other than 0, moved forward by ``k`` times it."""
    name, tracker, planner, duration_s, k, *forward = job
    forward_m = forward[0] if forward else 0.0
    sc = SCENARIOS[name] if duration_s is None else SCENARIOS[name].with_(duration_s=duration_s)
    sim = build_simulation(sc, tracker, planner=planner)
    if forward_m:
        sim.data.qpos[0] += k * forward_m
    else:
        sim.data.qpos[2] += k * RAISE_M
    res = sim.run(sc.duration_s, log="summary")
    return k, bool(res.fell), float(res.fall_time_s), float(mean_velocity_heading(res, 3.0)[0])


def _fell(fell: bool, t_fall_s: float) -> str:
    return f"yes, {t_fall_s:.2f} s" if fell else "no"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenario", default="cassie-stairs-10cm", choices=sorted(SCENARIOS), metavar="NAME")
    ap.add_argument("--tracker", default="qp", choices=("qp", "pbc"))
    ap.add_argument(
        "--planner",
        default="one-step",
        help=f"planner, or comma-separated planners side by side: {', '.join(PLANNERS)} (default one-step)",
    )
    ap.add_argument("--starts", type=int, default=16, help="number of starts, 1 to 100 (default 16)")
    ap.add_argument(
        "--forward", type=float, default=0.0, help="move start k forward by k times this, m, instead of raising it"
    )
    ap.add_argument("--duration", type=float, default=None, help="simulated time, s (default: the scenario's)")
    ap.add_argument("--jobs", type=int, default=1, help="worker processes, 1 to 64 (default 1)")
    args = ap.parse_args(argv)
    planners = list(dict.fromkeys(args.planner.split(",")))
    unknown = [p for p in planners if p not in PLANNERS]
    if unknown or not planners:
        ap.error(f"--planner: unknown planner {', '.join(unknown) or '(none)'}; known: {', '.join(PLANNERS)}")
    if not 1 <= args.starts <= 100:
        ap.error(f"--starts must be 1 to 100, got {args.starts}")
    if not 1 <= args.jobs <= 64:
        ap.error(f"--jobs must be 1 to 64, got {args.jobs}")
    if not 0.0 <= args.forward <= 0.1:
        ap.error(f"--forward must be 0 to 0.1 m, got {args.forward}")
    if args.duration is not None and not 0.0 < args.duration <= SCENARIOS[args.scenario].duration_s:
        ap.error(f"--duration must be above 0 and at most the scenario's {SCENARIOS[args.scenario].duration_s:g} s")
    jobs = [
        (args.scenario, args.tracker, p, args.duration, k, args.forward) for p in planners for k in range(args.starts)
    ]
    if args.jobs == 1:
        runs = [walk_from(job) for job in jobs]
    else:
        with ProcessPoolExecutor(max_workers=args.jobs) as pool:
            runs = list(pool.map(walk_from, jobs))
    by_planner = {p: runs[i * args.starts : (i + 1) * args.starts] for i, p in enumerate(planners)}
    print("| k | " + " | ".join(f"{p}: fell | {p}: forward speed, last 3 s, m/s" for p in planners) + " |")
    print("|---|" + "---|---|" * len(planners))
    for k in range(args.starts):
        cells = [f"{_fell(fell, t_fall)} | {vx:.3f}" for _, fell, t_fall, vx in (by_planner[p][k] for p in planners)]
        print(f"| {k} | " + " | ".join(cells) + " |")
    for p in planners:
        walked = sum(not fell for _, fell, _, _ in by_planner[p])
        print(f"\n{args.scenario} / {args.tracker} / {p}: {walked} of {args.starts} starts walked")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
