"""amlip_qp.qp.bench: recording a walk's QPs outside the timed ticks."""

import numpy as np

from amlip_qp.qp.bench import record_walk


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


def test_report_names_the_backends_that_are_not_installed():
    from amlip_qp.qp.bench import format_report

    report = {
        "n_problems": 3, "scenario": "cassie-1mps", "missing_backends": ["osqp"],
        "solvers": {"proxsuite-warm": {"median_us": 70.0, "p99_us": 90.0, "ratio_to_warm": 1.0, "failures": 0}},
        "tick_us": {"median": 380.0, "p99": 700.0},
    }  # fmt: skip
    text = format_report(report)
    assert "not installed, not compared: osqp" in text and ".[bench]" in text
    report["missing_backends"] = []
    assert "not installed" not in format_report(report)
