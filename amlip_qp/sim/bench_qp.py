"""``amlip-qp bench qp``: replay recorded tracker QPs through several solvers.

:func:`record_walk` runs a scenario with the whole-body QP tracker (the
tracker named ``"qp"`` in :data:`amlip_qp.sim.factory.TRACKER_MODULES`) and
copies every tick's problem, keeping the whole controller tick times
(estimate, plan, build, solve). :func:`bench_solvers` replays the recorded
sequence through

- ``proxsuite-warm``: one persistent ProxQP, ``update`` + warm start (the
  tracker's path);
- ``proxsuite-init``: ProxQP re-initialised at every problem (as TSID does);
- every other installed ``qpsolvers`` backend among daqp, osqp, quadprog
  (fixed variables substituted first,
  :meth:`~amlip_qp.qp.problem.QPProblem.without_fixed_variables`);

and reports the median and 99th percentile solve time per solver (µs) and
each one's ratio to the warm ProxSuite path. The solvers take turns in
blocks of 50 consecutive problems (each keeping its own state), so the
machine's slow speed drifts, which reached 1.6x between runs on the 2-core
development machine, affect every solver alike and the ratios stay
comparable.

Recording needs the controller and the MuJoCo plant, so the benchmark lives
in ``sim``, the layer that may import both (``docs/ARCHITECTURE.md``).

Arguments :func:`run_bench` reads from the namespace:

- ``json``: ``None``, ``"-"`` (JSON on stdout, table on stderr) or a file path;
- ``ticks``: number of recorded tracker QPs to replay (>= 1000 for a
  measurement; default 1200 when absent);
- ``scenario``: optional scenario name (default ``"cassie-1mps"``).
"""

from __future__ import annotations

import argparse
import time
import warnings
from typing import TYPE_CHECKING

import numpy as np

from amlip_qp.exceptions import InputError, QPError
from amlip_qp.qp.problem import QPProblem
from amlip_qp.qp.solver import ProxQPSolver
from amlip_qp.sim.factory import build_simulation, load, make_tracker
from amlip_qp.sim.scenarios import get_scenario

if TYPE_CHECKING:  # pragma: no cover - typing only
    from amlip_qp.control.wbc.tracker import QPTracker
    from amlip_qp.robots.robot import Robot

#: qpsolvers backends compared when installed.
QPSOLVERS_BACKENDS: tuple[str, ...] = ("daqp", "osqp", "quadprog")

#: The tracker whose problems are recorded (a name of :data:`amlip_qp.sim.factory.TRACKER_MODULES`).
QP_TRACKER = "qp"


def _make_qp_tracker(robot: Robot) -> QPTracker:
    """A new :data:`QP_TRACKER` for ``robot``, typed as the whole-body QP tracker it is."""
    from amlip_qp.control.wbc.tracker import QPTracker

    tracker = make_tracker(QP_TRACKER, robot)
    assert isinstance(tracker, QPTracker), f"tracker {QP_TRACKER!r} is a {type(tracker).__name__}"
    return tracker


def record_walk(n_ticks: int = 1200, scenario: str = "cassie-1mps", t_skip_s: float = 1.0):
    """Run ``scenario`` with a recording QP tracker.

    Args:
        n_ticks: Problems to keep (after ``t_skip_s``), >= 1.
        scenario: A name of :data:`amlip_qp.sim.scenarios.SCENARIOS`.
        t_skip_s: Walking time to skip before recording starts (start-up), s.

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
    tracker = _make_qp_tracker(load(sc.robot))
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

    result = sim.run(duration, on_tick=keep)
    skip = int(round(t_skip_s / dt_s))
    return problems, result.tick_time_us[skip:], result.fell


def tracker_solver_options() -> dict:
    """The ProxQP options the whole-body QP tracker uses (taken from a default tracker)."""
    return _make_qp_tracker(load("rabbit")).solver.options


def _stats(times_us: list[float]) -> dict:
    t = np.asarray(times_us, dtype=float)
    return {"median_us": float(np.median(t)), "p99_us": float(np.percentile(t, 99)), "n": int(t.size)}


#: Problems solved untimed before the timed pass (CPU frequency and caches
#: settle; the first few hundred solves on an idle machine ran up to 1.5x slower).
WARMUP_PROBLEMS = 200


class _ProxSuiteRunner:
    """The tracker's path: solve; after a failure retry once from scratch (timed too)."""

    def __init__(self, warm: bool, options: dict):
        self.solver = ProxQPSolver(**{**options, "warm_start": warm})
        self.failures = 0
        self.retries = 0

    def __call__(self, problem: QPProblem) -> None:
        try:
            self.solver.solve(problem)
        except QPError:
            self.retries += 1
            try:
                self.solver.solve(problem)
            except QPError:
                self.failures += 1


class _QPSolversRunner:
    """One ``qpsolvers`` backend (stateless: fixed variables substituted per problem)."""

    def __init__(self, backend: str):
        self.backend = backend
        self.failures = 0

    def __call__(self, problem: QPProblem) -> None:
        try:
            problem.solve_with(self.backend)
        except QPError:
            self.failures += 1


#: Problems per turn when the solvers take turns (see :func:`_time_interleaved`).
BLOCK_PROBLEMS = 50


def _time_interleaved(problems: list[QPProblem], runners: dict, block: int = BLOCK_PROBLEMS) -> dict[str, list[float]]:
    """Time every runner on every problem, µs. The runners take turns in
    blocks of ``block`` consecutive problems (each keeps its own state and sees
    the problems in order): the machine's slow speed drifts hit every solver
    alike, while within a block each solver runs with warm caches, as in the
    tracker's loop (solving problem by problem in turn let osqp's large sparse
    set-up evict the others' data and doubled their times)."""
    times: dict[str, list[float]] = {name: [] for name in runners}
    clock = time.perf_counter_ns
    for start in range(0, len(problems), block):
        chunk = problems[start : start + block]
        for name, run in runners.items():
            out = times[name]
            for p in chunk:
                t0 = clock()
                run(p)
                out.append((clock() - t0) * 1e-3)
    return times


def bench_solvers(
    problems: list[QPProblem], backends: tuple[str, ...] | None = None, solver_options: dict | None = None
) -> dict:
    """Solve-time statistics per solver on ``problems`` (see the module docstring).

    ``solver_options`` are the :class:`~amlip_qp.qp.solver.ProxQPSolver` arguments of both
    ProxSuite entries (default: the tracker's, :func:`tracker_solver_options`), so the
    bench times the solver exactly as the tracker runs it.

    Returns:
        ``{name: {"median_us", "p99_us", "n", "failures", "ratio_to_warm"}}``
        (ProxSuite entries also count ``cold_retries``: failed warm solves
        retried from scratch, as the tracker does, timing included);
        ``ratio_to_warm`` is the median over the warm ProxSuite median.
    """
    import qpsolvers

    if not problems:
        raise InputError("bench_solvers needs at least one problem")
    options = solver_options if solver_options is not None else tracker_solver_options()
    wanted = backends if backends is not None else QPSOLVERS_BACKENDS

    def make_runners() -> dict[str, _ProxSuiteRunner | _QPSolversRunner]:
        runners: dict[str, _ProxSuiteRunner | _QPSolversRunner] = {
            "proxsuite-warm": _ProxSuiteRunner(True, options),
            "proxsuite-init": _ProxSuiteRunner(False, options),
        }
        for backend in wanted:
            if backend in qpsolvers.available_solvers:
                runners[backend] = _QPSolversRunner(backend)
        return runners

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # osqp's dense-to-sparse conversion notices
        _time_interleaved(problems[:WARMUP_PROBLEMS], make_runners())  # untimed warm-up
        runners = make_runners()
        times = _time_interleaved(problems, runners)
    out: dict[str, dict] = {}
    for name, run in runners.items():
        out[name] = {**_stats(times[name]), "failures": run.failures}
        if isinstance(run, _ProxSuiteRunner):
            out[name]["cold_retries"] = run.retries
    ref = out["proxsuite-warm"]["median_us"]
    for stats in out.values():
        stats["ratio_to_warm"] = stats["median_us"] / ref if ref > 0 else float("nan")
    return out


def run(n_ticks: int = 1200, scenario: str = "cassie-1mps") -> dict:
    """Record a walk, bench the solvers, and return the JSON-ready report.

    Returns:
        ``{"solvers": {...}, "tick_us": {"median", "p99"}, "n_problems", "scenario", "fell",
        "missing_backends"}``; ``missing_backends`` lists the backends of
        :data:`QPSOLVERS_BACKENDS` that are not installed (the ``bench`` extra).
    """
    import qpsolvers

    problems, tick_us, fell = record_walk(n_ticks, scenario)
    return {
        "missing_backends": [b for b in QPSOLVERS_BACKENDS if b not in qpsolvers.available_solvers],
        "scenario": scenario,
        "n_problems": len(problems),
        "fell": bool(fell),
        "solvers": bench_solvers(problems),
        "tick_us": {"median": float(np.median(tick_us)), "p99": float(np.percentile(tick_us, 99))},
    }


def format_report(report: dict) -> str:
    """A human-readable table of :func:`run`'s report."""
    lines = [
        f"{report['n_problems']} tracker QPs replayed from {report['scenario']}",
        f"{'solver':<16}{'median µs':>12}{'p99 µs':>12}{'x warm':>9}{'fails':>7}",
    ]
    for name, s in report["solvers"].items():
        lines.append(
            f"{name:<16}{s['median_us']:>12.1f}{s['p99_us']:>12.1f}{s['ratio_to_warm']:>9.2f}{s['failures']:>7d}"
        )
    t = report["tick_us"]
    lines.append(f"controller tick (estimate, plan, build, solve): median {t['median']:.1f} µs, p99 {t['p99']:.1f} µs")
    missing = report.get("missing_backends") or []
    if missing:
        lines.append(f"not installed, not compared: {', '.join(missing)} (pip install -e '.[bench]')")
    return "\n".join(lines)


def run_bench(args: argparse.Namespace) -> int:
    """Record a walk, replay its QPs through every solver, print the table (and JSON)."""
    from amlip_qp.output_paths import check_output_path, emit_report

    n_ticks = int(getattr(args, "ticks", None) or 1200)
    scenario = getattr(args, "scenario", None) or "cassie-1mps"
    target = getattr(args, "json", None)
    check_output_path("--json", target)
    report = run(n_ticks=n_ticks, scenario=scenario)
    emit_report(format_report(report), report, target)
    return 0 if not report["fell"] else 1
