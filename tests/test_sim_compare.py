"""The comparison's table (the runs themselves are tested through the CLI in test_sim_cli.py)."""

from __future__ import annotations

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
    monkeypatch.setattr(factory, "build_simulation", lambda scenario, tracker: built.append((scenario.robot, tracker)))
    tasks = compare.build_tasks(["rabbit", "cassie"], ["pbc", "qp"], [], CompareSettings(), seed=0, noise=False)
    assert len(tasks) > 4  # nominal, ramp and push runs per pair
    compare.prepare_generated_code(tasks)
    assert sorted(built) == [("cassie", "pbc"), ("cassie", "qp"), ("rabbit", "pbc"), ("rabbit", "qp")]


def test_a_tracker_a_profile_says_cannot_run_is_skipped_with_its_reason(tmp_path):
    from amlip_qp.experiments.compare import unsupported_pairs
    from amlip_qp.paths import MODELS_DIR

    text = (MODELS_DIR / "h1.toml").read_text()
    text = text.replace('file = "unitree_h1/h1.xml"', f'file = "{MODELS_DIR / "unitree_h1" / "h1.xml"}"')
    no_pbc = tmp_path / "no_pbc.toml"
    no_pbc.write_text(text + '\n[unsupported]\npbc = "no PBC here"\n')
    assert unsupported_pairs(["cassie", str(no_pbc)], ["pbc", "qp"]) == [(str(no_pbc), "pbc", "no PBC here")]
    assert unsupported_pairs(["cassie", "g1", "h1", "rabbit"], ["pbc", "qp"]) == []
