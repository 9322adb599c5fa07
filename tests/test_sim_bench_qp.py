"""amlip_qp.sim.bench_qp (`amlip-qp bench qp`): recording a walk's QPs, timing solvers, the report, bad arguments."""

import numpy as np
import pytest

from amlip_qp.cli import main
from amlip_qp.qp import QPProblem
from amlip_qp.sim.bench_qp import bench_solvers, format_report, record_walk, tracker_solver_options


def test_record_walk_keeps_one_distinct_problem_per_solved_tick():
    problems, tick_us, fell = record_walk(n_ticks=40, scenario="cassie-1mps", t_skip_s=0.05)
    assert not fell
    assert len(tick_us) == 40
    assert np.all(tick_us > 0)
    assert 38 <= len(problems) <= 40  # the tracker solved (almost) every tick
    # Copies, not the builder's live buffers: consecutive states differ.
    assert problems[0].H is not problems[1].H
    assert not np.array_equal(problems[0].b, problems[-1].b)
    for p in problems:
        p.validate()


def test_the_bench_times_the_solver_with_the_trackers_options():
    from amlip_qp.sim.factory import load, make_tracker

    options = tracker_solver_options()
    assert options == make_tracker("qp", load("cassie")).solver.options
    assert set(options) >= {"eps_abs", "max_iter", "warm_start"}


def _problems(n):
    """A drifting sequence of small strictly convex QPs with an equality and a box."""
    out = []
    for k in range(n):
        H = np.array([[2.0, 0.5], [0.5, 1.0]])
        g = np.array([1.0 + 0.01 * k, -1.0])
        out.append(
            QPProblem(
                H=H, g=g, A=np.array([[1.0, 1.0]]), b=np.array([0.5]),
                C=np.array([[1.0, -1.0]]), l=np.array([-0.5]), u=np.array([0.5]),
                lb=np.full(2, -1.0), ub=np.full(2, 1.0),
            )
        )  # fmt: skip
    return out


def test_every_installed_solver_solves_every_problem_and_the_warm_path_is_the_reference():
    problems = _problems(60)
    stats = bench_solvers(problems, backends=("quadprog",), solver_options={})
    assert {"proxsuite-warm", "proxsuite-init", "quadprog"} <= set(stats)
    for s in stats.values():
        assert s["n"] == 60 and s["failures"] == 0 and s["p99_us"] >= s["median_us"] > 0
    assert stats["proxsuite-warm"]["ratio_to_warm"] == 1.0
    assert stats["proxsuite-warm"]["cold_retries"] == 0


def test_report_names_the_backends_that_are_not_installed():
    report = {
        "n_problems": 3, "scenario": "cassie-1mps", "missing_backends": ["osqp"],
        "solvers": {"proxsuite-warm": {"median_us": 70.0, "p99_us": 90.0, "ratio_to_warm": 1.0, "failures": 0}},
        "tick_us": {"median": 380.0, "p99": 700.0},
    }  # fmt: skip
    text = format_report(report)
    assert "not installed, not compared: osqp" in text and ".[bench]" in text
    report["missing_backends"] = []
    assert "not installed" not in format_report(report)


@pytest.mark.parametrize(
    "argv, needle",
    [
        (["bench", "qp", "--ticks", "0"], "expected a number of ticks in [1, 20000], got 0"),
        (["bench", "qp", "--ticks", "many"], "expected a number of ticks in [1, 20000], got 'many'"),
        (["bench", "qp", "--ticks", "20001"], "expected a number of ticks in [1, 20000], got 20001"),
        (["bench", "qp", "--scenario", "moonwalk"], "unknown scenario 'moonwalk'"),
    ],
)
def test_bad_arguments_exit_2_with_one_line(argv, needle, capsys):
    with pytest.raises(SystemExit) as info:
        code = main(argv)
        raise SystemExit(code)
    assert info.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and needle in err[0]
