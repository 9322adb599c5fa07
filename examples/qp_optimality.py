"""Is the QP tracker's solution the optimum of its QP in every tick? Walk, re-solve every tick, print a table.

The QP tracker solves one problem a tick with its profile's solver, hot- or
warm-started from the tick before (DAQP from its last working set, ProxQP from
its last iterate, at the tracker's tolerance). This script walks a named
scenario with each solver given, records every tick's problem and solution
(``QPTracker.record``), and solves each problem again from scratch with DAQP
(``DAQPSolver(warm_start=False)``: an exact active-set solve with every bound).
A tick's solution is off the optimum when its cost exceeds the fresh solve's
by more than 1e-3 of ``max(1, |cost*|)``, or when the fresh solve fails. The
ticks the tracker solved without its torque-limit rows (the problem infeasible
with them, counted in ``QPTracker.relaxed_solves``) are counted apart and not
compared.

An optional forward push on the base (``--push NS``: 0.2 s from 3 s, besides
the scenario's own pushes) shows the ticks at the edge of feasibility::

    python examples/qp_optimality.py --scenario rabbit-0.5mps --push 10 --duration 4.4
    python examples/qp_optimality.py --scenario h1-1mps --push 45 --duration 4.5 --solvers proxqp

One table row per solver: the walk's outcome, the ticks solved, the relaxed
ticks (and the first one's time), and the ticks off the optimum before 3 s
(the push's start) and from it, with the largest excess cost and the largest ``|x - x*|``
among them (``x`` stacks the joint accelerations, rad/s² or m/s², and the
contact forces, N). About as long as the walk itself on one core.
"""

from __future__ import annotations

import argparse
import math
import sys
from typing import NamedTuple

import numpy as np

from amlip_qp.control.wbc.config import QP_SOLVERS
from amlip_qp.control.wbc.tracker import QPTracker
from amlip_qp.exceptions import InputError, QPError
from amlip_qp.qp.daqp_solver import DAQPSolver
from amlip_qp.qp.problem import QPProblem
from amlip_qp.sim.loop.run_types import Push
from amlip_qp.sim.scenarios.factory import build_simulation, load
from amlip_qp.sim.scenarios.named import get_scenario
from amlip_qp.sim.scenarios.scenarios import Scenario, check_scenario

#: A tick's solution is off the optimum above this excess cost, relative to ``max(1, |cost*|)``.
RELATIVE_COST_TOL = 1e-3
#: When the push starts and how long it lasts, s.
PUSH_START_S, PUSH_DURATION_S = 3.0, 0.2


class Tick(NamedTuple):
    """One tick the tracker solved: its time (s); whether it was solved without the torque rows; the
    excess cost of its solution over a fresh solve's and ``max |x - x*|`` (NaN when not compared or
    when the fresh solve failed); and whether that makes it off the optimum."""

    t_s: float
    relaxed: bool
    excess_cost: float
    dx: float
    off: bool


def cost(problem: QPProblem, x: np.ndarray) -> float:
    """The problem's objective ``1/2 x'Hx + g'x`` at ``x``."""
    return float(0.5 * x @ problem.H @ x + problem.g @ x)


def judge(t_s: float, problem: QPProblem, x: np.ndarray, relaxed: bool, reference: DAQPSolver) -> Tick:
    """The :class:`Tick` of a solution ``x`` of ``problem`` against a fresh solve (none when ``relaxed``)."""
    if relaxed:
        return Tick(t_s, True, math.nan, math.nan, False)
    try:
        x_star = reference.solve(problem).x
    except QPError:
        return Tick(t_s, False, math.nan, math.nan, True)
    best = cost(problem, x_star)
    excess = cost(problem, x) - best
    return Tick(t_s, False, excess, float(np.abs(x - x_star).max()), excess > RELATIVE_COST_TOL * max(1.0, abs(best)))


def pushed_scenario(scenario: str, push_Ns: float, duration_s: float) -> Scenario:
    """The named scenario for ``duration_s``, with the forward push of ``push_Ns`` (none at 0) besides its own.

    Raises:
        InputError: An unknown scenario, or a duration or push outside the robot's bounds
            (:func:`~amlip_qp.sim.scenarios.scenarios.check_scenario`).
    """
    sc = get_scenario(scenario)
    force = (push_Ns / PUSH_DURATION_S, 0.0, 0.0)
    pushes = (*sc.pushes, Push(PUSH_START_S, force, PUSH_DURATION_S)) if push_Ns > 0.0 else sc.pushes
    sc = sc.with_(pushes=pushes, duration_s=duration_s)
    check_scenario(sc)
    return sc


def walk(scenario: str, solver: str, push_Ns: float, duration_s: float) -> tuple[list[Tick], dict]:
    """Walk ``scenario`` with the QP tracker on ``solver``; every solved tick judged (:func:`judge`), and
    the walk's outcome (``fell``, ``fall_time_s``, ``fallbacks``)."""
    sc = pushed_scenario(scenario, push_Ns, duration_s)
    tracker = QPTracker(load(sc.robot), qp_solver=solver)
    tracker.record = True
    sim = build_simulation(sc, tracker)
    dt_s = sim.controller.dt_s
    calls: list[tuple[float, bool, bool]] = []  # per recorded problem: its tick's time, relaxed, solved
    ticks_seen: list[None] = []  # one entry per tracker call: the tick's index
    compute = tracker.compute

    def recording_compute(kin, target):
        before = len(tracker.recorded)
        result = compute(kin, target)
        if len(tracker.recorded) > before:
            calls.append((len(ticks_seen) * dt_s, bool(result.info.get("relaxed", 0.0)), bool(result.ok)))
        ticks_seen.append(None)
        return result

    tracker.compute = recording_compute  # type: ignore[method-assign]
    result = sim.run(sc.duration_s, log="summary")
    reference = DAQPSolver(warm_start=False)
    recorded = zip(calls, tracker.recorded)  # a failed solve is recorded too (x NaN): the fallback's tick
    ticks = [judge(t, p, x, rel, reference) for (t, rel, solved), (p, x) in recorded if solved]
    return ticks, {"fell": bool(result.fell), "fall_time_s": result.fall_time_s, "fallbacks": tracker.fallbacks}


def table_row(scenario: str, solver: str, ticks: list[Tick], outcome: dict) -> str:
    """The table's row of one walk (see the module doc)."""
    walked = f"fell at {outcome['fall_time_s']:.2f} s" if outcome["fell"] else "walked"
    relaxed = [k for k in ticks if k.relaxed]
    first = f" (first at {relaxed[0].t_s:.4f} s)" if relaxed else ""
    cells = []
    before = [k for k in ticks if k.off and k.t_s < PUSH_START_S]
    after = [k for k in ticks if k.off and k.t_s >= PUSH_START_S]
    for part in (before, after):
        if not part:
            cells.append("0")
            continue
        excess = max((k.excess_cost for k in part if not math.isnan(k.excess_cost)), default=math.nan)
        dx = max((k.dx for k in part if not math.isnan(k.dx)), default=math.nan)
        cells.append(f"{len(part)} (from {part[0].t_s:.4f} s; cost up to +{excess:.3g}, dx up to {dx:.3g})")
    return (
        f"| {scenario} | {solver} | {walked}, {outcome['fallbacks']} fallbacks | {len(ticks)} | "
        f"{len(relaxed)}{first} | {cells[0]} | {cells[1]} |"
    )


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenario", default="rabbit-0.5mps", help="a named scenario (rabbit-0.5mps)")
    parser.add_argument("--solvers", default="daqp,proxqp", help="the QP tracker's solvers, comma-separated")
    parser.add_argument("--push", type=float, default=0.0, help="forward push at 3 s, N s over 0.2 s (0: none)")
    parser.add_argument("--duration", type=float, default=4.0, help="seconds walked (4)")
    args = parser.parse_args(argv)
    solvers = [s.strip() for s in args.solvers.split(",") if s.strip()]
    try:
        if not solvers or any(s not in QP_SOLVERS for s in solvers):
            raise InputError(f"--solvers: choose from {', '.join(QP_SOLVERS)}, got {args.solvers!r}")
        if not (math.isfinite(args.push) and args.push >= 0.0):
            raise InputError(f"--push must be a forward impulse >= 0 N s, got {args.push!r}")
        if not (math.isfinite(args.duration) and args.duration > 0.0):
            raise InputError(f"--duration must be a positive number of seconds, got {args.duration!r}")
        if args.push > 0.0 and args.duration <= PUSH_START_S + PUSH_DURATION_S:
            raise InputError(f"--duration must pass the push's end, {PUSH_START_S + PUSH_DURATION_S:g} s")
        pushed_scenario(args.scenario, args.push, args.duration)  # the robot's bounds, before any walk
    except InputError as exc:
        parser.error(str(exc))
    print(
        "| scenario | solver | walk | ticks solved | solved without the torque rows | off the optimum before"
        " 3 s | off the optimum from 3 s |"
    )
    print("|---|---|---|---:|---|---|---|")
    for solver in solvers:
        ticks, outcome = walk(args.scenario, solver, args.push, args.duration)
        print(table_row(args.scenario, solver, ticks, outcome), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
