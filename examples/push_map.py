"""The push map: the largest push survived over direction x phase of the step, per tracker or planner, and their ratio.

Runs the shipped spec (``examples/sweeps/push_map.toml``: Cassie at 1 m/s,
0.2 s pushes, 8 directions x 5 phases, bisection of the impulse, both
trackers) with ``amlip-qp sweep`` into ``--out``, or reads a finished sweep
folder (``--from``), and draws one polar heat map per tracker (the largest
impulse survived, N s; direction from forward, drawn up, towards left; phase
as the radius) and one of their ratio (QP / PBC). It prints the summary as
a Markdown table (per tracker the median, mean, least and largest impulse
survived over the cells, the cells at the top of the range and those where
it survives more than the other tracker), then one line with the per-cell
ratio QP / PBC and the sweep's cost. A sweep whose cells vary the planner
(``examples/sweeps/push_map_planners.toml``: the QP tracker with the
one-step law and with the step-timing MPC) is compared by planner instead,
MPC / one-step, with the ratios of the medians and of the weakest cells.
``--against CSV`` adds the cells of another push-map sweep's ``results.csv``
for the sweep's trackers and the groups the sweep lacks (a row without a
planner is the one-step law's), so that the MPC's cells are compared with
one-step cells measured before instead of running them again (e.g. the PBC's
MPC half alone, ``amlip-qp sweep examples/sweeps/push_map_planners_pbc.toml
--grid planner=mpc --out out/pbc_mpc_only``, against the PBC's one-step cells
of ``docs/media/push_map_results.csv``; compare maps of the same bisection)::

    python examples/push_map.py --out out/push_map              # run the sweep (resumes), then draw
    python examples/push_map.py --from out/push_map --figure docs/media/push_map.png
    python examples/push_map.py --spec examples/sweeps/push_map_planners.toml --out out/push_map_planners
    python examples/push_map.py --spec examples/sweeps/push_map_planners_pbc.toml --out out/push_map_planners_pbc
    python examples/push_map.py --from out/pbc_mpc_only --against docs/media/push_map_results.csv

``--out`` does not run a sweep its folder already holds finished (every cell
measured, none failed): it draws it, and the sweep's own wall time stays in
its ``summary.json``; delete the folder to measure again. ``--csv PATH``
copies the sweep's ``results.csv`` to ``PATH``.
"""

from __future__ import annotations

import argparse
import contextlib
import csv
import json
import shutil
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from matplotlib.colors import TwoSlopeNorm

from amlip_qp.cli import main as amlip_qp_main
from amlip_qp.exceptions import InputError
from amlip_qp.output_paths import check_output_path
from amlip_qp.sweep.figures import grid_values, polar_map

SPEC = Path(__file__).resolve().parent / "sweeps" / "push_map.toml"
VALUE = "max_push_impulse_Ns"
#: How the groups a map compares are named in its tables and figures.
LABELS = {"pbc": "PBC", "qp": "QP", "mpc": "MPC"}


def read_records(folder: Path) -> list[dict]:
    """The rows of ``folder/results.csv`` as records ``{"params": ..., "metrics": ...}`` (numbers parsed)."""
    return read_csv_records(folder / "results.csv")


def read_csv_records(path: Path) -> list[dict]:
    """The rows of a push-map sweep's ``results.csv`` at ``path`` as records (see :func:`read_records`)."""
    with open(path, newline="") as fh:
        rows = list(csv.DictReader(fh))
    out = []
    for r in rows:
        params = {
            "tracker": r["tracker"],
            "push_direction_deg": float(r["push_direction_deg"]),
            "push_phase": float(r["push_phase"]),
        }
        if "planner" in r:
            params["planner"] = r["planner"]
        out.append({"params": params, "metrics": {VALUE: float(r[VALUE]) if r[VALUE] else float("nan")}})
    return out


def with_against(records: list[dict], against: Path | None) -> list[dict]:
    """``records`` after the cells of ``against`` (a push-map ``results.csv``; ``None``: none) of their
    trackers, in the groups (tracker, planner) they lack; a row without a planner is the one-step law's."""
    if against is None:
        return records
    have = {(r["params"]["tracker"], r["params"].get("planner", "one-step")) for r in records}
    trackers = {tracker for tracker, _ in have}
    extra = []
    for r in read_csv_records(against):
        p = r["params"]
        p.setdefault("planner", "one-step")
        if p["tracker"] in trackers and (p["tracker"], p["planner"]) not in have:
            extra.append(r)
    if any("planner" not in r["params"] for r in records):  # a sweep without planners: the one-step law's
        records = [{**r, "params": {**r["params"], "planner": "one-step"}} for r in records]
    return extra + records


def check_against(path: Path) -> str | None:
    """What keeps ``path`` from being compared against (a push-map ``results.csv``), or ``None``."""
    if not path.is_file():
        return "no such file"
    with open(path, newline="") as fh:
        columns = next(csv.reader(fh), [])
    lacking = [c for c in ("tracker", "push_direction_deg", "push_phase", VALUE) if c not in columns]
    return f"has no column {', '.join(lacking)}: not a push-map results.csv" if lacking else None


def check_sweep_folder(folder: Path) -> str | None:
    """What keeps ``folder`` from being drawn as a push map, or ``None``."""
    missing = [name for name in ("results.csv", "summary.json", "spec.json") if not (folder / name).is_file()]
    if missing:
        return f"not a finished sweep folder (no {', '.join(missing)}); run the sweep first (--out)"
    with open(folder / "results.csv", newline="") as fh:
        columns = next(csv.reader(fh), [])
    needed = ["tracker", "push_direction_deg", "push_phase", VALUE]
    lacking = [c for c in needed if c not in columns]
    if lacking:
        return f"results.csv has no column {', '.join(lacking)}: not a push-map sweep (see {SPEC.name})"
    return None


def finished(folder: Path) -> bool:
    """Whether ``folder`` holds a push-map sweep with every cell measured and none failed."""
    if check_sweep_folder(folder) is not None:
        return False
    summary = json.loads((folder / "summary.json").read_text())
    return summary.get("failed") == 0 and all(r["metrics"][VALUE] == r["metrics"][VALUE] for r in read_records(folder))


def grouping(records: list[dict]) -> tuple[str, list[str]]:
    """What the map compares: ``planner`` when its cells vary the planner, else ``tracker``; and the values."""
    for key in ("planner", "tracker"):
        values = list(dict.fromkeys(r["params"].get(key) for r in records))
        if key == "tracker" or (len(values) > 1 and None not in values):
            return key, values
    raise AssertionError("unreachable")


def _ns(value: float, high: float) -> str:
    return f"≥ {high:g}" if value >= high else f"{value:.1f}"


def cell_time_s(folder: Path, summary: dict) -> float:
    """Every cell's own wall time, s, also of the cells an earlier run of the sweep measured."""
    cells_s = [json.loads(f.read_text()).get("wall_s", 0.0) for f in sorted((folder / "cells").glob("*.json"))]
    return sum(cells_s) or summary["cell_wall_s_total"]


def summary_table(folder: Path, against: Path | None = None) -> str:
    """The map's summary: a Markdown table per tracker (or planner), then the per-cell ratio and the sweep's cost
    (with ``against``: its cells too, :func:`with_against`; the cost is the sweep's own)."""
    records = with_against(read_records(folder), against)
    summary = json.loads((folder / "summary.json").read_text())
    high = json.loads((folder / "spec.json").read_text())["bisect"]["high"]
    key, trackers = grouping(records)
    cells: dict[str, dict[tuple[float, float], float]] = {t: {} for t in trackers}
    for r in records:
        p = r["params"]
        cells[p[key]][(p["push_direction_deg"], p["push_phase"])] = r["metrics"][VALUE]
    got = {t: np.array([v for v in cells[t].values() if v == v]) for t in trackers}  # NaN: a failed cell
    rows = {
        "largest impulse survived, median over the cells, N s": [_ns(float(np.median(got[t])), high) for t in trackers],
        "mean (least – largest), N s": [
            f"{np.mean(got[t]):.1f} ({_ns(got[t].min(), high)} – {_ns(got[t].max(), high)})" for t in trackers
        ],
        f"cells at the top of the range (≥ {high:g} N s)": [str(int(np.sum(got[t] >= high))) for t in trackers],
        "cells measured (failed)": [f"{got[t].size} ({len(cells[t]) - got[t].size})" for t in trackers],
    }
    ratio = ""
    if len(trackers) == 2:
        first, second = trackers
        a, b = LABELS.get(first, first), LABELS.get(second, second)
        pairs = [(cells[second][k], cells[first][k]) for k in cells[second] if k in cells[first]]
        pairs = [(q, p) for q, p in pairs if q == q and p == p]
        more = [sum(p > q for q, p in pairs), sum(q > p for q, p in pairs)]
        rows[f"cells where it survives more than the other {key}"] = [str(n) for n in more]
        r = np.array([q / p for q, p in pairs if p > 0])
        same = len(pairs) - sum(more)
        ratio = (
            f"Per cell {b} / {a}: median {np.median(r):.2f} ({r.min():.2f} – {r.max():.2f}); {same} cells the same. "
        )
        if key == "planner":
            ratio += (
                f"{b} / {a}: the medians {np.median(got[second]) / np.median(got[first]):.2f}, "
                f"the weakest cells {got[second].min() / got[first].min():.2f}. "
            )
    labels = [LABELS.get(t, t) for t in trackers]
    lines = ["| | " + " | ".join(labels) + " |", "|---|" + "---|" * len(trackers)]
    lines += [f"| {name} | " + " | ".join(values) + " |" for name, values in rows.items()]
    cell_s = cell_time_s(folder, summary)
    with open(folder / "results.csv", newline="") as fh:
        walks = sum(int(r["bisect_walks"]) for r in csv.DictReader(fh) if r.get("bisect_walks"))
    reused = f"the {len(records) - summary['cells']} other cells from {against.name}; " if against else ""
    cost = f"{summary['cells']} cells, {walks} walks, {cell_s:.0f} s of cell time; {reused}" + (
        f"the sweep: {summary['wall_time_s'] / 60:.0f} min wall on {summary['workers']} worker(s)."
        if not summary.get("resumed")
        else f"its last run: {summary['ran']} cells in {summary['wall_time_s'] / 60:.0f} min wall on "
        f"{summary['workers']} worker(s), {summary['resumed']} cells run before."
    )
    return "\n".join(lines) + "\n\n" + ratio + cost


def refuse(message: str) -> int:
    """Bad input: one line on stderr, exit status 2 (as ``amlip-qp``), before any work."""
    sys.stderr.write(f"push_map.py: error: {message}\n")
    return 2


def draw(folder: Path, figure: Path, against: Path | None = None) -> None:
    """One polar map per tracker (or planner) in the sweep (and ``against``'s, :func:`with_against`), and the
    ratio of the two when there are two."""
    records = with_against(read_records(folder), against)
    key, trackers = grouping(records)
    summary = json.loads((folder / "summary.json").read_text())
    spec = json.loads((folder / "spec.json").read_text())
    high = spec["bisect"]["high"]
    maps = {t: grid_values(records, "push_direction_deg", "push_phase", VALUE, {key: t}) for t in trackers}
    panels = len(trackers) + (1 if len(trackers) == 2 else 0)
    fig = plt.figure(figsize=(4.4 * panels, 4.6))
    for i, t in enumerate(trackers):
        ds, ps, z = maps[t]
        ax = fig.add_subplot(1, panels, i + 1, projection="polar")
        mesh = polar_map(ax, ds, ps, z, cmap="viridis", vmin=0.0, vmax=high)
        capped = int(np.sum(z >= high))
        ax.set_title(
            f"{LABELS.get(t, t)}: largest impulse survived\n({capped} of {z.size} cells >= {high:g} N s)", fontsize=9
        )
        fig.colorbar(mesh, ax=ax, shrink=0.7, pad=0.1, label="N s")
    if panels > len(trackers):
        ds, ps, zq = maps[trackers[1]]
        _, _, zp = maps[trackers[0]]
        with np.errstate(divide="ignore", invalid="ignore"):
            ratio = np.where(zp > 0, zq / zp, np.nan)
        ax = fig.add_subplot(1, panels, panels, projection="polar")
        finite = ratio[np.isfinite(ratio)]
        top = max(2.0, float(np.max(finite))) if finite.size else 2.0
        mesh = polar_map(ax, ds, ps, ratio, cmap="RdBu", norm=TwoSlopeNorm(vmin=0.0, vcenter=1.0, vmax=top))
        a, b = (LABELS.get(t, t) for t in trackers)
        ax.set_title(f"{b} / {a} (blue: {b} survives more)", fontsize=9)
        fig.colorbar(mesh, ax=ax, shrink=0.7, pad=0.1, label="ratio")
    tracker = f", {LABELS.get(records[0]['params']['tracker'])} tracker" if key == "planner" else ""
    fig.suptitle(
        f"Cassie at 1 m/s{tracker}, 0.2 s pushes (direction: 0° forward, 90° left; radius: step phase); "
        f"{summary['cells']} cells, {cell_time_s(folder, summary) / 60:.0f} min of cell time",
        fontsize=9,
    )
    fig.tight_layout()
    figure.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(figure, dpi=130)
    print(f"wrote {figure}", file=sys.stderr)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    where = parser.add_mutually_exclusive_group(required=True)
    where.add_argument("--out", type=Path, help="run the shipped spec into this folder (a finished sweep resumes)")
    where.add_argument("--from", dest="source", type=Path, help="draw from this finished sweep folder")
    parser.add_argument("--spec", type=Path, default=SPEC, help=f"the sweep spec (default {SPEC.name})")
    parser.add_argument("--workers", type=int, default=None, help="worker processes (default: one per core)")
    parser.add_argument("--figure", type=Path, default=None, help="figure path (default: FOLDER/push_map.png)")
    parser.add_argument("--csv", type=Path, default=None, help="also copy the sweep's results.csv to this path")
    parser.add_argument(
        "--against", type=Path, default=None, help="compare with the cells of this push-map results.csv too"
    )
    args = parser.parse_args(argv)
    if args.workers is not None and not 1 <= args.workers <= 64:
        return refuse(f"--workers must be 1 to 64, got {args.workers}")
    if args.against is not None and (problem := check_against(args.against)):
        return refuse(f"--against {args.against}: {problem}")
    folder = args.source
    problem = check_sweep_folder(folder) if folder is not None else None
    if problem:
        return refuse(f"--from {folder}: {problem}")
    try:  # the default figure of --out goes into the sweep's folder, which the sweep makes
        figure = args.figure or (folder / "push_map.png" if folder else None)
        check_output_path("--figure", None if figure is None else str(figure), create_folder=True)
        check_output_path("--csv", None if args.csv is None else str(args.csv), create_folder=True)
    except InputError as exc:
        return refuse(str(exc))
    code = 0
    if args.out is not None:
        folder = args.out
        if finished(folder):
            print(
                f"{folder} holds the sweep finished: drawing it (delete the folder to measure again)", file=sys.stderr
            )
        else:
            extra = ["--workers", str(args.workers)] if args.workers else []
            with contextlib.redirect_stdout(sys.stderr):  # standard output is the summary table
                code = amlip_qp_main(["sweep", str(args.spec), "--out", str(folder), "--no-progress", *extra])
            if code not in (0, 1):  # 1: some cell failed; the map shows it as missing
                return code
    draw(folder, args.figure or folder / "push_map.png", args.against)
    if args.csv is not None:
        shutil.copyfile(folder / "results.csv", args.csv)
    print(summary_table(folder, args.against))
    return code


if __name__ == "__main__":
    sys.exit(main())
