"""The comparison's table (the runs themselves are tested through the CLI in test_sim_cli.py)."""

from __future__ import annotations

from amlip_qp.sim.compare import format_table


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
