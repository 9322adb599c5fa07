"""Walk step commands from rest with both trackers and print the measured table (Markdown).

Usage: ``python examples/step_commands.py [--jobs 2]``

Each case of :data:`CASES` is exactly ``amlip-qp walk --robot R --tracker T --vx V``:
the CLI's scenario (the robot's default gait, 10 s, a constant ``--vx`` from
t = 0, i.e. a step from rest), built and summarised as the CLI does. The
command shaping (:mod:`amlip_qp.alip.command_shaping`) turns the step into a
ramp. One row per robot and command: the mean forward speed over the last 3 s
(the summary's ``mean_velocity[0]``, heading frame) with each tracker, or when
it fell. ``tests/test_walk_step_commands.py`` walks the same cases and asserts
each within 0.1 m/s of its command; this script only measures. Deterministic:
the same arguments give the same table.
"""

from __future__ import annotations

import argparse
from concurrent.futures import ProcessPoolExecutor

from amlip_qp.cli import build_parser
from amlip_qp.experiments.walk import scenario_from_args
from amlip_qp.sim.reports import summary
from amlip_qp.sim.scenarios import factory

#: The trackers, in the table's column order.
TRACKERS = ("pbc", "qp")
#: Per robot, the step commands from rest, m/s (forward, ``--vx``).
COMMANDS_MPS: tuple[tuple[str, tuple[float, ...]], ...] = (
    ("cassie", (1.0, 2.0, 2.5, -0.5)),
    ("rabbit", (0.5, 0.8, 1.0)),
)
#: (robot, tracker, vx m/s): every tracker walks every step command.
CASES: tuple[tuple[str, str, float], ...] = tuple(
    (robot, tracker, vx) for tracker in TRACKERS for robot, speeds in COMMANDS_MPS for vx in speeds
)


def walk(case: tuple[str, str, float]) -> dict:
    """``amlip-qp walk --robot R --tracker T --vx V``; the summary's numbers only (picklable)."""
    robot, tracker, vx = case
    args = build_parser().parse_args(["walk", "--robot", robot, "--tracker", tracker, f"--vx={vx}"])
    scenario = scenario_from_args(args)
    result = factory.build_simulation(scenario, args.tracker, seed=args.seed).run(scenario.duration_s)
    s = summary.summarize(result)
    return {
        "fell": s["fell"],
        "fall_time_s": s["fall_time_s"],
        "sim_time_s": s["sim_time_s"],
        "duration_s": scenario.duration_s,
        "mean_vx_mps": s["mean_velocity"][0],
    }


def cost(case: tuple[str, str, float]) -> float:
    """Relative wall time (Cassie's PBC is the slowest): run the slowest first."""
    robot, tracker, _ = case
    return (3.0 if robot == "cassie" else 1.0) * (1.5 if tracker == "pbc" else 1.0)


def walk_all(cases: list[tuple[str, str, float]], jobs: int) -> dict[tuple[str, str, float], dict]:
    """Every case, the slowest first, on ``jobs`` worker processes (in this process when 1)."""
    todo = sorted(dict.fromkeys(cases), key=cost, reverse=True)
    if jobs == 1:
        return {case: walk(case) for case in todo}
    with ProcessPoolExecutor(max_workers=jobs) as pool:
        return dict(zip(todo, pool.map(walk, todo)))


def _cell(r: dict) -> str:
    return f"fell at {r['fall_time_s']:.2f} s" if r["fell"] else f"{r['mean_vx_mps']:.3f}"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--jobs", type=int, default=2, help="worker processes, 1 to 64 (default 2)")
    args = ap.parse_args(argv)
    if not 1 <= args.jobs <= 64:
        ap.error(f"--jobs must be 1 to 64, got {args.jobs}")
    rows = walk_all(list(CASES), args.jobs)
    print("| robot | command m/s | " + " | ".join(f"{t.upper()} m/s" for t in TRACKERS) + " |")
    print("|---|---|" + "---|" * len(TRACKERS))
    for robot, speeds in COMMANDS_MPS:
        for vx in speeds:
            cells = " | ".join(_cell(rows[(robot, t, vx)]) for t in TRACKERS)
            print(f"| {robot} | {vx:.1f} | {cells} |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
