"""The terrain map: does each tracker walk up and down each slope at each speed? Run it and print the table.

Runs the shipped spec (``examples/sweeps/terrain_map.toml``: Cassie, blind,
10-s walks from rest, slopes of -15 to 15 degrees starting 1 m ahead, commanded
speeds of 0.25-1 m/s, both trackers: 56 walks) with ``amlip-qp sweep`` into a
new temporary folder (or ``--out``; a finished sweep there resumes), or reads a
finished sweep folder (``--from``), and prints a Markdown table: one row per
tracker and slope, one column per speed, each cell the mean forward speed
over the last 3 s of the walk (m/s) or when it fell. ``--figure`` copies the
sweep's heat map (``map_heat.png``: survived, per tracker) there::

    python examples/terrain_map.py --workers 1
    python examples/terrain_map.py --from out/terrain_map --figure docs/media/terrain_map.png

About 4 minutes on 2 free cores with 2 workers; the sweep's own messages go
to stderr, so the standard output is only the table.
"""

from __future__ import annotations

import argparse
import contextlib
import csv
import shutil
import sys
import tempfile
from pathlib import Path

from amlip_qp.cli import main as amlip_qp_main

SPEC = Path(__file__).resolve().parent / "sweeps" / "terrain_map.toml"
FIGURE = "map_heat.png"


def _slope_deg(terrain: str) -> float:
    return 0.0 if terrain == "flat" else float(terrain.split(":")[1])


def table(folder: Path) -> str:
    """The Markdown table of a finished terrain-map sweep in ``folder``."""
    with open(folder / "results.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    speeds = sorted({float(r["vx"]) for r in rows})
    trackers = list(dict.fromkeys(r["tracker"] for r in rows))
    terrains = sorted({r["terrain"] for r in rows}, key=_slope_deg)
    cells = {(r["tracker"], r["terrain"], float(r["vx"])): r for r in rows}
    lines = ["| tracker | slope | " + " | ".join(f"{v:g} m/s" for v in speeds) + " |"]
    lines.append("|---|---|" + "---|" * len(speeds))
    for t in trackers:
        for terrain in terrains:
            out = []
            for v in speeds:
                r = cells[(t, terrain, v)]
                if r["error"]:
                    out.append("error")
                elif r["survived"] == "true":
                    out.append(f"{float(r['mean_vx_mps']):.2f}")
                else:
                    out.append(f"**fell at {float(r['fall_time_s']):.2f} s**")
            lines.append(f"| {t} | {_slope_deg(terrain):g}° | " + " | ".join(out) + " |")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    where = parser.add_mutually_exclusive_group()
    where.add_argument("--out", type=Path, help="run the sweep into this folder (default: a new temporary one)")
    where.add_argument("--from", dest="source", type=Path, help="print the table of this finished sweep folder")
    parser.add_argument("--workers", type=int, default=None, help="worker processes (default: one per core)")
    parser.add_argument("--figure", type=Path, default=None, help=f"copy the sweep's {FIGURE} to this path")
    args = parser.parse_args(argv)
    if args.workers is not None and not 1 <= args.workers <= 64:
        parser.error(f"--workers must be 1 to 64, got {args.workers}")
    with tempfile.TemporaryDirectory(prefix="terrain_map_") as tmp:
        folder = args.source or args.out or Path(tmp)
        if args.source is None:
            extra = ["--workers", str(args.workers)] if args.workers else []
            with contextlib.redirect_stdout(sys.stderr):
                code = amlip_qp_main(["sweep", str(SPEC), "--out", str(folder), "--no-progress", *extra])
            if code != 0:
                return code
        if not (folder / "results.csv").is_file():
            sys.stderr.write(f"terrain_map.py: error: {folder} has no results.csv; run the sweep first\n")
            return 2
        print(table(folder))
        if args.figure is not None:
            args.figure.parent.mkdir(parents=True, exist_ok=True)
            shutil.copyfile(folder / FIGURE, args.figure)
    return 0


if __name__ == "__main__":
    sys.exit(main())
