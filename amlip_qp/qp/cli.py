"""Handler of ``amlip-qp bench qp`` (wired in :mod:`amlip_qp.cli`).

Arguments it reads from the namespace:

- ``json``: ``None``, ``"-"`` (JSON on stdout, table on stderr) or a file path;
- ``ticks``: number of recorded tracker QPs to replay (>= 1000 for the issue's
  acceptance; default 1200 when absent);
- ``scenario``: optional scenario name (default ``"cassie-1mps"``).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path


def run_bench(args: argparse.Namespace) -> int:
    """Record a Cassie walk, replay its QPs through every solver, print the table (and JSON)."""
    from amlip_qp.cli import check_output_path, writing
    from amlip_qp.qp.bench import format_report, run

    n_ticks = int(getattr(args, "ticks", None) or 1200)
    scenario = getattr(args, "scenario", None) or "cassie-1mps"
    target = getattr(args, "json", None)
    check_output_path("--json", target)
    report = run(n_ticks=n_ticks, scenario=scenario)
    table = format_report(report)
    if target == "-":
        sys.stderr.write(table + "\n")
        json.dump(report, sys.stdout, indent=2)
        sys.stdout.write("\n")
        return 0
    print(table)
    if target:
        with writing("--json", target):
            Path(target).write_text(json.dumps(report, indent=2) + "\n")
        print(f"wrote {target}")
    return 0 if not report["fell"] else 1
