"""Handlers of ``amlip-qp codegen`` and ``amlip-qp bench codegen`` (wired in :mod:`amlip_qp.cli`)."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from amlip_qp.exceptions import CodegenError
from amlip_qp.paths import CODEGEN_DIR, REPO_ROOT


def _display(folder: Path) -> str:
    """``codegen/`` for the repository's folder, else the path as given."""
    try:
        if folder.resolve() == CODEGEN_DIR.resolve():
            return str(CODEGEN_DIR.relative_to(REPO_ROOT)) + "/"
    except OSError:
        pass
    return str(folder).rstrip("/") + "/"


def run_codegen(args: argparse.Namespace) -> int:
    """Regenerate the C kernels (``--out DIR`` elsewhere) or, with ``--check``, compare.

    ``--check`` exits 1 naming the stale or missing files in one line, 0 when
    the folder matches a fresh generation.
    """
    from amlip_qp.codegen import generate

    folder = Path(args.out) if args.out else CODEGEN_DIR
    shown = _display(folder)
    files = generate.generate_files()
    if args.check:
        stale = generate.stale_files(folder, files)
        if stale:
            names = ", ".join(f"{shown}{name} {state}" for name, state in stale)
            sys.stderr.write(f"amlip-qp codegen --check: stale: {names} (run 'amlip-qp codegen' to regenerate)\n")
            return 1
        print(f"{shown} is up to date ({', '.join(files)})")
        return 0
    if folder.exists() and not folder.is_dir():
        raise CodegenError(f"--out {folder} is not a folder; pass a folder path")
    generate.write_files(folder, files)
    print(f"wrote {', '.join(shown + name for name in files)}")
    return 0


def run_bench(args: argparse.Namespace) -> int:
    """Time c-fast / casadi-function / numpy; print a table and optionally JSON (``--json PATH|-``)."""
    from amlip_qp.cli import check_output_path, writing
    from amlip_qp.codegen.bench import format_table, run_benchmark

    check_output_path("--json", args.json)
    result = run_benchmark(calls=args.calls)
    table = format_table(result)
    if args.json == "-":
        sys.stderr.write(table + "\n")
        json.dump(result, sys.stdout, indent=2)
        sys.stdout.write("\n")
        return 0
    print(table)
    if args.json:
        with writing("--json", args.json):
            Path(args.json).write_text(json.dumps(result, indent=2) + "\n")
        print(f"wrote {args.json}")
    return 0
