"""The output folder of a sweep: per-cell records, the tidy table, the summary.

Layout of ``DIR``:

- ``spec.json``: the spec the folder belongs to (a different spec is refused);
- ``cells/<id>.json``: one record per finished cell, written atomically (a
  temporary file renamed into place), so an interrupted sweep resumes by
  skipping the cells already there;
- ``results.csv`` (and ``results.parquet`` when pyarrow imports): one row per
  cell in cell order, the columns ``cell``, ``id``, one per swept parameter,
  ``seed``, one per metric, then ``error`` (empty, or what a failed cell's walk
  raised: its metrics are then empty); floats as their shortest round-trip
  text, so the same cells give the same bytes;
- ``summary.json``: counts (``failed`` and ``failed_cells`` among them), wall
  time, the backend, per-metric ranges.
"""

from __future__ import annotations

import csv
import io
import json
import math
import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from amlip_qp.exceptions import InputError

SPEC_FILE = "spec.json"
CELLS_DIR = "cells"
TABLE_FILE = "results.csv"
PARQUET_FILE = "results.parquet"
SUMMARY_FILE = "summary.json"


def write_atomic(path: Path, data: bytes) -> None:
    """Write ``data`` to ``path`` through a temporary file in the same folder and a rename."""
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    try:
        with open(tmp, "wb") as fh:
            fh.write(data)
        os.replace(tmp, path)
    finally:
        if tmp.exists():
            tmp.unlink()


def cell_text(value: Any) -> str:
    """A table cell: floats as ``repr`` (shortest round trip), ``true``/``false``, empty for missing or NaN."""
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return ""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return repr(value)
    return str(value)


class SweepFolder:
    """The output folder ``path`` of the sweep whose plain spec is ``spec``."""

    def __init__(self, path: str | Path, spec: dict[str, Any]):
        self.path = Path(path)
        self.spec = spec
        self.cells = self.path / CELLS_DIR

    def check(self) -> None:
        """Refuse (before anything is written) a folder that holds something else or another spec's sweep.

        Raises:
            InputError: ``DIR`` is a file, is not empty and not a sweep folder,
                belongs to a different spec, or cannot be created.
        """
        p = self.path
        if p.exists() and not p.is_dir():
            raise InputError(f"--out {p}: is a file; give a folder")
        if p.is_dir() and any(p.iterdir()):
            spec_path = p / SPEC_FILE
            if not spec_path.is_file():
                raise InputError(f"--out {p}: the folder is not empty and holds no sweep ({SPEC_FILE}); give another")
            try:
                theirs = json.loads(spec_path.read_text())
            except (OSError, ValueError):
                raise InputError(f"--out {p}: unreadable {SPEC_FILE}; give another folder") from None
            if theirs != json.loads(json.dumps(self.spec)):
                raise InputError(
                    f"--out {p}: holds the sweep of another spec ({spec_path}); give another folder to keep both"
                )
        parent = p.parent if not p.exists() else p
        while not parent.exists():
            parent = parent.parent
        if not os.access(parent, os.W_OK):
            raise InputError(f"--out {p}: {parent} is not writable")

    def prepare(self) -> None:
        """Create the folder and ``cells/``, and write ``spec.json`` the first time."""
        self.cells.mkdir(parents=True, exist_ok=True)
        spec_path = self.path / SPEC_FILE
        if not spec_path.exists():
            write_atomic(spec_path, (json.dumps(self.spec, indent=2, sort_keys=True) + "\n").encode())

    def finished(self, cell_id: str) -> dict[str, Any] | None:
        """The record of a finished cell, or ``None`` (missing, unreadable or failed: it runs again)."""
        try:
            record = json.loads((self.cells / f"{cell_id}.json").read_text())
        except (OSError, ValueError):
            return None
        if not isinstance(record, dict) or record.get("id") != cell_id or record.get("error"):
            return None
        return record

    def save(self, record: dict[str, Any]) -> dict[str, Any]:
        """Write a cell's record atomically; return it as read back (JSON values, NaN as ``None``)."""
        text = json.dumps(_jsonable(record), indent=1, sort_keys=True, allow_nan=False) + "\n"
        write_atomic(self.cells / f"{record['id']}.json", text.encode())
        return json.loads(text)

    def write_table(self, records: Sequence[dict[str, Any]], parameters: Sequence[str], metrics: Sequence[str]) -> str:
        """``results.csv`` (and ``results.parquet`` with pyarrow) of ``records`` in cell order; the CSV path."""
        columns = ["cell", "id", *parameters, "seed", *metrics, "error"]
        rows = [
            [
                r["index"],
                r["id"],
                *(r["params"].get(p) for p in parameters),
                r["seed"],
                *(r["metrics"].get(m) for m in metrics),
                r.get("error"),
            ]
            for r in sorted(records, key=lambda r: r["index"])
        ]
        buf = io.StringIO()
        writer = csv.writer(buf, lineterminator="\n")
        writer.writerow(columns)
        writer.writerows([[cell_text(v) for v in row] for row in rows])
        path = self.path / TABLE_FILE
        write_atomic(path, buf.getvalue().encode())
        try:
            import pyarrow as pa
            import pyarrow.parquet as pq
        except ImportError:
            return str(path)
        table = pa.Table.from_pylist([dict(zip(columns, row)) for row in rows])
        sink = pa.BufferOutputStream()
        pq.write_table(table, sink)
        write_atomic(self.path / PARQUET_FILE, sink.getvalue().to_pybytes())
        return str(path)

    def write_summary(self, summary: dict[str, Any]) -> None:
        """``summary.json``."""
        text = json.dumps(_jsonable(summary), indent=2, allow_nan=False) + "\n"
        write_atomic(self.path / SUMMARY_FILE, text.encode())


def metric_ranges(records: Sequence[dict[str, Any]], metrics: Sequence[str]) -> dict[str, dict[str, float]]:
    """Per numeric metric: ``min``, ``max`` and ``mean`` over the cells where it is defined (booleans as 0/1)."""
    out = {}
    for m in metrics:
        vals = [float(r["metrics"].get(m)) for r in records if isinstance(r["metrics"].get(m), (int, float))]
        if vals:
            out[m] = {"min": min(vals), "max": max(vals), "mean": sum(vals) / len(vals)}
    return out


def _jsonable(value: Any) -> Any:
    if isinstance(value, dict):
        return {str(k): _jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_jsonable(v) for v in value]
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value
