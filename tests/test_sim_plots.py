"""The comparison figure marks values at the top of their search range ("≥") and values not measured ("n/a")."""

from __future__ import annotations

import math

import matplotlib.pyplot as plt
import pytest

from amlip_qp.exceptions import InputError
from amlip_qp.sim import plots


def _rows():
    """A synthetic comparison table: Cassie's QP held the whole ramp and the largest push; Rabbit is planar."""
    base = {"velocity_error_rms": 0.05, "foot_placement_error_rms_m": 0.01, "tick_time_median_us": 300.0}
    return [
        {**base, "robot": "cassie", "tracker": "pbc", "highest_steady_speed_mps": 1.6, "speed_at_upper_bound": False,
         "max_sagittal_impulse_Ns": 37.5, "sagittal_impulse_at_upper_bound": False,
         "max_lateral_impulse_Ns": 15.0, "lateral_impulse_at_upper_bound": False},
        {**base, "robot": "cassie", "tracker": "qp", "highest_steady_speed_mps": 2.1, "speed_at_upper_bound": True,
         "max_sagittal_impulse_Ns": 60.0, "sagittal_impulse_at_upper_bound": True,
         "max_lateral_impulse_Ns": 22.5, "lateral_impulse_at_upper_bound": False},
        {**base, "robot": "rabbit", "tracker": "pbc", "highest_steady_speed_mps": 1.2, "speed_at_upper_bound": False,
         "max_sagittal_impulse_Ns": 40.0, "sagittal_impulse_at_upper_bound": True, "max_lateral_impulse_Ns": None},
        {**base, "robot": "rabbit", "tracker": "qp", "highest_steady_speed_mps": 1.0, "speed_at_upper_bound": False,
         "max_sagittal_impulse_Ns": 30.0, "sagittal_impulse_at_upper_bound": False, "max_lateral_impulse_Ns": None},
    ]  # fmt: skip


def _panel_texts(fig, key):
    """(text, x, y) of the labels in the panel of metric ``key``."""
    index = [k for k, _ in plots.COMPARISON_METRICS].index(key)
    ax = fig.axes[index]
    return sorted((t.get_text(), round(t.get_position()[0], 6), t.get_position()[1]) for t in ax.texts)


def test_comparison_figure_marks_capped_and_missing_values():
    fig = plots.draw_comparison(_rows())
    try:
        width = 0.8 / 2
        cassie, rabbit = 0.0, 1.0  # bar groups; pbc left of the group's centre, qp right
        # Only the capped values are labelled "≥ value", on top of their bars.
        assert _panel_texts(fig, "highest_steady_speed_mps") == [("≥ 2.1", cassie + width / 2, 2.1)]
        assert _panel_texts(fig, "max_sagittal_impulse_Ns") == [
            ("≥ 40", rabbit - width / 2, 40.0),
            ("≥ 60", cassie + width / 2, 60.0),
        ]
        # Planar Rabbit has no lateral push: both of its bars are empty and say so, just above the axis
        # (y in axes units), inside the panel.
        assert _panel_texts(fig, "max_lateral_impulse_Ns") == [
            ("n/a", rabbit - width / 2, 0.02),
            ("n/a", rabbit + width / 2, 0.02),
        ]
        for ax in fig.axes[: len(plots.COMPARISON_METRICS)]:
            assert ax.get_xlim() == (-0.5, 1.5)
        # Metrics missing from every row (not measured here) are n/a for every bar.
        assert [t[0] for t in _panel_texts(fig, "torque_rms_mean_Nm")] == ["n/a"] * 4
        # A measured, uncapped metric carries no label; the capped bar still has its height.
        assert _panel_texts(fig, "velocity_error_rms") == []
        lateral = fig.axes[[k for k, _ in plots.COMPARISON_METRICS].index("max_lateral_impulse_Ns")]
        pbc_cassie, pbc_rabbit, qp_cassie, qp_rabbit = (p.get_height() for p in lateral.patches)
        assert (pbc_cassie, qp_cassie) == (15.0, 22.5) and math.isnan(pbc_rabbit) and math.isnan(qp_rabbit)
    finally:
        plt.close(fig)


def test_comparison_figure_writes_the_file_and_checks_its_suffix(tmp_path):
    path = plots.comparison_figure(_rows(), tmp_path / "new" / "cmp.svg")
    assert path.read_text().lstrip().startswith("<?xml")
    with pytest.raises(InputError, match="must end in .png, .pdf, .svg"):
        plots.comparison_figure(_rows(), tmp_path / "cmp.jpeg")
