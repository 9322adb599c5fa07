"""Handler of ``amlip-qp sweep`` (its parser is in :mod:`amlip_qp.cli`).

Order of work: read the spec and the command-line grid, expand the cells,
check every cell's walk options (and each plant once), check the output
folder and the Ray cluster; only then is anything written or simulated. Bad
input exits 2 with one line and leaves the folder as it was.
"""

from __future__ import annotations

import argparse
import sys
import time
import warnings
from typing import Any

from amlip_qp.exceptions import InputError, UnverifiedCommandWarning
from amlip_qp.sim.scenarios.scenarios import held_warnings, release_warnings
from amlip_qp.sweep import backends
from amlip_qp.sweep import spec as spec_mod
from amlip_qp.sweep.cells import Cell
from amlip_qp.sweep.results import SweepFolder, metric_ranges
from amlip_qp.sweep.run_cell import DEFAULT_METRICS, METRICS, check_plants, parameter_names, walk_run


def build_spec(args: argparse.Namespace) -> spec_mod.SweepSpec:
    """The spec file (if any) with ``--grid``, ``--set``, ``--duration``, ``--metrics`` and ``--bisect`` applied."""
    doc: dict[str, Any] = spec_mod.load_spec_file(args.spec) if args.spec else {}
    doc = {k: (dict(v) if isinstance(v, dict) else v) for k, v in doc.items()}
    params = doc.setdefault("parameters", {})
    fixed = doc.setdefault("fixed", {})
    if not isinstance(params, dict) or not isinstance(fixed, dict):
        raise InputError("[parameters] and [fixed] must be tables")
    for text in args.grid:
        name, values = spec_mod.parse_assignment(text, "--grid")
        items = [v for v in values.split(",") if v.strip()]
        if not items:
            raise InputError(f"--grid {text!r}: no values: the grid would be empty")
        params[name] = [spec_mod.parse_cli_value(v) for v in items]
    for text in args.set:
        name, value = spec_mod.parse_assignment(text, "--set")
        fixed[name] = spec_mod.parse_cli_value(value)
    if args.duration is not None:
        fixed["duration"] = args.duration
    if args.metrics is not None:
        doc.setdefault("sweep", {})["metrics"] = [m.strip() for m in args.metrics.split(",") if m.strip()]
    if args.bisect is not None:
        name, rest = spec_mod.parse_assignment(args.bisect, "--bisect")
        parts = rest.split(":")
        try:
            low, high, iterations = float(parts[0]), float(parts[1]), int(parts[2])
        except (ValueError, IndexError):
            raise InputError(f"--bisect expects NAME=LOW:HIGH:ITERATIONS, got {args.bisect!r}") from None
        doc["bisect"] = {"parameter": name, "low": low, "high": high, "iterations": iterations}
    return spec_mod.parse_spec(doc)


def metric_columns(spec: spec_mod.SweepSpec) -> tuple[str, ...]:
    """The table's metric columns; :class:`InputError` for an unknown metric."""
    if spec.bisect is not None:
        name = spec.bisect.parameter
        return (f"max_{name}", f"max_{name}_capped", "bisect_walks")
    metrics = spec.metrics if spec.metrics is not None else DEFAULT_METRICS
    unknown = [m for m in metrics if m not in METRICS]
    if unknown:
        raise InputError(f"unknown metric {unknown[0]!r}; known: {', '.join(METRICS)}")
    if not metrics:
        raise InputError("[sweep] metrics is empty: name at least one")
    return tuple(metrics)


def check_cells(spec: spec_mod.SweepSpec, cells: list[Cell]) -> None:
    """Parse every cell's walk (at both ends of a bisection) and load each plant once: bad input fails here.

    Walks outside the robots' verified envelopes (``[verified]``) give one
    :class:`~amlip_qp.exceptions.UnverifiedCommandWarning` for the whole sweep,
    naming the first and counting the others.
    """
    known = parameter_names()
    names = [*spec.parameters, *spec.fixed, *([spec.bisect.parameter] if spec.bisect else [])]
    unknown = [n for n in names if n not in known]
    if unknown:
        raise InputError(f"unknown parameter {unknown[0]!r}; known: {', '.join(known)}")
    runs = []
    unverified: list[str] = []
    for cell in cells:
        ends = (
            [{}] if spec.bisect is None else [{spec.bisect.parameter: v} for v in (spec.bisect.low, spec.bisect.high)]
        )
        for extra in ends:
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always", UnverifiedCommandWarning)
                try:
                    runs.append(walk_run({**cell.params, **extra}, cell.seed))
                except InputError as exc:
                    raise InputError(f"cell {cell.index} ({_describe(cell)}): {exc}") from None
            for w in caught:
                if issubclass(w.category, UnverifiedCommandWarning):
                    unverified.append(f"cell {cell.index} ({_describe(cell)}): {w.message}")
                else:
                    warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    if unverified:
        more = f" (and {len(unverified) - 1} more walks outside the verified envelope)" if len(unverified) > 1 else ""
        warnings.warn(unverified[0] + more, UnverifiedCommandWarning, stacklevel=2)
    check_plants(runs)


def _describe(cell: Cell) -> str:
    return ", ".join(f"{k}={v}" for k, v in cell.swept)


def run_sweep(args: argparse.Namespace) -> int:
    """``amlip-qp sweep``: run the cells not yet in ``--out``; write the table, summary and figures.

    Returns 0, or 1 when a cell failed (its walk raised; recorded in the table's ``error``
    column and retried by the next run).
    """
    spec = build_spec(args)
    metrics = metric_columns(spec)
    cells = spec_mod.cells_of(spec)
    with held_warnings() as unverified:  # said once the input is known good
        check_cells(spec, cells)
        folder = SweepFolder(args.out, spec.plain())
        folder.check()
    release_warnings(unverified)
    ray, started = (None, False) if args.ray is None else backends.connect_ray(args.ray or None)
    try:
        folder.prepare()
        records: dict[str, dict[str, Any]] = {}
        for cell in cells:
            rec = folder.finished(cell.id)
            if rec is not None:
                records[cell.id] = {**rec, "index": cell.index}
        todo = [c.task() for c in cells if c.id not in records]
        workers = backends.ray_cpus(ray) if ray is not None else (args.workers or backends.default_workers())
        backend = f"ray ({args.ray or 'local'})" if ray is not None else "process pool"
        t0 = time.perf_counter()
        _run(todo, records, folder, ray, workers, args.no_progress)
        wall = time.perf_counter() - t0
    finally:
        if started and ray is not None:
            ray.shutdown()
    done = [records[c.id] for c in cells]
    failed = [r for r in done if r.get("error")]
    table = folder.write_table(done, list(spec.parameters), metrics)
    summary = {
        "cells": len(cells),
        "ran": len(todo),
        "resumed": len(cells) - len(todo),
        "failed": len(failed),
        "failed_cells": [{"cell": r["index"], "id": r["id"], "error": r["error"]} for r in failed],
        "backend": backend,
        "workers": workers,
        "wall_time_s": wall,
        "cells_per_s": len(todo) / wall if todo and wall > 0 else None,
        "cell_wall_s_total": sum(records[t["id"]].get("wall_s", 0.0) for t in todo),
        "parameters": list(spec.parameters),
        "metrics": list(metrics),
        "metric_ranges": metric_ranges(done, metrics),
        "figures": [],
    }
    if not args.no_figures:
        from amlip_qp.sweep.figures import sweep_figures

        summary["figures"] = sweep_figures(folder.path, spec, done, metrics)
    folder.write_summary(summary)
    sys.stdout.write(
        f"{len(cells)} cells ({len(todo)} run, {len(cells) - len(todo)} already done) in {wall:.1f} s "
        f"on {backend} with {workers} worker(s): {table}\n"
    )
    if failed:
        first = failed[0]
        sys.stderr.write(
            f"amlip-qp sweep: {len(failed)} of {len(cells)} cells failed (first: cell {first['index']}: "
            f"{first['error']}); see the error column of {table}; run the same command again to retry them\n"
        )
        return 1
    return 0


def _run(todo, records, folder, ray, workers, no_progress) -> None:
    from tqdm import tqdm

    bar = tqdm(total=len(todo), unit="cell", desc="sweep", disable=no_progress or not todo, file=sys.stderr)

    def on_record(record: dict[str, Any]) -> None:
        records[record["id"]] = folder.save(record)
        bar.update(1)

    try:
        if ray is not None:
            backends.run_ray(ray, todo, on_record)
        else:
            backends.run_local(todo, workers, on_record)
    finally:
        bar.close()
