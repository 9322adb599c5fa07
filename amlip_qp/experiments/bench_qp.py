"""``amlip-qp bench qp``: replay recorded tracker QPs through every installed QP solver.

:func:`record_walk` runs a scenario with the whole-body QP tracker (the
tracker named ``"qp"`` in :data:`amlip_qp.control.registry.TRACKER_MODULES`, with ProxQP whatever
the profile's solver: :data:`RECORD_QP_SOLVER`; the full problem in every tick, so that every
recorded problem has one shape) and
copies every tick's problem, keeping the whole controller tick times
(estimate, plan, build, solve) and MuJoCo's state at the end of the walk.
:func:`bench_solvers` replays the recorded sequence through every solver of
:data:`amlip_qp.experiments.qp_solver_list.SOLVERS` that imports, each driven through
its own interface (:mod:`amlip_qp.experiments.qp_runners`,
:mod:`amlip_qp.experiments.qp_runners_sparse`): the tracker's warm-started
persistent ProxQP (the reference of the time ratios) and ProxQP re-initialised
at every problem, DAQP hot-started, PIQP, Clarabel, QPALM, quadprog, qpmad,
OSQP and the other ``qpsolvers`` backends.

It reports per solver the median and 99th percentile solve time per problem
(µs), its ratio to the warm ProxQP median, the median in MuJoCo steps (over
the time of one ``mj_step`` alone on the walk's end state,
:mod:`amlip_qp.experiments.mujoco_yardstick`, so that the figure carries across
machines), and its agreement with reference solutions
(:func:`reference_solutions`; :mod:`amlip_qp.experiments.bench_qp_report`).

The solvers take turns in blocks of :data:`BLOCK_PROBLEMS` consecutive
problems (each keeping its own state and seeing the problems in order), and
the MuJoCo yardstick runs once in every block, so the machine's speed drifts
(up to 1.6x within minutes on the 2-core development machine) affect every
solver alike and the ratios stay comparable. Each runner builds a block's
problems in its solver's own format before timing them; the timed call is
what a tracker keeping that solver would do per tick (the report says what).

Recording needs the controller and the MuJoCo plant, so the benchmark lives
in ``sim``, the layer that may import both (``docs/ARCHITECTURE.md``).

Arguments :func:`run_bench` reads from the namespace:

- ``json``: ``None``, ``"-"`` (JSON on stdout, table on stderr) or a file path;
- ``ticks``: number of recorded tracker QPs to replay (default 1200 when absent);
- ``scenario``: optional scenario name (default ``"cassie-1mps"``);
- ``solvers``: optional comma-separated solver names (default: all).
"""

from __future__ import annotations

import argparse
import contextlib
import os
import sys
import time
import warnings
from typing import TYPE_CHECKING

import numpy as np

from amlip_qp.control.registry import tracker_class
from amlip_qp.exceptions import InputError, QPError
from amlip_qp.experiments import qp_solver_list
from amlip_qp.experiments.bench_qp_report import agreement, format_report, time_stats
from amlip_qp.experiments.mujoco_yardstick import snapshot_walk, step_time_us
from amlip_qp.experiments.qp_runners import DAQPRunner, ProxSuiteRunner, Runner
from amlip_qp.experiments.qp_solver_list import REFERENCE, SolverSettings, SolverSpec
from amlip_qp.profiles import DEFAULT_ROBOT, DEFAULT_SCENARIO
from amlip_qp.qp.problem import QPProblem
from amlip_qp.qp.solver import ProxQPSolver
from amlip_qp.sim.scenarios.factory import build_simulation, load
from amlip_qp.sim.scenarios.named import get_scenario

if TYPE_CHECKING:  # pragma: no cover - typing only
    from amlip_qp.control.wbc.tracker import QPTracker
    from amlip_qp.robots.robot import Robot

__all__ = ["bench_solvers", "format_report", "record_walk", "reference_solutions", "run", "run_bench"]

#: The tracker whose problems are recorded (a name of :data:`amlip_qp.control.registry.TRACKER_MODULES`).
QP_TRACKER = "qp"

#: Problems solved untimed before the timed pass (CPU frequency and caches
#: settle; the first few hundred solves on an idle machine ran up to 1.5x slower).
WARMUP_PROBLEMS = 200

#: Problems per turn when the solvers take turns (see :func:`time_interleaved`).
BLOCK_PROBLEMS = 50

#: Tolerances the reference ProxQP tries in turn (the first it reaches in :data:`REFERENCE_MAX_ITER`).
REFERENCE_EPS = (1e-12, 1e-11, 1e-10, 1e-9)
REFERENCE_MAX_ITER = 1000


#: The solver of the recording tracker, whichever the robot's profile names: ProxQP, the path whose
#: warm solve is the reference of the time ratios, so the recorded walk is the one that solver drove.
RECORD_QP_SOLVER = "proxqp"


def _make_qp_tracker(robot: Robot, airborne_reduction: bool = False) -> QPTracker:
    """A new :data:`QP_TRACKER` for ``robot`` with :data:`RECORD_QP_SOLVER`, typed as the whole-body QP
    tracker it is; ``airborne_reduction`` as :class:`QPTracker`'s (here off by default: the full
    problem in every tick, one shape)."""
    from amlip_qp.control.wbc.tracker import QPTracker

    cls = tracker_class(QP_TRACKER)
    assert cls is QPTracker, f"tracker {QP_TRACKER!r} is a {cls.__name__}"
    return QPTracker(robot, qp_solver=RECORD_QP_SOLVER, airborne_reduction=airborne_reduction)


def record_walk(
    n_ticks: int = 1200,
    scenario: str = DEFAULT_SCENARIO,
    t_skip_s: float = 1.0,
    mujoco_state: list | None = None,
    airborne_reduction: bool = False,
):
    """Run ``scenario`` with a recording QP tracker.

    Args:
        n_ticks: Problems to keep (after ``t_skip_s``), >= 1.
        scenario: A name of :data:`amlip_qp.sim.scenarios.named.SCENARIOS`.
        t_skip_s: Walking time to skip before recording starts (start-up), s.
        mujoco_state: If given, MuJoCo's ``(model, data)`` at the end of the walk is appended to it
            (the state the yardstick replays, :func:`amlip_qp.experiments.mujoco_yardstick.step_time_us`).
        airborne_reduction: Record the problems the tracker solves by default, the airborne problem
            while the swing foot is in the air (two shapes), instead of the full problem in every
            tick (``False``, the default here: one shape, which :func:`bench_solvers` needs).

    The problems are copied by a harness callback after each timed tick, so
    the tick times do not include the recording.

    Returns:
        ``(problems, tick_time_us, fell)``: the problems of the ticks solved
        after ``t_skip_s``, the controller tick wall times of those ticks (µs),
        and whether the robot fell.
    """
    if n_ticks < 1:
        raise InputError(f"n_ticks must be >= 1, got {n_ticks}")
    sc = get_scenario(scenario)
    tracker = _make_qp_tracker(load(sc.robot), airborne_reduction)
    sim = build_simulation(sc, tracker)
    dt_s = sim.controller.dt_s
    duration = t_skip_s + n_ticks * dt_s
    problems: list[QPProblem] = []
    seen: dict[str, np.ndarray | None] = {"x": None}

    def keep(t_s, data) -> None:
        # After the timed controller tick: copy the problem it solved.
        x = tracker.last_solution
        if t_s > t_skip_s + 1e-9 and x is not None and x is not seen["x"] and tracker.last_problem is not None:
            problems.append(tracker.last_problem.copy())
        seen["x"] = x

    results: list = []
    state = snapshot_walk(lambda: results.append(sim.run(duration, on_tick=keep)))
    if mujoco_state is not None:
        mujoco_state.append(state)
    skip = int(round(t_skip_s / dt_s))
    return problems, results[0].tick_time_us[skip:], results[0].fell


def tracker_solver_options() -> dict:
    """The ProxQP options of the whole-body QP tracker's ProxQP path (``QPTracker(qp_solver="proxqp")``,
    taken from a tracker of the default robot)."""
    from amlip_qp.control.wbc.tracker import QPTracker

    return QPTracker(load(DEFAULT_ROBOT), qp_solver="proxqp").solver.options


def reference_solutions(problems: list[QPProblem]) -> tuple[list[np.ndarray], dict[float, int]]:
    """ProxQP re-initialised on every problem at the tightest tolerance of :data:`REFERENCE_EPS` it
    reaches. Returns the solutions and how many problems each tolerance solved.

    Raises:
        QPError: a problem no tolerance solved.
    """
    solvers = {
        eps: ProxQPSolver(eps_abs=eps, max_iter=REFERENCE_MAX_ITER, warm_start=False, eps_primal_inf=1e-12)
        for eps in REFERENCE_EPS
    }
    refs: list[np.ndarray] = []
    used = dict.fromkeys(REFERENCE_EPS, 0)
    for p in problems:
        for eps, solver in solvers.items():
            try:
                refs.append(solver.solve(p).x)
            except QPError:
                continue
            used[eps] += 1
            break
        else:
            raise QPError("the reference ProxQP solved no tolerance of this problem", problem=p)
    return refs, used


def time_interleaved(
    problems: list[QPProblem], runners: dict[str, Runner], block: int = BLOCK_PROBLEMS, yardstick: tuple | None = None
) -> tuple[dict[str, list[float]], dict[str, list], list[float]]:
    """Time every runner on every problem, µs. The runners take turns in blocks of ``block``
    consecutive problems (each keeps its own state and sees the problems in order; it builds the
    block's data untimed first): the machine's slow speed drifts hit every solver alike, while
    within a block each solver runs with warm caches, as in the tracker's loop (solving problem by
    problem in turn let osqp's large sparse set-up evict the others' data and doubled their times).
    ``yardstick``: MuJoCo's ``(model, data)``, one step-time measurement per block.

    Returns:
        ``(times_us, solutions, step_us)``: per runner the times and the solutions (``None`` where
        it found none), and the yardstick's step time of each block (µs).
    """
    times: dict[str, list[float]] = {name: [] for name in runners}
    solutions: dict[str, list] = {name: [] for name in runners}
    steps_us: list[float] = []
    clock = time.perf_counter_ns
    for start in range(0, len(problems), block):
        chunk = problems[start : start + block]
        for name, run in runners.items():
            data = [run.prepare(p) for p in chunk]
            out, xs = times[name], solutions[name]
            for d in data:
                run.load(d)
                t0 = clock()
                x = run.solve(d)
                out.append((clock() - t0) * 1e-3)
                xs.append(x)
        if yardstick is not None:
            model, mj_data = yardstick
            steps_us.append(step_time_us(model, mj_data, rounds=1))
    return times, solutions, steps_us


def solver_settings() -> SolverSettings:
    """What the runners are built with: the tracker's ProxQP options, its absolute tolerance for the
    iterative solvers and its ProxQP's primal infeasibility threshold."""
    options = tracker_solver_options()
    return SolverSettings(
        proxqp=options, eps_abs=float(options["eps_abs"]), eps_primal_inf=float(options["eps_primal_inf"])
    )


def bench_solvers(
    problems: list[QPProblem],
    solvers: tuple[SolverSpec, ...] = qp_solver_list.SOLVERS,
    settings: SolverSettings | None = None,
    yardstick: tuple | None = None,
) -> dict:
    """Solve-time statistics and agreement per solver on ``problems`` (see the module docstring).

    Args:
        problems: Problems of one shape, in the tracker's order.
        solvers: The solvers to compare (:data:`~amlip_qp.experiments.qp_solver_list.REFERENCE` is added
            when absent); those that do not import are listed under ``missing``.
        settings: What the runners are built with (default: the tracker's ProxQP options and its
            absolute tolerance for the iterative solvers).
        yardstick: MuJoCo's ``(model, data)`` for the step-time yardstick, or ``None``.

    Returns:
        ``{"solvers": {name: {"median_us", "p99_us", "n", "failures", "ratio_to_warm", "max_dx",
        "max_violation", "max_cost_excess", "start", "timed"}}, "missing": [lines], "versions"
        (pip package -> version), "mujoco_step_us", "reference", "reference_eps"}`` (ProxSuite entries also count
        ``cold_retries``: failed warm solves retried from scratch, as the tracker does, timing included; the
        hot DAQP runners give ``update_median_us`` and ``solve_median_us``: DAQP's update and solve timed apart).
    """
    if not problems:
        raise InputError("bench_solvers needs at least one problem")
    if {(p.n, p.n_eq, p.n_in) for p in problems} != {(problems[0].n, problems[0].n_eq, problems[0].n_in)}:
        raise InputError("bench_solvers needs problems of one shape (a tracker keeps its layout)")
    settings = settings if settings is not None else solver_settings()
    specs = solvers if any(s.name == REFERENCE for s in solvers) else (qp_solver_list.SOLVERS[0], *solvers)
    present = [s for s in specs if qp_solver_list.available(s)]
    missing = [qp_solver_list.missing_line(s) for s in specs if s not in present]

    def make_runners() -> dict[str, Runner]:
        runners = {s.name: s.make(settings) for s in present}
        for run in runners.values():
            run.setup(problems)
        return runners

    refs, used = reference_solutions(problems)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the backends' conversion notices (dense to sparse, ...)
        time_interleaved(problems[:WARMUP_PROBLEMS], make_runners())  # untimed warm-up
        runners = make_runners()
        times, solutions, steps_us = time_interleaved(problems, runners, yardstick=yardstick)
    out: dict[str, dict] = {}
    for name, run in runners.items():
        out[name] = {**time_stats(times[name]), "failures": run.failures, **agreement(problems, solutions[name], refs)}
        out[name].update(start=run.start, timed=run.timed)
        if isinstance(run, ProxSuiteRunner):
            out[name]["cold_retries"] = run.retries
        if isinstance(run, DAQPRunner) and run.update_ns and run.solve_ns:
            out[name]["update_median_us"] = float(np.median(run.update_ns)) * 1e-3
            out[name]["solve_median_us"] = float(np.median(run.solve_ns)) * 1e-3
    ref = out[REFERENCE]["median_us"]
    for stats in out.values():
        stats["ratio_to_warm"] = stats["median_us"] / ref if ref > 0 else float("nan")
    tightest = min(e for e, k in used.items() if k)
    loosest = max(e for e, k in used.items() if k)
    return {
        "solvers": out,
        "missing": missing,
        "versions": qp_solver_list.versions(present),
        "mujoco_step_us": float(np.median(steps_us)) if steps_us else None,
        "reference": f"ProxQP re-initialised at eps_abs {tightest:g}"
        + (f" ({used[tightest]} problems; up to {loosest:g} for the rest)" if loosest != tightest else ""),
        "reference_eps": {f"{e:g}": k for e, k in used.items()},
    }


@contextlib.contextmanager
def solver_output_to_stderr():
    """Send what the solvers print themselves (from C: HiGHS' banner, Gurobi's licence line) to
    stderr meanwhile, so that ``--json -`` keeps stdout pure JSON."""
    sys.stdout.flush()
    saved = os.dup(1)
    try:
        os.dup2(2, 1)
        yield
    finally:
        os.dup2(saved, 1)
        os.close(saved)


def run(n_ticks: int = 1200, scenario: str = DEFAULT_SCENARIO, solvers: str | None = None) -> dict:
    """Record a walk, bench the solvers, and return the JSON-ready report.

    Returns:
        :func:`bench_solvers`' report with ``"tick_us": {"median", "p99"}``, ``"n_problems"``,
        ``"scenario"``, ``"fell"``, and ``"settings"`` (the tracker's ProxQP options).
    """
    specs = qp_solver_list.select(solvers)
    state: list = []
    problems, tick_us, fell = record_walk(n_ticks, scenario, mujoco_state=state)
    settings = solver_settings()
    with solver_output_to_stderr():
        report = bench_solvers(problems, specs, settings, yardstick=state[0])
    return {
        "scenario": scenario,
        "n_problems": len(problems),
        "fell": bool(fell),
        **report,
        "settings": {"proxqp": settings.proxqp, "eps_abs_iterative": settings.eps_abs},
        "tick_us": {"median": float(np.median(tick_us)), "p99": float(np.percentile(tick_us, 99))},
    }


def run_bench(args: argparse.Namespace) -> int:
    """Record a walk, replay its QPs through every solver, print the table (and JSON)."""
    from amlip_qp.output_paths import check_output_path, emit_report

    n_ticks = int(getattr(args, "ticks", None) or 1200)
    scenario = getattr(args, "scenario", None) or DEFAULT_SCENARIO
    solvers = getattr(args, "solvers", None)
    target = getattr(args, "json", None)
    check_output_path("--json", target)
    qp_solver_list.select(solvers)  # a bad name exits 2 before the walk
    get_scenario(scenario)
    report = run(n_ticks=n_ticks, scenario=scenario, solvers=solvers)
    emit_report(format_report(report), report, target)
    return 0 if not report["fell"] else 1
