"""PBC vs QP on Cassie and Rabbit: a thin wrapper over ``amlip-qp compare``.

Usage: ``python examples/compare_trackers.py [--out DIR] [--full]``
Runs ``amlip-qp compare --quick`` (short runs, one bisection step: under two
minutes when both robots walk on two cores) unless ``--full`` is given, prints
the table, and writes ``DIR/compare.png`` and ``DIR/compare.json`` (default
DIR: ./out).
"""

from __future__ import annotations

import argparse
from pathlib import Path

from amlip_qp import cli


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="out", help="output folder (default ./out)")
    ap.add_argument("--full", action="store_true", help="the full comparison (amlip-qp compare's defaults)")
    args = ap.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    cmd = ["compare", "--plot", str(out / "compare.png"), "--json", str(out / "compare.json")]
    if not args.full:
        cmd.append("--quick")
    return cli.main(cmd)


if __name__ == "__main__":
    raise SystemExit(main())
