"""Walk speed of this checkout against another one, interleaved on the same machine.

The machine's speed drifts (by up to 1.6x within minutes on the 2-core
development machine), so a walk's wall time means little alone. This script
alternates walks of a reference checkout (``--reference``, e.g. a
``git worktree`` of an older commit) and of this checkout, each in its own
process (reference first in the odd pairs, this checkout first in the even
ones), and compares them within each pair. Every walk is timed the same way,
whatever the checkout's harness reports: the loop's wall time per control
tick, the controller's tick (``tick_time_us``, which every version records)
and MuJoCo's steps (``mujoco.mj_step`` wrapped with a timer in the walk's
process before the walk). The harness's own time is what is left; it holds
the wrapper's own call (well under a microsecond a tick, the same for both). Each part
is also divided by two yardsticks of the machine's speed, to compare walks run
at different machine speeds: MuJoCo's step time of the same walk (``_per_mujoco``;
stable under load, but a leaner loop leaves MuJoCo's data in the caches and its
step faster, so it understates a leaner code's gain) and MuJoCo's step time
alone, measured in the same process right after the walk (``_per_step``;
:mod:`amlip_qp.experiments.mujoco_yardstick`, this checkout's recipe in both walks:
``mj_step`` replayed on copies of the state at the end of the 0.5-s warm-up
walk; independent of the code, but it swings with the machine's load). The
real-time factors' ratio needs no yardstick; the ABBA order and the median
over the pairs average the drift out.

    git worktree add --detach /tmp/ref REVISION    # REVISION: the commit to compare with
    python examples/speed_against.py --reference /tmp/ref --pairs 5

prints one line per walk and the medians over the pairs. Exit status: 0, or 2
with one line on bad input (a reference folder without the package, a bad
number, an unknown scenario, tracker or log mode, an unwritable ``--json``),
before any walk.
"""

from __future__ import annotations

import argparse
import json
import math
import pathlib
import statistics
import subprocess
import sys

from amlip_qp.control.registry import TRACKER_MODULES
from amlip_qp.exceptions import InputError
from amlip_qp.output_paths import check_output_path
from amlip_qp.sim.loop.run_log import LOG_MODES
from amlip_qp.sim.scenarios.named import get_scenario

HERE = pathlib.Path(__file__).resolve().parents[1]
#: The yardstick's recipe (MuJoCo's step alone on a fixed state), run in the walks of both checkouts.
YARDSTICK = HERE / "amlip_qp" / "experiments" / "mujoco_yardstick.py"
#: The warm-up walk before each timed walk (imports, compiled kernels; its end state is the yardstick's), s.
WARMUP_S = 0.5

#: Runs in the walk's process, with the checkout first on sys.path.
WALK = r"""
import inspect, json, sys, time
import amlip_qp
import mujoco
import numpy as np
try:
    from amlip_qp.sim.scenarios.factory import build_simulation, load
    from amlip_qp.sim.scenarios.named import get_scenario
except ImportError:  # a checkout from before amlip_qp.sim was laid out by job
    from amlip_qp.sim.factory import build_simulation, load
    from amlip_qp.sim.scenarios import get_scenario

scenario, tracker_name, duration, log = sys.argv[1], sys.argv[2], float(sys.argv[3]), sys.argv[4]
yardstick, gathered = sys.argv[5], sys.argv[6] == "1"
sc = get_scenario(scenario).with_(duration_s=duration)

def tracker():
    if not gathered:
        return tracker_name
    from amlip_qp.control.wbc.tracker import QPTracker
    made = QPTracker(load(sc.robot), in_place_assembly=False)
    if made.build_backend != "c":
        raise SystemExit(f"no compiled build that gathers its inputs: {made.build_backend}")
    return made

ys = {}  # this checkout's amlip_qp/experiments/mujoco_yardstick.py, the same recipe in every version
exec(compile(open(yardstick).read(), yardstick, "exec"), ys)
# warm-up (imports, compiled kernels, caches), and the state the yardstick replays
model, state = ys["snapshot_walk"](lambda: build_simulation(sc, tracker()).run(WARMUP_S))
step, clock, spent = mujoco.mj_step, time.perf_counter_ns, []

def timed_step(m, d):
    t0 = clock()
    step(m, d)
    spent.append(clock() - t0)

mujoco.mj_step = timed_step
sim = build_simulation(sc, tracker())
if "log" in inspect.signature(sim.run).parameters:
    result = sim.run(duration, log=log)
else:  # a version without log modes
    result = sim.run(duration)
mujoco.mj_step = step  # unwrapped: the yardstick's steps are not the walk's
step_alone_us = ys["step_time_us"](model, state)
n = len(result.tick_time_us)
steps_per_tick = len(spent) / n
wall_us = result.wall_time_s * 1e6 / n
mujoco_us = sum(spent) * 1e-3 / n
controller_us = float(np.mean(result.tick_time_us))
print(json.dumps({
    "ticks": n, "fell": bool(result.fell), "realtime_factor": result.sim_time_s / result.wall_time_s,
    "wall_us": wall_us, "controller_us": controller_us, "mujoco_us": mujoco_us,
    "harness_us": wall_us - controller_us - mujoco_us, "step_alone_us": step_alone_us, "package": amlip_qp.__file__,
    "gathered": gathered, "steps_per_tick": steps_per_tick,
}))
"""


def walk(tree: pathlib.Path, args: argparse.Namespace, gathered: bool = False) -> dict:
    """One walk of the checkout at ``tree`` in a fresh process; its timing record
    (``gathered``: the QP tracker with ``in_place_assembly=False``, its compiled build that gathers its inputs
    in Python)."""
    env_code = f"import sys; sys.path.insert(0, {str(tree)!r})\nWARMUP_S = {WARMUP_S!r}\n" + WALK
    out = subprocess.run(
        [
            sys.executable,
            "-c",
            env_code,
            args.scenario,
            args.tracker,
            str(args.duration),
            args.log,
            str(YARDSTICK),
            "1" if gathered else "0",
        ],  # fmt: skip
        capture_output=True,
        text=True,
        cwd=tree,
        check=False,
    )
    if out.returncode != 0:
        raise RuntimeError(f"the walk of {tree} failed:\n{out.stderr.strip()[-2000:]}")
    rec = json.loads(out.stdout.strip().splitlines()[-1])
    if not pathlib.Path(rec["package"]).resolve().is_relative_to(tree):
        raise RuntimeError(f"the walk meant for {tree} imported {rec['package']}")
    for part in ("wall", "controller", "harness"):
        rec[f"{part}_per_mujoco"] = rec[f"{part}_us"] / rec["mujoco_us"]
    for part in ("wall", "controller", "harness", "mujoco"):  # per a tick's worth of MuJoCo steps alone
        rec[f"{part}_per_step"] = rec[f"{part}_us"] / (rec["step_alone_us"] * rec["steps_per_tick"])
    return rec


def line(name: str, r: dict) -> str:
    return (
        f"{name:9s} {r['realtime_factor']:5.2f}x  wall {r['wall_us']:6.1f}  controller {r['controller_us']:6.1f}  "
        f"MuJoCo {r['mujoco_us']:5.1f}  harness {r['harness_us']:6.1f} µs/tick  |  "
        f"per MuJoCo step: wall {r['wall_per_mujoco']:5.2f}  harness {r['harness_per_mujoco']:4.2f}  |  "
        f"step alone {r['step_alone_us']:5.2f} µs;"
        f" per step alone: wall {r['wall_per_step']:5.2f}  harness {r['harness_per_step']:4.2f}"
        + ("  FELL" if r["fell"] else "")
    )


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--reference", required=True, help="a checkout of the reference version (its top folder)")
    p.add_argument("--pairs", type=int, default=5, help="reference/this walk pairs, interleaved (default 5)")
    p.add_argument("--scenario", default="cassie-1mps", help="scenario (default cassie-1mps)")
    p.add_argument("--tracker", default="qp", help="tracker (default qp)")
    p.add_argument("--duration", type=float, default=10.0, help="simulated time per walk, s (default 10)")
    p.add_argument("--log", default="summary", help="this checkout's log mode (default summary)")
    p.add_argument(
        "--gathered",
        action="store_true",
        help="this checkout's QP tracker with in_place_assembly=False, the compiled build that gathers its inputs "
        "in Python (the reference's as it is)",
    )
    p.add_argument("--json", default=None, help="write every record and the medians to this JSON file ('-': stdout)")
    args = p.parse_args(argv)
    ref = pathlib.Path(args.reference).resolve()
    if not (ref / "amlip_qp" / "__init__.py").is_file():
        print(f"error: --reference {args.reference}: no amlip_qp package there (give a checkout's top folder)")
        return 2
    if args.pairs < 1 or not (args.duration > 0 and math.isfinite(args.duration)):
        print("error: --pairs must be >= 1 and --duration a finite number of seconds > 0")
        return 2
    try:  # every walk's settings, before any walk
        get_scenario(args.scenario)
        if args.tracker not in TRACKER_MODULES:
            raise InputError(f"--tracker {args.tracker}: unknown; known: {', '.join(TRACKER_MODULES)}")
        if args.log not in LOG_MODES:
            raise InputError(f"--log {args.log}: unknown; known: {', '.join(LOG_MODES)}")
        if args.gathered and args.tracker != "qp":
            raise InputError(f"--gathered is an option of the qp tracker, not of {args.tracker}")
        check_output_path("--json", args.json)
    except InputError as exc:
        print(f"error: {exc}")
        return 2
    pairs = []
    for i in range(args.pairs):
        # ABBA: the order alternates, so a steady drift of the machine's speed favours neither
        if i % 2 == 0:
            pair = {"reference": walk(ref, args), "this": walk(HERE, args, args.gathered)}
        else:
            this = walk(HERE, args, args.gathered)
            pair = {"reference": walk(ref, args), "this": this}
        pairs.append(pair)
        print(line("reference", pair["reference"]))
        print(line("this", pair["this"]), flush=True)
    keys = (
        "realtime_factor", "wall_per_mujoco", "harness_per_mujoco", "wall_per_step", "harness_per_step",
        "mujoco_per_step", "harness_us", "controller_us",
    )  # fmt: skip
    ratios = {k: statistics.median(p["this"][k] / p["reference"][k] for p in pairs) for k in keys}
    medians = {who: {k: statistics.median(p[who][k] for p in pairs) for k in keys} for who in ("reference", "this")}
    print(f"medians over {len(pairs)} pairs (this ÷ reference, per pair):")
    for k in keys:
        print(
            f"  {k:20s} reference {medians['reference'][k]:8.3f}  this {medians['this'][k]:8.3f}  ratio {ratios[k]:.3f}"
        )
    report = json.dumps({"pairs": pairs, "medians": medians, "ratios": ratios}, indent=1)
    if args.json == "-":
        print(report)
    elif args.json:
        pathlib.Path(args.json).write_text(report)
    return 0


if __name__ == "__main__":
    sys.exit(main())
