"""``examples/friction_demand.py``: the feet's contact forces, by the slope under them."""

from __future__ import annotations

import importlib.util
import pathlib

import numpy as np
import pytest

from amlip_qp import load_robot

ROOT = pathlib.Path(__file__).resolve().parents[1]


def _module():
    spec = importlib.util.spec_from_file_location("friction_demand", ROOT / "examples" / "friction_demand.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_feet_carry_the_robots_weight_on_flat_ground():
    """Rabbit walking 1.5 s on flat ground: every foot contact is on level ground (slope under 1°), the
    normal forces summed per tick average the robot's weight within 5 %, and the table's one row says so."""
    module = _module()
    rows, fall_s = module.contact_rows({"scenario": "rabbit-1mps", "duration": 1.5})
    assert fall_s is None and rows.shape[1] == 4 and len(rows) > 1000
    assert rows[:, 1].max() < 1.0
    ticks, index = np.unique(rows[:, 0], return_inverse=True)
    per_tick_N = np.bincount(index, weights=rows[:, 2])
    weight_N = load_robot("rabbit").mass_kg * 9.81
    # the contacts of the ticks with a foot on the ground, averaged over every tick of the walk
    mean_N = per_tick_N.sum() / round(1.5 / 0.0005)
    assert abs(mean_N - weight_N) < 0.05 * weight_N, (mean_N, weight_N)
    lines = module.table_rows(1.0, rows, fall_s)
    assert len(lines) == 1 and lines[0].startswith("| 1 (walked) | 0–5° |")


def test_the_table_counts_a_contact_at_the_friction_limit_as_sliding():
    module = _module()
    rows = np.array(
        [[0.1, 38.0, 100.0, 100.0], [0.2, 38.0, 100.0, 50.0], [0.3, 2.0, 100.0, 10.0], [3.9, 2.0, 100.0, 99.0]]
    )
    lines = module.table_rows(1.0, rows, 4.0)  # the last contact is within 0.2 s of the fall: left out
    assert lines == [
        "| 1 (fell at 4.00 s) | 0–5° | 1 | 0.10 | 0.10 | 0% |",
        "| 1 (fell at 4.00 s) | 36–42° | 2 | 0.75 | 0.95 | 50% |",
    ]


@pytest.mark.parametrize("argv", [["--friction", "0"], ["--friction", "x"], ["--walk", "novalue"], ["--walk", "vx=99"]])
def test_bad_options_exit_2_before_any_walk(argv):
    with pytest.raises(SystemExit) as info:
        _module().main(argv)
    assert info.value.code == 2
