"""The humanoids' QP walks with four force points per foot against the bundled two-point sole line.

Usage: ``python examples/four_point_feet.py [--robots g1,h1] [--jobs 2]``

Each four-point profile is the bundled one with its ``[feet]`` sole line replaced by a sole of
:data:`SOLES` (written into a temporary folder by :func:`sole_profile`; the tests build theirs
with the same function). G1's sole: its four Menagerie foot spheres, at x = 0.12 m
(y = +-0.03 m) and x = -0.05 m (y = +-0.025 m), 0.035 m below the ankle. H1's: the rectangle of
its toe bar (y = -0.03 to 0.03 m at x = 0.14 m) and heel capsule (x = -0.035 m), 0.07 m below
the ankle, and the triangle of the toe bar's ends and the one heel capsule. Every sole walks
three commands with the QP tracker, exactly as ``amlip-qp walk --robot ROBOT --tracker qp``
with :data:`COMMANDS` (``ROBOT`` the robot's name, or the four-point profile's path); the push
is the force of the robot's ``push`` scenario (:data:`PUSH_N`) for 0.2 s at 6 s. One row per
robot and sole: the mean velocity over the last 3 s (heading frame) and the foot placement
error RMS, or when the walk fell. Deterministic: the same arguments give the same table.
"""

from __future__ import annotations

import argparse
import tempfile
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

from amlip_qp.cli import build_parser
from amlip_qp.experiments.walk import scenario_from_args
from amlip_qp.paths import MODELS_DIR
from amlip_qp.sim.reports import summary
from amlip_qp.sim.scenarios import factory

#: Per robot: its bundled two-point sole line (the profile's TOML line), then the four-point soles
#: that replace it, by name; the first is the one the tests walk.
SOLES: dict[str, tuple[str, dict[str, str]]] = {
    "g1": (
        "force_points_m = [[0.12, 0.0, -0.035], [-0.05, 0.0, -0.035]]",
        {
            "four spheres": "force_points_m = [[0.12, 0.03, -0.035], [0.12, -0.03, -0.035], "
            "[-0.05, 0.025, -0.035], [-0.05, -0.025, -0.035]]",
        },
    ),
    "h1": (
        "force_points_m = [[0.14, 0.0, -0.07], [-0.035, 0.0, -0.07]]",
        {
            "rectangle": "sole_rectangle_m = { x_front = 0.14, x_back = -0.035, half_width = 0.03, z = -0.07 }",
            "triangle": "force_points_m = [[0.14, 0.03, -0.07], [0.14, -0.03, -0.07], [-0.035, 0.0, -0.07], "
            "[-0.035, 0.0, -0.07]]",
        },
    ),
}
#: The bundled sole line's name in the table.
LINE = "line (bundled)"
#: Per robot: the force of its ``push`` scenario, N (0.2 s, forward).
PUSH_N = {"g1": 60.0, "h1": 150.0}
#: The table's columns: (heading, the walk's options; ``{F}`` the robot's push force).
COMMANDS: tuple[tuple[str, str], ...] = (
    ("1 m/s, 10 s", "--speed-profile 0:0,1:0,3:1 --duration 10"),
    ("in place, 20 s", "--duration 20"),
    ("push at 6 s, 10 s", "--speed-profile 0:0,1:0,3:1 --push 6:{F},0,0:0.2 --duration 10"),
)


def sole_profile(robot: str, folder: Path, sole: str | None = None) -> Path:
    """Write bundled ``robot``'s profile with sole ``sole`` (default: its first) into ``folder``; its path.

    Raises:
        ValueError: The bundled profile no longer holds the sole line this replaces.
    """
    line, soles = SOLES[robot]
    sole = sole or next(iter(soles))
    text = (MODELS_DIR / f"{robot}.toml").read_text()
    if line not in text:
        raise ValueError(f"{robot}.toml no longer has the sole line {line!r}")
    text = text.replace(line, soles[sole]).replace('file = "unitree_', f'file = "{MODELS_DIR}/unitree_')
    path = Path(folder) / f"{robot}_{sole.replace(' ', '_')}.toml"
    path.write_text(text)
    return path


def walk_argv(robot: str, profile: str, options: str) -> list[str]:
    """``amlip-qp walk``'s arguments for one cell (``profile``: the robot's name or a profile's path)."""
    return ["walk", "--robot", profile, "--tracker", "qp", *options.replace("{F}", f"{PUSH_N[robot]:g}").split()]


def walk(argv: list[str]) -> dict:
    """One walk as the CLI builds it; the summary's numbers the table shows (picklable)."""
    args = build_parser().parse_args(argv)
    scenario = scenario_from_args(args)
    s = summary.summarize(factory.build_simulation(scenario, args.tracker, seed=args.seed).run(scenario.duration_s))
    keys = ("fell", "fall_time_s", "mean_velocity", "foot_placement_error_rms_m", "fallback_ticks")
    return {k: s[k] for k in keys}


def cell(r: dict) -> str:
    vx, vy = r["mean_velocity"]
    numbers = f"{vx:.3f}, {vy:.3f} / {r['foot_placement_error_rms_m']:.3f}"
    return f"fell at {r['fall_time_s']:.2f} s ({numbers})" if r["fell"] else numbers


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="four_point_feet.py", description=__doc__.splitlines()[0])
    ap.add_argument("--robots", default="g1,h1", help=f"comma-separated robots of {', '.join(SOLES)} (default all)")
    ap.add_argument("--jobs", type=int, default=2, help="worker processes, 1 to 64 (default 2)")
    args = ap.parse_args(argv)
    robots = [r for r in args.robots.split(",") if r]
    if not robots or any(r not in SOLES for r in robots):
        ap.error(f"--robots takes robots of {', '.join(SOLES)}, got {args.robots!r}")
    if not 1 <= args.jobs <= 64:
        ap.error(f"--jobs must be 1 to 64, got {args.jobs}")
    with tempfile.TemporaryDirectory(prefix="four_point_feet_") as tmp:
        rows = [(r, LINE, r) for r in robots]
        rows += [(r, name, str(sole_profile(r, Path(tmp), name))) for r in robots for name in SOLES[r][1]]
        rows.sort(key=lambda row: (robots.index(row[0]), row[1] != LINE))
        cases = [walk_argv(robot, profile, options) for robot, _, profile in rows for _, options in COMMANDS]
        if args.jobs == 1:
            results = [walk(c) for c in cases]
        else:
            with ProcessPoolExecutor(max_workers=args.jobs) as pool:
                results = list(pool.map(walk, cases))
    heading = " | ".join(f"{h}: mean v (x, y) m/s / foot placement error RMS m" for h, _ in COMMANDS)
    print(f"| robot | feet | {heading} |")
    print("|---|---|" + "---|" * len(COMMANDS))
    for i, (robot, name, _) in enumerate(rows):
        cells = " | ".join(cell(r) for r in results[i * len(COMMANDS) : (i + 1) * len(COMMANDS)])
        print(f"| {robot} | {name} | {cells} |")
    fallbacks = sum(r["fallback_ticks"] for r in results)
    print(f"\nQP fallback ticks over the {len(results)} walks: {fallbacks}.")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
