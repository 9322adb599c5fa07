"""Figures of a walking run and of a tracker comparison.

Matplotlib :class:`~matplotlib.figure.Figure` objects written to files, without pyplot: no display
needed, and importing this module changes no matplotlib setting (its backend stays the user's).
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.figure import Figure

from amlip_qp.exceptions import InputError
from amlip_qp.sim.loop.run_types import RunResult
from amlip_qp.sim.reports.summary import heading_frame_xy, step_velocities
from amlip_qp.sim.world.terrain import parse_terrain

#: File suffixes the figures are written as (the format follows the suffix).
FIGURE_SUFFIXES = (".png", ".pdf", ".svg")


def check_figure_path(path: str | os.PathLike) -> Path:
    """``path`` as a Path if its suffix is one of :data:`FIGURE_SUFFIXES`; :class:`InputError` otherwise."""
    p = Path(path)
    if p.suffix.lower() not in FIGURE_SUFFIXES:
        raise InputError(f"figure file must end in {', '.join(FIGURE_SUFFIXES)}, got {str(path)!r}")
    return p


def _save(fig, path: str | os.PathLike) -> Path:
    """Write ``fig`` to ``path`` (its folder created); a failed write raises :class:`OSError`."""
    p = check_figure_path(path)
    p.parent.mkdir(parents=True, exist_ok=True)
    # Our own file object: Pillow, given a file name, ignores a failing close (a full disk).
    with open(p, "wb") as fh:
        fig.savefig(fh, format=p.suffix[1:].lower(), dpi=110)
    return p


def _legend(ax, **kw) -> None:
    if ax.get_legend_handles_labels()[0]:
        ax.legend(**kw)


def _mark_fall(ax, result: RunResult) -> None:
    if result.fell:
        ax.axvline(result.fall_time_s, color="k", ls=":", lw=1.0, label="fall")


def _side_view(ax, result: RunResult, terrain_text: str) -> None:
    """Ground profile under the CoM's path, CoM height and the feet's touchdown points, against x."""
    terrain = parse_terrain(terrain_text)
    com = result.log["com"]
    if com.shape[0] == 0:
        return
    xs = np.linspace(float(com[:, 0].min()) - 0.5, float(com[:, 0].max()) + 0.5, 600)
    ys = np.interp(xs, com[:, 0], com[:, 1]) if np.all(np.diff(com[:, 0]) > 0) else np.full_like(xs, com[-1, 1])
    ground = np.array([terrain.height_m(float(x), float(y)) for x, y in zip(xs, ys)])
    ax.fill_between(xs, ground, ground.min() - 0.1, color="tan", alpha=0.6, label=f"ground ({terrain.text})")
    ax.plot(com[:, 0], com[:, 2], color="C0", lw=0.8, label="CoM")
    if result.steps:
        touch = np.array([np.asarray(s.swing_actual_m, dtype=float) for s in result.steps])
        ax.plot(touch[:, 0], touch[:, 2], "kv", ms=4, label="swing contact site at touchdown")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("height [m]")
    _legend(ax, loc="upper left", fontsize=7, ncol=3)


def walk_figure(result: RunResult, path: str | os.PathLike, title: str | None = None) -> Path:
    """Speed, ``L`` and its prediction, foot-placement error, output tracking errors against time; on a
    terrain (``result.info["terrain"]`` not flat) a fifth panel, the side view (:func:`_side_view`). Returns the path.
    """
    check_figure_path(path)
    log = result.log
    t = log["t"]
    planar = bool(result.info.get("planar", False))
    terrain = str(result.info.get("terrain", "flat"))
    if terrain == "flat":
        fig = Figure(figsize=(10, 12))
        axes = fig.subplots(4, 1, sharex=True)
    else:
        fig = Figure(figsize=(10, 15))
        axes = fig.subplots(5, 1)
        for ax in axes[1:4]:
            ax.sharex(axes[0])
        _side_view(axes[4], result, terrain)
    fig.suptitle(title or f"{result.robot} / {result.tracker}" + (" (fell)" if result.fell else ""))

    ax = axes[0]
    v_h = heading_frame_xy(log["com_vel"], log["heading"])
    ax.plot(t, v_h[:, 0], color="C0", lw=0.6, alpha=0.5, label="$v_x$ CoM (heading frame)")
    ax.plot(t, log["cmd_vx"], color="C0", ls="--", label="$v_x$ command")
    t0, vm, _ = step_velocities(result)
    if t0.size:
        ends = np.array([s.t_end_s for s in result.steps][: t0.size])
        ax.step(ends, vm[:, 0], where="pre", color="C3", label="$v_x$ step mean")
    if not planar:
        ax.plot(t, v_h[:, 1], color="C1", lw=0.6, alpha=0.5, label="$v_y$ CoM")
        ax.plot(t, log["cmd_vy"], color="C1", ls="--", label="$v_y$ command")
    ax.set_ylabel("speed [m/s]")
    _mark_fall(ax, result)
    _legend(ax, loc="upper left", fontsize=7, ncol=3)

    ax = axes[1]
    ax.plot(t, log["L"][:, 1], color="C0", lw=0.8, label="$L_y$ (filtered)")
    ax.plot(t, log["L_hat"][:, 1], color="C3", lw=0.8, label=r"$\hat L_y(T^-)$ predicted")
    ax.plot(t, log["L_des"][:, 1], color="C2", ls="--", lw=0.8, label=r"$L_y^{des}$ (next step end)")
    end_times_s = [s.t_end_s for s in result.steps]
    if end_times_s:
        ax.plot(end_times_s, [s.L_end_Nms[1] for s in result.steps], "k.", ms=4, label="$L_y$ at step end")
    if not planar:
        ax.plot(t, log["L"][:, 0], color="C1", lw=0.6, alpha=0.7, label="$L_x$ (filtered)")
        ax.plot(t, log["L_hat"][:, 0], color="C4", lw=0.6, alpha=0.7, label=r"$\hat L_x(T^-)$")
    ax.set_ylabel("L about stance contact [kg m²/s]")
    _mark_fall(ax, result)
    _legend(ax, loc="upper left", fontsize=7, ncol=3)

    ax = axes[2]
    if result.steps:
        err = np.array([np.asarray(s.swing_actual_m)[:2] - np.asarray(s.swing_target_m)[:2] for s in result.steps])
        ax.plot(ends, err[:, 0], "o-", ms=3, label="x (actual - target)")
        if not planar:
            ax.plot(ends, err[:, 1], "s-", ms=3, label="y (actual - target)")
    ax.axhline(0.0, color="k", lw=0.5)
    ax.set_ylabel("foot placement error\nat touchdown [m]")
    _mark_fall(ax, result)
    _legend(ax, loc="upper left", fontsize=7)

    ax = axes[3]
    names = result.info.get("output_names") or [f"h{i}" for i in range(log["h"].shape[1])]
    err = log["h"] - log["h_d"]
    for i, name in enumerate(names):
        ax.plot(t, err[:, i], lw=0.6, label=name)
    ax.set_ylabel("output error $h - h_d$\n[m or rad]")
    ax.set_xlabel("time [s]")
    _mark_fall(ax, result)
    _legend(ax, loc="upper left", fontsize=6, ncol=3)
    fig.tight_layout()
    return _save(fig, path)


#: (key in a comparison row, axis label) of the comparison figure's panels.
COMPARISON_METRICS: tuple[tuple[str, str], ...] = (
    ("velocity_error_rms", "velocity error RMS [m/s]"),
    ("foot_placement_error_rms_m", "foot placement error RMS [m]"),
    ("L_end_of_step_error_rms", "L end-of-step error RMS [kg m²/s]"),
    ("output_tracking_rms_mean", "mean output tracking RMS [m|rad]"),
    ("torque_rms_mean_Nm", "mean torque RMS [N m]"),
    ("highest_steady_speed_mps", "highest steady speed [m/s]"),
    ("max_sagittal_impulse_Ns", "largest sagittal push survived [N s]"),
    ("max_lateral_impulse_Ns", "largest lateral push survived [N s]"),
    ("tick_time_median_us", "tick time median [µs]"),
)

#: Row key of a searched value -> row key of the flag that says it reached the top of the search
#: range (the robot did at least that: ">=" in the table and the figure).
AT_UPPER_BOUND: dict[str, str] = {
    "highest_steady_speed_mps": "speed_at_upper_bound",
    "max_sagittal_impulse_Ns": "sagittal_impulse_at_upper_bound",
    "max_lateral_impulse_Ns": "lateral_impulse_at_upper_bound",
}


def series_label(row: dict[str, Any]) -> str:
    """The tracker of a comparison row and, when the row names one, its planner: ``"qp / mpc"``."""
    return f"{row['tracker']} / {row['planner']}" if row.get("planner") else str(row["tracker"])


def comparison_figure(rows: Sequence[dict[str, Any]], path: str | os.PathLike) -> Path:
    """Write :func:`draw_comparison` of ``rows`` to ``path`` (PNG); returns the path."""
    check_figure_path(path)
    return _save(draw_comparison(rows), path)


def draw_comparison(rows: Sequence[dict[str, Any]]) -> Figure:
    """Bar charts of the comparison metrics, grouped by robot, one bar per tracker and planner.

    ``rows`` are the per-(robot, tracker, planner) dictionaries of :mod:`amlip_qp.experiments.compare`
    (a bar's legend entry is :func:`series_label`, ``"qp / mpc"``).
    A value that reached the top of its search range (its flag in
    :data:`AT_UPPER_BOUND` is true) is labelled
    "≥ value" above its bar; a missing, ``None`` or non-finite value (the
    lateral push of a planar robot, an experiment left out) is an empty bar
    labelled "n/a".
    """
    robots = list(dict.fromkeys(r["robot"] for r in rows))
    trackers = list(dict.fromkeys(series_label(r) for r in rows))
    ncol = 3
    nrow = int(np.ceil(len(COMPARISON_METRICS) / ncol))
    fig = Figure(figsize=(4.2 * ncol, 3.2 * nrow))
    axes = fig.subplots(nrow, ncol)
    width = 0.8 / max(len(trackers), 1)
    x = np.arange(len(robots))
    for ax, (key, label) in zip(axes.flat, COMPARISON_METRICS):
        for j, trk in enumerate(trackers):
            xs = x + (j - (len(trackers) - 1) / 2) * width
            vals, capped = [], []
            for rob in robots:
                row = next((r for r in rows if r["robot"] == rob and series_label(r) == trk), None)
                v = None if row is None else row.get(key)
                vals.append(np.nan if v is None else float(v))
                capped.append(row is not None and key in AT_UPPER_BOUND and bool(row.get(AT_UPPER_BOUND[key])))
            ax.bar(xs, vals, width, label=trk, color=f"C{j}")
            for xi, v, cap in zip(xs, vals, capped):
                if not np.isfinite(v):  # x in data, y in axes units: just above the axis, whatever the scale
                    na_at = ax.get_xaxis_transform()
                    ax.text(xi, 0.02, "n/a", ha="center", va="bottom", fontsize=8, color="0.35", transform=na_at)
                elif cap:
                    ax.text(xi, v, f"≥ {v:.3g}", ha="center", va="bottom", fontsize=8)
        ax.set_xticks(x, robots)
        ax.set_xlim(-0.5, len(robots) - 0.5)
        ax.set_title(label, fontsize=9)
        if all(not np.isfinite(p.get_height()) for p in ax.patches):
            ax.set_yticks([])  # nothing measured: no scale
        else:
            ax.margins(y=0.15)  # room for the labels above the bars
    for ax in list(axes.flat)[len(COMPARISON_METRICS) :]:
        ax.axis("off")
    axes.flat[0].legend(fontsize=8)
    fig.suptitle("Trackers and planners (≥: the top of the search range was reached)")
    fig.tight_layout()
    return fig
