"""Handlers of ``amlip-qp codegen`` and ``amlip-qp bench codegen`` (wired in :mod:`amlip_qp.cli`)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import amlip_qp.paths as paths
from amlip_qp.exceptions import InputError
from amlip_qp.output_paths import check_output_folder, writing


def _display(folder: Path, checkout: Path | None) -> str:
    """A folder of the checkout relative to its root (``amlip_qp/codegen/generated/``), else as given."""
    try:
        if checkout is not None:
            return str(folder.resolve().relative_to(checkout.resolve())) + "/"
    except (OSError, ValueError):
        pass
    return str(folder).rstrip("/") + "/"


def run_codegen(args: argparse.Namespace) -> int:
    """Regenerate the C kernels (``--out DIR`` elsewhere) or, with ``--check``, compare.

    Without ``--out`` the folder is the package's ``codegen/generated/``: it
    is rewritten only in a source checkout (:func:`amlip_qp.paths.checkout_root`);
    an installed package's data is left alone (exit 2, one line). ``--check``
    compares the folder's files with a fresh generation in memory and exits
    1 naming the stale or missing files in one line, 0 when they match; for
    an installed package it says that it checked the installed files.

    The output folder is checked (created if missing) before anything is
    generated, and a write that fails later names ``--out``: both exit 2 in
    one line (:mod:`amlip_qp.output_paths`).
    """
    from amlip_qp.codegen import generate

    checkout = paths.checkout_root()
    packaged = args.out is None
    if packaged and checkout is None and not args.check:
        raise InputError(
            f"amlip_qp is an installed package ({paths.PACKAGE_DIR}), not a source checkout: its generated C "
            "is package data and is not rewritten; pass --out DIR to write the sources elsewhere"
        )
    folder = paths.CODEGEN_DIR if packaged else Path(args.out)
    option = "the generated folder" if packaged else "--out"
    if not args.check:
        check_output_folder(option, str(folder))
    shown = _display(folder, checkout)
    files = generate.generate_files()
    if args.check:
        fresh = f"a fresh generation (CasADi {generate.CASADI_VERSION})"
        stale = generate.stale_files(folder, files)
        if stale:
            names = ", ".join(f"{shown}{name} {state}" for name, state in stale)
            if packaged and checkout is None:
                fix = (
                    "an installed package, not a source checkout: the kernels compile from the fresh "
                    "generation; reinstall amlip_qp with the CasADi version it pins to match"
                )
            else:
                fix = "run 'amlip-qp codegen' to regenerate"
            sys.stderr.write(f"amlip-qp codegen --check: stale: {names} against {fresh} ({fix})\n")
            return 1
        kind = " (an installed package, not a source checkout)" if packaged and checkout is None else ""
        print(f"{shown}{kind} is up to date: {', '.join(files)} equal {fresh}")
        return 0
    with writing(option, str(folder)):
        generate.write_files(folder, files)
    print(f"wrote {', '.join(shown + name for name in files)}")
    return 0


def run_bench(args: argparse.Namespace) -> int:
    """Time c-fast / casadi-function / numpy; print a table and optionally JSON (``--json PATH|-``)."""
    from amlip_qp.codegen.bench import format_table, run_benchmark
    from amlip_qp.output_paths import check_output_path, emit_report

    check_output_path("--json", args.json)
    result = run_benchmark(calls=args.calls)
    emit_report(format_table(result), result, args.json)
    return 0
