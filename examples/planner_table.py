"""Walk Cassie with the step-timing MPC and with the one-step law, and print the measured table (Markdown).

Usage: ``python examples/planner_table.py [--rows all|nominal|push|stairs] [--jobs 2] [--json PATH]``

Each row is one ``amlip-qp walk`` command (QP tracker, exact sensors, the
robot's own model), run once with ``--planner one-step`` and once with
``--planner mpc``: the undisturbed 1 m/s walk, the ``cassie-push`` scenario,
forward pushes of 60-100 N s at 3 s (0.2 s long) in a 6-s walk at 1 m/s,
and the terrain-aware 10 cm stairs. The numbers are the run summary's
(``docs/SUMMARY_SCHEMA.md``): whether the robot fell, the steps taken, the
mean velocity over the last 3 s in the heading frame, the velocity error RMS
(steps from 2 s on), the foot placement error RMS and the controller tick's
median. The commands run in this process's interpreter through
:func:`amlip_qp.cli.main`, exactly as typed. About 2 simulated minutes; on 2
free cores about 4 minutes of wall time with one worker.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import shlex
from concurrent.futures import ProcessPoolExecutor

from amlip_qp.cli import main as amlip_qp_main

PLANNERS = ("one-step", "mpc")
#: Forward pushes at 3 s of a 6-s walk at 1 m/s, 0.2 s long: the force in N (impulse = force * 0.2 s).
PUSH_FORCES_N = (300, 325, 350, 400, 450, 500)
PUSH_DURATION_S = 0.2

ROWS: dict[str, list[str]] = {
    "nominal": ["--scenario cassie-1mps --duration 4", "--scenario cassie-push"],
    "push": [f"--scenario cassie-1mps --duration 6 --push 3:{f},0,0:{PUSH_DURATION_S}" for f in PUSH_FORCES_N],
    "stairs": ["--scenario cassie-stairs-10cm"],
}


def _walk(job: tuple[str, str]) -> dict:
    """The JSON summary of ``amlip-qp walk ARGS --planner PLANNER``."""
    args, planner = job
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        status = amlip_qp_main(["walk", *shlex.split(args), "--planner", planner, "--json", "-", "--no-progress"])
    if status not in (0, 1):  # 1: the robot fell, the summary is still written
        raise RuntimeError(f"amlip-qp walk {args} --planner {planner} exited {status}")
    return json.loads(out.getvalue())


def _impulse(args: str) -> str:
    """`` (60 N s)`` for a walk with a push option, else nothing."""
    if "--push" not in args:
        return ""
    force_n = float(args.split("--push ")[1].split(":")[1].split(",")[0])
    duration_s = float(args.split("--push ")[1].split(":")[2])
    return f" ({force_n * duration_s:.0f} N s)"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rows", choices=("all", *ROWS), default="all", help="which walks (default all)")
    ap.add_argument("--jobs", type=int, default=2, help="worker processes (default 2)")
    ap.add_argument("--json", default=None, help="also write the summaries as JSON to this path")
    args = ap.parse_args(argv)
    if not 1 <= args.jobs <= 64:
        ap.error(f"--jobs must be 1 to 64, got {args.jobs}")
    walks = [w for key, ws in ROWS.items() if args.rows in ("all", key) for w in ws]
    jobs = [(w, p) for w in walks for p in PLANNERS]
    with ProcessPoolExecutor(max_workers=args.jobs) as pool:
        rows = dict(zip(jobs, pool.map(_walk, jobs)))
    print(
        "| command | planner | result | steps | mean v, m/s | velocity error RMS, m/s"
        " | foot placement error RMS, m | controller tick median, µs |"
    )
    print("|---|---|---|---|---|---|---|---|")
    for w, p in jobs:
        r = rows[(w, p)]
        if r["fell"]:
            result, v, v_err = f"**fell at {r['fall_time_s']:.2f} s**", "", ""
        else:
            result, v = "walked", f"{r['mean_velocity'][0]:.3f}"
            v_err = "" if r["velocity_error_rms"] is None else f"{r['velocity_error_rms']:.3f}"
        print(
            f"| `amlip-qp walk {w} --planner {p}`{_impulse(w)} | {p} | {result} | {r['steps']} | {v} | {v_err} | "
            f"{r['foot_placement_error_rms_m']:.3f} | {r['tick_time_us']['median']:.0f} |"
        )
    if args.json:
        with open(args.json, "w") as f:
            json.dump({f"{w} --planner {p}": r for (w, p), r in rows.items()}, f, indent=2)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
