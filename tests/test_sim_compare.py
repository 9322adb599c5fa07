"""The comparison's table (the runs themselves are tested through the CLI in test_sim_cli.py)."""

from __future__ import annotations

import re
import warnings

import pytest

from amlip_qp.experiments.compare import format_table


def test_table_formats_rows():
    rows = [
        {
            "robot": "cassie",
            "tracker": "pbc",
            "fell": False,
            "velocity_error_rms": 0.1234,
            "max_sagittal_impulse_Ns": 60.0,
            "sagittal_impulse_at_upper_bound": True,
            "max_lateral_impulse_Ns": None,
        },
    ]
    table = format_table(rows).splitlines()
    assert len(table) == 3 and "0.123" in table[2] and ">=60.0" in table[2] and table[2].count(" - ") >= 1


def test_compare_table_marks_values_at_the_top_of_the_search():
    row = {
        "robot": "cassie",
        "tracker": "qp",
        "fell": False,
        "highest_steady_speed_mps": 2.1,
        "speed_at_upper_bound": True,
    }
    row.update(max_sagittal_impulse_Ns=60.0, sagittal_impulse_at_upper_bound=True, max_lateral_impulse_Ns=22.5)
    cells = format_table([row]).splitlines()[2].split()
    assert cells[cells.index("no") + 7 :][:3] == [">=2.10", ">=60.0", "22.5"]


def test_generated_code_is_prepared_once_per_robot_and_tracker(monkeypatch):
    from amlip_qp.experiments import compare
    from amlip_qp.experiments.robustness import CompareSettings
    from amlip_qp.sim.scenarios import factory

    built = []

    def build(scenario, tracker, planner):
        built.append((scenario.robot, tracker, planner))

    monkeypatch.setattr(factory, "build_simulation", build)
    tasks = compare.build_tasks(["rabbit", "cassie"], ["pbc", "qp"], [], CompareSettings(), seed=0, noise=False)
    assert len(tasks) > 4  # nominal, ramp and push runs per pair
    compare.prepare_generated_code(tasks)
    assert sorted(built) == [(r, t, "one-step") for r in ("cassie", "rabbit") for t in ("pbc", "qp")]
    built.clear()
    both = compare.build_tasks(["rabbit"], ["qp"], [], CompareSettings(), ramp=False, planners=["one-step", "mpc"])
    compare.prepare_generated_code(both)
    assert built == [("rabbit", "qp", "one-step"), ("rabbit", "qp", "mpc")]  # the MPC's kernels too


def test_every_experiment_runs_once_per_planner_and_one_step_tasks_are_unchanged():
    from amlip_qp.exceptions import UnverifiedCommandWarning
    from amlip_qp.experiments import compare
    from amlip_qp.experiments.robustness import CompareSettings

    robots, trackers, settings = ["cassie", "rabbit"], ["pbc", "qp"], CompareSettings()
    with warnings.catch_warnings():
        warnings.simplefilter("error", UnverifiedCommandWarning)  # both ramps end inside the verified envelope
        one = compare.build_tasks(robots, trackers, [], settings)
        both = compare.build_tasks(robots, trackers, [], settings, planners=["one-step", "mpc"])
    assert len(both) == 2 * len(one) == 2 * (2 * 4 + 2 * 3)  # nominal, ramp, push x (and y on Cassie)
    assert [t for t in both if t.planner == "one-step"] == one
    assert [t.kind for t in both if t.planner == "mpc"] == [t.kind for t in one]
    firsts = [(t.robot, t.tracker, t.planner) for t in both[:8:4]]
    assert firsts == [("cassie", "pbc", "one-step"), ("cassie", "pbc", "mpc")]  # each tracker's planners in turn


def test_an_unknown_planner_is_refused_before_anything_runs():
    from amlip_qp.exceptions import InputError
    from amlip_qp.experiments import compare
    from amlip_qp.experiments.compare_table import check_planners
    from amlip_qp.experiments.robustness import CompareSettings

    assert check_planners(["mpc", "one-step", "mpc"]) == ["mpc", "one-step"]
    for bad in ([], ["one-step", "two-step"]):
        with pytest.raises(InputError, match="planners must be a non-empty list from one-step, mpc"):
            compare.build_tasks(["cassie"], ["qp"], [], CompareSettings(), planners=bad)


def test_table_and_figure_give_each_tracker_per_planner():
    from amlip_qp.sim.reports.plots import draw_comparison

    rows = [
        {"robot": "cassie", "tracker": trk, "planner": pl, "fell": False, "max_sagittal_impulse_Ns": x}
        for trk, pl, x in (("qp", "one-step", 30.0), ("qp", "mpc", 45.0))
    ]
    lines = format_table(rows).splitlines()
    assert len(lines) == 4
    cells = [re.split(r"\s{2,}", line) for line in lines[2:]]
    assert [c[:3] for c in cells] == [["cassie", "qp / one-step", "no"], ["cassie", "qp / mpc", "no"]]
    push_x = re.split(r"\s{2,}", lines[0]).index("push x Ns")
    assert (cells[0][push_x], cells[1][push_x]) == ("30.0", "45.0")
    fig = draw_comparison(rows)
    legend = fig.axes[0].get_legend()
    assert [t.get_text() for t in legend.get_texts()] == ["qp / one-step", "qp / mpc"]
    push = next(ax for ax in fig.axes if ax.get_title().startswith("largest sagittal push"))
    assert [p.get_height() for p in push.patches] == [30.0, 45.0]


def test_a_tracker_a_profile_says_cannot_run_is_skipped_with_its_reason(tmp_path):
    from amlip_qp.experiments.compare import unsupported_pairs
    from amlip_qp.paths import MODELS_DIR

    text = (MODELS_DIR / "h1.toml").read_text()
    text = text.replace('file = "unitree_h1/h1.xml"', f'file = "{MODELS_DIR / "unitree_h1" / "h1.xml"}"')
    no_pbc = tmp_path / "no_pbc.toml"
    no_pbc.write_text(text + '\n[unsupported]\npbc = "no PBC here"\n')
    assert unsupported_pairs(["cassie", str(no_pbc)], ["pbc", "qp"]) == [(str(no_pbc), "pbc", "no PBC here")]
    assert unsupported_pairs(["cassie", "g1", "h1", "rabbit"], ["pbc", "qp"]) == []
