"""The comparison figure marks values at the top of their search range ("≥") and values not measured ("n/a")."""

from __future__ import annotations

import math

import matplotlib.pyplot as plt
import numpy as np
import pytest

from amlip_qp.exceptions import InputError
from amlip_qp.sim.reports import plots


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


def _walk_result(terrain: str):
    """A synthetic 2 s walk up the first metres of ``terrain``: the CoM 0.85 m above the ground, 4 steps."""
    from amlip_qp.control.walking.controller import StepRecord
    from amlip_qp.sim.loop.run_types import RunResult
    from amlip_qp.sim.world.terrain import parse_terrain

    ground = parse_terrain(terrain)
    t = np.linspace(0.0, 2.0, 401)
    x = 0.5 * t
    com = np.stack([x, np.zeros_like(x), 0.85 + np.array([ground.height_m(xi, 0.0) for xi in x])], axis=1)
    n = t.size
    steps = [
        StepRecord(
            t_start_s=0.5 * k,
            t_end_s=0.5 * (k + 1),
            stance="left" if k % 2 else "right",
            swing_target_m=np.array([0.25 * (k + 1), 0.0, 0.0]),
            swing_actual_m=np.array([0.25 * (k + 1), 0.0, ground.height_m(0.25 * (k + 1), 0.0)]),
            L_end_Nms=np.zeros(3),
            L_target_Nms=np.zeros(3),
            com_vel_end_mps=np.array([0.5, 0.0, 0.0]),
            heading_rad=0.0,
        )
        for k in range(4)
    ]
    log = {
        "t": t, "com": com, "com_vel": np.tile([0.5, 0.0, 0.0], (n, 1)), "heading": np.zeros(n),
        "cmd_vx": np.full(n, 0.5), "cmd_vy": np.zeros(n), "L": np.zeros((n, 3)), "L_hat": np.zeros((n, 2)),
        "L_des": np.zeros((n, 2)), "h": np.zeros((n, 2)), "h_d": np.zeros((n, 2)),
    }  # fmt: skip
    info = {"output_names": ("a", "b"), "terrain": terrain}
    return RunResult("cassie", "qp", 2.0, 2.0, 1.0, False, float("nan"), log, steps, np.zeros(n), 0, info=info)


def test_walk_figure_adds_a_side_view_on_a_terrain(tmp_path):
    import imageio.v3 as iio

    flat = iio.imread(plots.walk_figure(_walk_result("flat"), tmp_path / "flat.png"))
    slope = iio.imread(plots.walk_figure(_walk_result("slope:10"), tmp_path / "slope.png"))
    assert flat.shape[0] == 12 * 110 and slope.shape[0] == 15 * 110  # a fifth panel, 3 inches high
    # the side view is drawn: the bottom fifth of the slope figure holds the ground's tan fill
    bottom = slope[-3 * 110 :, :, :3].reshape(-1, 3).astype(int)
    tan = np.array([210, 180, 140])
    assert np.any(np.all(np.abs(bottom - (0.4 * 255 + 0.6 * tan)) < 12, axis=1))
