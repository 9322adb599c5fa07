"""Regenerate the measured blocks of docs/RESULTS.md from the commands that produce them.

Usage: ``python examples/results_page.py --list | --check | --all | --only ID[,ID] [--page PATH]``.
Each generated block of the page sits between two markers::

    <!-- results: ID -->
    Command: `amlip-qp bench codegen`
    Measured 2026-12-06 (11 s wall) with Python 3.11.7, MuJoCo 4.0.1, Pinocchio 4.1.0, ...

    (the command's output: a Markdown table, or its text in a code block)
    <!-- /results: ID -->

:data:`MANIFEST` lists the blocks: an id, the command (an argv list; ``amlip-qp`` and ``python``
run with this interpreter, from the repository's top folder), how its output becomes the block
(``markdown``: its standard output is a Markdown table; ``text``: its standard output, shown as
a code block; ``compare-json``: the JSON file ``amlip-qp compare --json`` writes, as a Markdown
table of the library's comparison columns) and about how long it takes on 2 cores.

- ``--list``: the ids, commands and rough costs.
- ``--only ID[,ID]``: run those commands and rewrite their blocks in place (the command line,
  the date and versions line and the output); everything outside the markers is left as it is.
- ``--all``: every block, one after the other (each block is written as soon as it is measured).
- ``--check``: no simulation: every marker of the page has a manifest entry and every entry a
  block, each block is well formed and starts with the command line its entry gives, and no
  Markdown table lies outside the blocks (the page's measurements are all generated).

Bad input (an unknown id, a missing page, markers that do not pair) exits 2 with one line; a
failing ``--check`` prints one line per problem and exits 1; a command that fails leaves its
block untouched and exits 1.
"""

from __future__ import annotations

import argparse
import importlib.metadata
import json
import platform
import re
import shlex
import subprocess
import sys
import time
from dataclasses import dataclass
from datetime import datetime, timezone
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
PAGE = ROOT / "docs" / "RESULTS.md"
#: Where the commands that write JSON write it (the repository's ``out/`` folder is not tracked).
JSON_DIR = "out/results"

KINDS = ("markdown", "text", "compare-json")


@dataclass(frozen=True)
class Entry:
    """One generated block of the page.

    Attributes:
        id: The block's id in its markers (lower case, digits and ``-``).
        argv: The command; ``argv[0]`` is ``amlip-qp``, ``python`` or a program on the PATH.
        kind: How the command's output becomes the block (one of :data:`KINDS`).
        cost_s: Roughly how long the command takes on 2 cores, wall time in seconds.
    """

    id: str
    argv: tuple[str, ...]
    kind: str
    cost_s: float

    def json_path(self) -> Path:
        """For ``compare-json``: the file the command writes, its ``--json`` argument."""
        return ROOT / self.argv[self.argv.index("--json") + 1]


def argv(command: str) -> tuple[str, ...]:
    """A manifest command written as one line, split as a shell splits it."""
    return tuple(shlex.split(command))


def entry(entry_id: str, command: str, cost_s: float, kind: str = "markdown") -> Entry:
    """A manifest entry from its command written as one line."""
    return Entry(entry_id, argv(command), kind, cost_s)


#: ``amlip-qp compare``'s options in the blocks but the JSON file's name and ending.
COMPARE = f"--jobs 1 --no-plot --json {JSON_DIR}/compare"
ACCEPTANCE = "python examples/acceptance_table.py"
PUSH_MAP, MEDIA = "python examples/push_map.py --workers 2", "docs/media"

MANIFEST: tuple[Entry, ...] = (
    # one worker, the 2 cores shared with other jobs: Rabbit 95 s, Cassie 290 s, H1 789 s, G1 548 s measured
    *(
        entry(f"compare-{robot}", f"amlip-qp compare --robots {robot} {COMPARE}-{robot}.json", cost_s, "compare-json")
        for robot, cost_s in (("rabbit", 95), ("cassie", 290), ("h1", 790), ("g1", 550))
    ),
    # the closed-chain plant with the robot's sensors and the EKF, one process: 1049 s measured at load 5-8
    entry(
        "compare-cassie-cc-ekf",
        "amlip-qp compare --robots cassie --plant cassie-closed-chain --sensors robot --estimator ekf "
        f"{COMPARE}-cassie-cc-ekf.json",
        1050,
        "compare-json",
    ),
    # both trackers with both planners on Cassie, 16 experiments, one process: 1123-1795 s measured at load 6-12
    entry(
        "compare-planners-cassie",
        f"amlip-qp compare --robots cassie --planners one-step,mpc {COMPARE}-planners-cassie.json",
        1120,
        "compare-json",
    ),
    # 20 walks of 4-20 s on 2 worker processes: 166 s measured
    entry("acceptance-ideal-cassie", f"{ACCEPTANCE} --set ideal --robots cassie", 170),
    # 30 walks of 9-20 s on the closed-chain plant with the EKF, one process: 1405 s measured on the shared
    # machine (load average about 5 on its 2 cores; 531 s with 2 processes before)
    entry("acceptance-cc-ekf-cassie", f"{ACCEPTANCE} --set cc-ekf --robots cassie --estimator-columns --jobs 1", 1400),
    # 6 walks of 10-20 s on 2 worker processes: 151 s measured with other work on the machine
    entry("acceptance-ideal-rabbit", f"{ACCEPTANCE} --set ideal --robots rabbit", 150),
    # 12 walks of 10-20 s on 2 worker processes: 188 s measured
    entry("acceptance-ideal-h1", f"{ACCEPTANCE} --set ideal --robots h1", 190),
    # 16 walks of 10-20 s, both trackers, one process (the QP's 8 alone: 337 s measured)
    entry("acceptance-g1", f"{ACCEPTANCE} --set all --robots g1 --jobs 1", 800),
    # 15 QP walks of 10-20 s on the humanoids' two- and four-point soles, one process
    entry("four-point-feet", "python examples/four_point_feet.py --jobs 1", 700),
    # 18 walks of 4-14 s (QP tracker, both planners), one process: 224 s measured on the shared machine
    entry("planner-table", "python examples/planner_table.py --jobs 1", 230),
    # 29 walks on the closed-chain plant with the EKF, 4-20 s, one process: 810 s measured on the shared machine
    entry("paper-claims", "python examples/paper_claims.py --jobs 1", 810),
    # two 8-s walks across the Wave Field (floor friction 1 and 3), MuJoCo contact forces per tick: 14-49 s measured
    entry("friction-demand", "python examples/friction_demand.py --friction 1,3", 50),
    # the terrain-map sweep (56 walks of at most 10 s), one worker, and its figure: 1131 s measured at load 5-7
    entry("terrain-map", "python examples/terrain_map.py --workers 1 --figure docs/media/terrain_map.png", 1130),
    # the push maps (80 cells, 410-560 walks of at most 5.5 s, 2 workers; 31, 9 and 20 min measured), then the
    # figure, cells' table and summary; only the drawing when out/FOLDER holds the sweep finished
    *(
        entry(
            f"push-map{tag}",
            f"{PUSH_MAP} {spec}--out out/{name} --figure {MEDIA}/{name}.png --csv {MEDIA}/{name}_results.csv",
            cost_s,
        )
        for tag, spec, name, cost_s in (
            ("", "", "push_map", 3300),
            ("-planners", "--spec examples/sweeps/push_map_planners.toml ", "push_map_planners", 3600),
            ("-planners-pbc", "--spec examples/sweeps/push_map_planners_pbc.toml ", "push_map_planners_pbc", 4800),
        )
    ),
    # 14 terrain scenarios x both trackers, 28 walks of 14-20 s, one worker process: 1249 s measured on
    # the 2 cores shared with other jobs (load average 5-8)
    entry("terrain", "python examples/terrain_table.py --jobs 1", 1250),
    # 32 walks of 14 s on the stairs (16 starts x both planners), QP, one process: 1059 s measured at load 4.5-6
    entry(
        "raised-starts-stairs",
        "python examples/raised_starts.py --scenario cassie-stairs-10cm --tracker qp --planner one-step,mpc --jobs 1",
        1060,
    ),
    # 14 walks of 10 s from rest, one process: 379 s measured on the 2 cores shared with other jobs
    entry("step-commands", "python examples/step_commands.py --jobs 1", 380),
    entry("bench-mpc", "amlip-qp bench mpc", 20, "text"),  # with the recorded QP walk it times in turns: 10-20 s
    entry("bench-codegen", "amlip-qp bench codegen", 10, "text"),
    # 20-26 s measured
    entry("bench-qp", "amlip-qp bench qp", 25, "text"),
    # 11 s measured on a quiet machine, 86 s on a loaded one
    entry("bench-ekf", "amlip-qp bench ekf", 30, "text"),
    # 32 walks of 4 s (4 robots x 2 trackers x 2 log modes x 2 repeats), the yardstick after each
    entry(
        "bench-harness",
        "amlip-qp bench harness --scenario robots --trackers qp,pbc --duration 4 --repeats 2",
        400,
        "text",
    ),
    # 6 cells of 2 s with 1 and with 2 workers, 3 times
    entry("bench-sweep", "amlip-qp bench sweep", 120, "text"),
    # two 7-s walks and their figures: 101 s measured with other jobs on the machine
    entry("prediction-study", "python examples/prediction_study.py", 100, "text"),
    # each 11-22 s measured (the checks and a 3-s walk in place)
    *(
        entry(f"check-robot-{robot}", f"amlip-qp check-robot {robot}", 20, "text")
        for robot in ("cassie", "rabbit", "h1", "g1")
    ),
)

OPEN = re.compile(r"^<!-- results: ([a-z0-9-]+) -->$")
CLOSE = re.compile(r"^<!-- /results: ([a-z0-9-]+) -->$")
MEASURED = "Measured "


class PageError(Exception):
    """The page or the request cannot be used as it is (one line for the user)."""


def entries() -> dict[str, Entry]:
    """The manifest by id."""
    return {e.id: e for e in MANIFEST}


def command_text(entry: Entry) -> str:
    """The command as a user types it, from the repository's top folder."""
    return shlex.join(entry.argv)


def command_line(entry: Entry) -> str:
    """The block's first line: its command."""
    return f"Command: `{command_text(entry)}`"


def _resolved(argv: tuple[str, ...]) -> list[str]:
    """``amlip-qp`` and ``python`` run with this interpreter, so the environment is this one."""
    if argv[0] == "amlip-qp":
        return [sys.executable, "-m", "amlip_qp", *argv[1:]]
    if argv[0] == "python":
        return [sys.executable, *argv[1:]]
    return list(argv)


def _version(*distributions: str) -> str:
    for name in distributions:
        try:
            return importlib.metadata.version(name)
        except importlib.metadata.PackageNotFoundError:
            continue
    return "not installed"


def versions() -> str:
    """The versions the measurements depend on, read now."""
    return ", ".join(
        [
            f"Python {platform.python_version()}",
            f"MuJoCo {_version('mujoco')}",
            f"Pinocchio {_version('pin', 'pinocchio')}",
            f"ProxSuite {_version('proxsuite')}",
            f"daqp {_version('daqp')}",
            f"CasADi {_version('casadi')}",
            f"numpy {_version('numpy')}",
        ]
    )


def compare_markdown(data: dict[str, Any]) -> str:
    """``amlip-qp compare --json``'s rows as a Markdown table of the library's own columns and cells."""
    from amlip_qp.experiments.compare_table import TABLE_COLUMNS, table_cell

    lines = ["| " + " | ".join(header for _, header, _ in TABLE_COLUMNS) + " |"]
    lines.append("|" + "---|" * len(TABLE_COLUMNS))
    for row in data["rows"]:
        lines.append("| " + " | ".join(table_cell(row, key, fmt) for key, _, fmt in TABLE_COLUMNS) + " |")
    return "\n".join(lines)


def body(entry: Entry, stdout: str) -> str:
    """The block's output part from what the command printed (or wrote, for ``compare-json``)."""
    if entry.kind == "markdown":
        return stdout.strip("\n")
    if entry.kind == "text":
        return "```text\n" + stdout.strip("\n") + "\n```"
    if entry.kind == "compare-json":
        return compare_markdown(json.loads(entry.json_path().read_text()))
    raise PageError(f"{entry.id}: unknown kind {entry.kind!r}; known: {', '.join(KINDS)}")


def measure(entry: Entry) -> list[str]:
    """Run the entry's command; the block's lines between its markers."""
    if entry.kind == "compare-json":
        entry.json_path().parent.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    proc = subprocess.run(_resolved(entry.argv), cwd=ROOT, capture_output=True, text=True)
    wall_s = time.perf_counter() - t0
    if proc.returncode != 0:
        last = (proc.stderr.strip().splitlines() or ["(no message)"])[-1]
        raise RuntimeError(f"{entry.id}: `{command_text(entry)}` exited {proc.returncode}: {last}")
    date = datetime.now(timezone.utc).strftime("%Y-%m-%d")
    return [
        command_line(entry),
        f"{MEASURED}{date} ({wall_s:.0f} s wall) with {versions()}.",
        "",
        *body(entry, proc.stdout).splitlines(),
    ]


def blocks(lines: list[str]) -> dict[str, tuple[int, int]]:
    """The page's blocks: id -> (index of the opening marker, index of the closing one).

    Raises:
        PageError: A marker without its partner, a block inside another or an id used twice.
    """
    found: dict[str, tuple[int, int]] = {}
    open_id: str | None = None
    start = 0
    for i, line in enumerate(lines):
        if m := OPEN.match(line):
            if open_id is not None:
                raise PageError(f"line {i + 1}: block {m.group(1)!r} opens inside block {open_id!r}")
            if m.group(1) in found:
                raise PageError(f"line {i + 1}: block {m.group(1)!r} appears twice")
            open_id, start = m.group(1), i
        elif m := CLOSE.match(line):
            if open_id != m.group(1):
                raise PageError(f"line {i + 1}: closing marker of {m.group(1)!r} without its opening marker")
            found[open_id] = (start, i)
            open_id = None
        elif line.lstrip().startswith("<!--") and "results:" in line:
            raise PageError(f"line {i + 1}: malformed marker {line.strip()!r}")
    if open_id is not None:
        raise PageError(f"line {start + 1}: block {open_id!r} is not closed")
    return found


def read_page(page: Path) -> list[str]:
    if not page.is_file():
        raise PageError(f"no results page at {page}")
    return page.read_text().split("\n")


def check(page: Path) -> list[str]:
    """The page's problems against the manifest (empty: the page is consistent)."""
    lines = read_page(page)
    found = blocks(lines)
    manifest = entries()
    problems = [f"{i}: block in the page but not in the manifest" for i in found if i not in manifest]
    problems += [f"{i}: in the manifest but no block in the page" for i in manifest if i not in found]
    inside = {k for start, end in found.values() for k in range(start, end + 1)}
    problems += [
        f"line {k + 1}: a table outside the generated blocks (every table is a block's command's output)"
        for k, line in enumerate(lines)
        if line.lstrip().startswith("|") and k not in inside and not (k and lines[k - 1].lstrip().startswith("|"))
    ]
    for i, (start, end) in found.items():
        if i not in manifest:
            continue
        inner = lines[start + 1 : end]
        if not inner or inner[0] != command_line(manifest[i]):
            problems.append(f"{i}: the block does not start with {command_line(manifest[i])!r}")
        elif len(inner) < 4 or not inner[1].startswith(MEASURED) or inner[2] != "" or not inner[3].strip():
            problems.append(f"{i}: the block needs the command, a '{MEASURED}...' line, a blank line and the output")
        elif manifest[i].kind == "text" and (inner[3] != "```text" or inner[-1] != "```"):
            problems.append(f"{i}: a text block's output is one ```text code block")
        elif manifest[i].kind != "text" and not inner[3].startswith("|"):
            problems.append(f"{i}: the output is a Markdown table")
    return problems


def rewrite(page: Path, entry_id: str, inner: list[str]) -> None:
    """Replace the lines between ``entry_id``'s markers with ``inner``; nothing else changes."""
    lines = read_page(page)
    start, end = blocks(lines)[entry_id]
    page.write_text("\n".join(lines[: start + 1] + inner + lines[end:]))


def _cost(seconds: float) -> str:
    return f"~{seconds:.0f} s" if seconds < 90 else f"~{seconds / 60:.0f} min"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    what = ap.add_mutually_exclusive_group(required=True)
    what.add_argument("--list", action="store_true", help="the blocks: id, command, rough cost")
    what.add_argument("--check", action="store_true", help="markers, manifest and command lines agree (no simulation)")
    what.add_argument("--all", action="store_true", help="run every command and rewrite every block")
    what.add_argument("--only", metavar="ID[,ID]", help="run these blocks' commands and rewrite their blocks")
    ap.add_argument("--page", type=Path, default=PAGE, help="the page (default docs/RESULTS.md)")
    args = ap.parse_args(argv)
    manifest = entries()
    try:
        if args.list:
            for e in MANIFEST:
                print(f"{e.id:<26} {_cost(e.cost_s):>8}  {command_text(e)}")
            print(f"{'all':<26} {_cost(sum(e.cost_s for e in MANIFEST)):>8}  (one after the other, 2 cores)")
            return 0
        if args.check:
            problems = check(args.page)
            for p in problems:
                print(p)
            if not problems:
                print(f"{args.page}: {len(manifest)} blocks, every one matches the manifest")
            return 1 if problems else 0
        ids = list(manifest) if args.all else [i for i in args.only.split(",") if i]
        unknown = [i for i in ids if i not in manifest]
        if unknown or not ids:
            raise PageError(f"unknown block id {', '.join(unknown) or '(none)'}; known: {', '.join(manifest)}")
        missing = [i for i in ids if i not in blocks(read_page(args.page))]
        if missing:
            raise PageError(f"{args.page} has no markers for {', '.join(missing)}; add them where the block goes")
    except PageError as exc:
        print(f"results_page: {exc}", file=sys.stderr)
        return 2
    for i in ids:
        print(f"{i}: {command_text(manifest[i])} ...", file=sys.stderr, flush=True)
        try:
            inner = measure(manifest[i])
        except RuntimeError as exc:
            print(f"results_page: {exc}", file=sys.stderr)
            return 1
        rewrite(args.page, i, inner)
        print(f"{i}: written ({inner[1]})", file=sys.stderr, flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
