"""amlip_qp.experiments.bench_qp (`amlip-qp bench qp`): recording a walk's QPs, every solver's answer against
ProxQP's, the report, a solver that is not installed, bad arguments."""

import re

import numpy as np
import pytest

from amlip_qp.cli import main
from amlip_qp.experiments import qp_solver_list
from amlip_qp.experiments.bench_qp import (
    bench_solvers,
    format_report,
    record_walk,
    reference_solutions,
    tracker_solver_options,
)
from amlip_qp.experiments.bench_qp_report import agreement
from amlip_qp.experiments.qp_runners_sparse import QPSolversRunner
from amlip_qp.experiments.qp_solver_list import SolverSpec

#: The solvers of the `test` extra (pyproject.toml), each driven through its own interface.
TEST_EXTRA_SOLVERS = ",".join(
    ("proxsuite-init", "daqp-hot", "daqp-hot-model", "daqp-tracker", "daqp-cold", "daqp-eliminated")
    + ("piqp", "clarabel", "qpalm", "quadprog", "qpmad", "eiquadprog", "osqp")
)
#: Active-set solvers: their x matches the reference's to this (the reference stops at 1e-12), and
#: their cost exceeds the reference's by at most this (the optimal costs are of order -1e3 to -1e4).
EXACT, EXACT_DX, EXACT_COST = (
    ("daqp-hot", "daqp-hot-model", "daqp-tracker", "daqp-cold", "daqp-eliminated", "quadprog", "qpmad", "eiquadprog"),
    1e-5,
    1e-6,
)
#: Interior-point solvers (their own duality-gap tolerances): cost excess at most this.
INTERIOR, INTERIOR_COST = ("piqp", "clarabel"), 1e-3
#: The solvers stopped at the tracker's absolute tolerance 1e-3 (ProxQP, OSQP, QPALM): the cost is
#: nearly flat along the split of the contact forces, and the equalities' multipliers (up to about
#: 1e4) times the residual the tolerance allows move it too; on these problems ProxQP re-initialised
#: at that tolerance ended up to 81 above the optimum, the tracker's warm ProxQP up to 12.
COARSE_COST = 200.0
#: Every solver: constraint violation at most this (twice the tracker's tolerance).
VIOLATION = 2e-3


@pytest.fixture(scope="module")
def walk():
    state = []
    problems, tick_us, fell = record_walk(n_ticks=120, scenario="cassie-1mps", t_skip_s=0.6, mujoco_state=state)
    return problems, tick_us, fell, state


def test_record_walk_keeps_the_full_problem_unless_asked_for_the_default_trackers(walk):
    """The solver benchmark's problems have one shape (the full problem in every tick); the MPC
    benchmark asks for the problems the default tracker solves: the airborne one mid-swing too."""
    problems = walk[0]
    assert len({p.n for p in problems}) == 1
    airborne, _, fell = record_walk(n_ticks=120, scenario="cassie-1mps", t_skip_s=0.6, airborne_reduction=True)
    assert not fell
    sizes = {p.n for p in airborne}
    assert len(sizes) == 2 and max(sizes) == problems[0].n


def test_record_walk_keeps_one_distinct_problem_per_solved_tick(walk):
    problems, tick_us, fell, state = walk
    assert not fell
    assert len(tick_us) == 120
    assert np.all(tick_us > 0)
    assert 118 <= len(problems) <= 120  # the tracker solved (almost) every tick
    # Copies, not the builder's live buffers: consecutive states differ.
    assert problems[0].H is not problems[1].H
    assert not np.array_equal(problems[0].b, problems[-1].b)
    for p in problems:
        p.validate()
    # Both kinds of tick: swing forces pinned to zero (lb == ub) and free (double support).
    n_fixed = {int(np.sum(p.lb == p.ub)) for p in problems}
    assert 0 in n_fixed and len(n_fixed) == 2
    assert len(state) == 1
    _, data = state[0]  # MuJoCo's state at the end of the walk, for the yardstick
    assert data.time > 0.6


def test_the_bench_times_the_solver_with_the_trackers_options():
    from amlip_qp.control.wbc.tracker import QPTracker
    from amlip_qp.sim.scenarios.factory import load

    options = tracker_solver_options()
    assert options == QPTracker(load("cassie"), qp_solver="proxqp").solver.options
    assert set(options) >= {"eps_abs", "max_iter", "warm_start"}


def test_the_reference_meets_a_tight_tolerance(walk):
    problems = walk[0][:40]
    refs, used = reference_solutions(problems)
    assert sum(used.values()) == 40
    assert max(max(p.residuals(x).values()) for p, x in zip(problems, refs)) < 1e-8


@pytest.fixture(scope="module")
def report(walk):
    problems, _, _, state = walk
    specs = qp_solver_list.select(TEST_EXTRA_SOLVERS)
    return bench_solvers(problems, specs, yardstick=state[0])


def test_daqps_update_and_solve_are_timed_apart_inside_its_hot_call(report):
    """The hot DAQP runners time DAQP's update and its solve apart, inside the timed call: both
    positive, together about the call (medians of the parts against the median of the whole)."""
    for name in ("daqp-hot", "daqp-hot-model"):
        s = report["solvers"][name]
        assert s["update_median_us"] > 0.0 and s["solve_median_us"] > 0.0
        assert s["update_median_us"] + s["solve_median_us"] < 1.5 * s["median_us"]
    for name in ("daqp-cold", "daqp-tracker", "proxsuite-init"):
        assert "update_median_us" not in report["solvers"][name]
    text = format_report(report)
    assert text.count("of it, timed apart (medians): DAQP's update") == 2


def test_every_test_extra_solver_agrees_with_proxqp(report):
    stats = report["solvers"]
    assert set(stats) == {"proxsuite-warm", *TEST_EXTRA_SOLVERS.split(",")}
    assert report["missing"] == []
    for name, s in stats.items():
        assert s["n"] >= 118 and s["failures"] == 0, name
        assert s["max_violation"] <= VIOLATION, name
        assert s["max_cost_excess"] <= COARSE_COST, name
        assert s["p99_us"] >= s["median_us"] > 0
    for name in EXACT:
        assert stats[name]["max_dx"] <= EXACT_DX and stats[name]["max_cost_excess"] <= EXACT_COST, name
    for name in INTERIOR:
        assert stats[name]["max_cost_excess"] <= INTERIOR_COST, name
    assert stats["proxsuite-warm"]["ratio_to_warm"] == 1.0
    assert stats["proxsuite-warm"]["cold_retries"] == 0
    assert report["mujoco_step_us"] > 0


def test_the_eliminated_runner_counts_a_problem_it_cannot_eliminate_as_a_failure(walk):
    from amlip_qp.experiments.qp_runners import DAQPEliminatedRunner

    good = walk[0][0]
    bad = good.copy()
    bad.A[1] = bad.A[0]  # a repeated equality row: no elimination
    bad.b[1] = bad.b[0]
    run = DAQPEliminatedRunner()
    x = run.solve(run.prepare(good))
    assert run.solve(run.prepare(bad)) is None and run.failures == 1
    assert x is not None and max(good.residuals(x).values()) < 1e-8
    assert len(run.elimination_us) == 1


@pytest.mark.parametrize("box_as_rows", [False, True])
def test_any_qpsolvers_backend_runs_through_the_generic_path(walk, box_as_rows):
    problems = walk[0][:30]
    run = QPSolversRunner("quadprog", box_as_rows=box_as_rows)
    xs = [run.solve(run.prepare(p)) for p in problems]
    refs, _ = reference_solutions(problems)
    agree = agreement(problems, xs, refs)
    assert run.failures == 0
    assert agree["max_dx"] <= EXACT_DX and agree["max_violation"] <= 1e-9


def test_the_report_names_every_solver_and_what_is_timed(report):
    text = format_report({**report, "scenario": "cassie-1mps", "n_problems": 120})
    table = text.split("timed per problem")[0]
    for name in report["solvers"]:
        assert f"\n{name} " in table and f"  {name}: " in text
    assert "MuJoCo steps" in text and "not installed" not in text
    assert report["versions"]["daqp"] in text and "pyqpmad" in report["versions"]
    # the eliminated problem's solve is timed without its elimination, whose own time is stated beside it
    assert re.search(r"daqp-eliminated: .*the elimination, untimed, took a median \d+\.\d µs", text)


def test_a_solver_that_is_not_installed_is_named_and_the_bench_goes_on(walk):
    ghost = SolverSpec("ghost", "amlip_qp_no_such_solver", "amlip-qp-no-such-solver", lambda s: None)
    specs = (*qp_solver_list.select("daqp-cold"), ghost)
    out = bench_solvers(walk[0][:20], specs)
    assert out["missing"] == ["not installed: ghost (pip install amlip-qp-no-such-solver)"]
    assert set(out["solvers"]) == {"proxsuite-warm", "daqp-cold"}
    assert "not installed: ghost (pip install amlip-qp-no-such-solver)" in format_report(out)


def test_eiquadprogs_form_holds_the_reference_solutions(walk):
    """Equalities and fixed variables as equality rows, each finite side of a row or a bound as one
    inequality row: the reference solutions satisfy them, and nothing else is added."""
    from amlip_qp.experiments.qp_runner_eiquadprog import eiquadprog_form

    problems = walk[0][:40]
    refs, _ = reference_solutions(problems)
    for p, x in zip(problems, refs):
        H, g, CE, ce0, CI, ci0 = eiquadprog_form(p)
        fixed = p.lb == p.ub
        assert CE.shape == (p.n_eq + int(fixed.sum()), p.n)
        n_in = sum(int(np.isfinite(v).sum()) for v in (p.l, p.u)) + sum(
            int((np.isfinite(v) & ~fixed).sum()) for v in (p.lb, p.ub)
        )
        assert CI.shape == (n_in, p.n)
        assert np.max(np.abs(CE @ x + ce0)) < 1e-8
        assert np.min(CI @ x + ci0) > -1e-8
        assert np.array_equal(H, p.H) and np.array_equal(g, p.g)
        assert all(a.flags.c_contiguous for a in (H, g, CE, ce0, CI, ci0))


def test_eiquadprog_solves_a_small_problem_exactly_and_names_an_infeasible_one():
    """min 1/2 |x - (1, 2)|^2 s.t. x0 + x1 = 1 (optimum (0, 1)) and x0 >= 0.5 (active): (0.5, 0.5).
    Then x0 >= 1 with x0 <= 0: no solution, counted with its status (the dual method finds the dual
    unbounded)."""
    from amlip_qp.experiments.qp_runner_eiquadprog import EiquadprogRunner
    from amlip_qp.qp.problem import QPProblem

    inf = np.inf
    p = QPProblem(
        H=np.eye(2), g=np.array([-1.0, -2.0]), A=np.array([[1.0, 1.0]]), b=np.array([1.0]),
        C=np.array([[1.0, 0.0]]), l=np.array([0.5]), u=np.array([inf]),
        lb=np.full(2, -inf), ub=np.full(2, inf),
    )  # fmt: skip
    run = EiquadprogRunner()
    x = run.solve(run.prepare(p))
    assert x is not None and np.allclose(x, [0.5, 0.5], atol=1e-12, rtol=0)
    assert run.failures == 0 and run.iterations >= 1
    bad = QPProblem(
        H=np.eye(1), g=np.zeros(1), A=np.zeros((0, 1)), b=np.zeros(0), C=np.eye(1), l=np.ones(1),
        u=np.full(1, inf), lb=np.full(1, -inf), ub=np.zeros(1),
    )  # fmt: skip
    assert run.solve(run.prepare(bad)) is None
    assert run.failures == 1 and run.statuses == {"dual unbounded (infeasible)": 1}
    # the workspace resizes back to the first problem's shape
    x = run.solve(run.prepare(p))
    assert x is not None and np.allclose(x, [0.5, 0.5], atol=1e-12, rtol=0)


def test_eiquadprog_without_a_compiler_is_named_not_usable_with_the_reason(monkeypatch, tmp_path):
    from amlip_qp.experiments import qp_runner_eiquadprog as eiq

    spec = next(s for s in qp_solver_list.SOLVERS if s.name == "eiquadprog")
    monkeypatch.setenv("AMLIP_QP_CC", "none")
    monkeypatch.setenv("AMLIP_QP_CACHE_DIR", str(tmp_path))
    eiq.load_shim.cache_clear()
    try:
        assert eiq.installed()
        assert not qp_solver_list.available(spec)
        line = qp_solver_list.missing_line(spec)
        assert line == "not usable: eiquadprog (AMLIP_QP_CC=none disables the C compiler)"
    finally:
        eiq.load_shim.cache_clear()
    assert not any(tmp_path.iterdir())


@pytest.mark.parametrize(
    "argv, needle",
    [
        (["bench", "qp", "--ticks", "0"], "expected a number of ticks in [1, 20000], got 0"),
        (["bench", "qp", "--ticks", "many"], "expected a number of ticks in [1, 20000], got 'many'"),
        (["bench", "qp", "--ticks", "20001"], "expected a number of ticks in [1, 20000], got 20001"),
        (["bench", "qp", "--scenario", "moonwalk"], "unknown scenario 'moonwalk'"),
        (["bench", "qp", "--solvers", "daqp-hot,gurobbi"], "unknown solver 'gurobbi'; choose from proxsuite-warm"),
        (["bench", "qp", "--solvers", ","], "--solvers: no solver named"),
    ],
)
def test_bad_arguments_exit_2_with_one_line(argv, needle, capsys):
    with pytest.raises(SystemExit) as info:
        code = main(argv)
        raise SystemExit(code)
    assert info.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and needle in err[0]
