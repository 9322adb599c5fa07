"""Figures of a finished grid sweep (matplotlib, written next to ``results.csv``).

The plotted value is the bisection's ``max_<parameter>`` or the first metric.
``tracker``, when swept, gives one panel (or line) per tracker; the other
swept parameters are the axes: ``push_direction_deg`` x ``push_phase`` -> a
polar heat map (direction as the angle from +x, forward, drawn upwards;
phase as the radius), any other two -> a heat map, one -> a line. Other
sweeps (random sampling, three or more axes) get no figure.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from amlip_qp.sweep.results import write_atomic

#: The swept parameter that splits a figure into panels.
FACET = "tracker"
POLAR = ("push_direction_deg", "push_phase")


def _edges(centres: Sequence[float] | np.ndarray, default_half: float) -> np.ndarray:
    """Cell edges around sorted ``centres`` (midpoints; the ends mirrored)."""
    c = np.asarray(centres, dtype=float)
    if c.size == 1:
        return np.array([c[0] - default_half, c[0] + default_half])
    mid = 0.5 * (c[1:] + c[:-1])
    return np.concatenate([[c[0] - (mid[0] - c[0])], mid, [c[-1] + (c[-1] - mid[-1])]])


def _number(v: Any) -> float:
    return float(v) if isinstance(v, (int, float)) else math.nan


def grid_values(records: Sequence[dict], x: str, y: str, value: str, where: dict) -> tuple[list, list, np.ndarray]:
    """``(x values, y values, Z[y, x])`` of ``value`` over the records matching ``where`` (NaN where missing)."""
    rows = [r for r in records if all(r["params"].get(k) == v for k, v in where.items())]
    xs = list(dict.fromkeys(r["params"][x] for r in rows))
    ys = list(dict.fromkeys(r["params"][y] for r in rows))
    z = np.full((len(ys), len(xs)), np.nan)
    for r in rows:
        z[ys.index(r["params"][y]), xs.index(r["params"][x])] = _number(r["metrics"].get(value))
    return xs, ys, z


def polar_map(ax, directions_deg: Sequence[float], phases: Sequence[float], z: np.ndarray, **kwargs):
    """Draw ``z[phase, direction]`` on polar axes ``ax`` (0 deg = forward, up; 90 deg = left); the mesh."""
    order = np.argsort(directions_deg)
    d = np.asarray(directions_deg, dtype=float)[order]
    step = float(np.min(np.diff(d))) if d.size > 1 else 360.0
    theta = np.radians(_edges(d, 0.5 * step))
    p_order = np.argsort(phases)
    r = _edges(np.asarray(phases, dtype=float)[p_order], 0.1)
    ax.set_theta_zero_location("N")
    mesh = ax.pcolormesh(theta, r, z[np.ix_(p_order, order)], shading="flat", **kwargs)
    ax.set_ylim(r[0], r[-1])  # the centre is the first phase's inner edge
    ax.set_xticks(np.radians(d))
    ax.set_xticklabels([f"{v:g}°" for v in d], fontsize=7)
    ax.set_yticks(np.asarray(phases, dtype=float)[p_order])
    ax.set_yticklabels([f"{v:g}" for v in np.asarray(phases)[p_order]], fontsize=6)
    return mesh


def _save(fig, path: Path) -> str:
    import io

    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=120, bbox_inches="tight")
    write_atomic(path, buf.getvalue())
    return str(path)


def sweep_figures(folder: Path, spec, records: Sequence[dict], metrics: Sequence[str]) -> list[str]:
    """Draw the figures of a grid sweep into ``folder``; their paths (none for other sweeps)."""
    if spec.sampling != "grid":
        return []
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    value = metrics[0]
    facets = list(spec.parameters.get(FACET, [None])) if isinstance(spec.parameters.get(FACET), list) else [None]
    axes = [p for p in spec.parameters if p != FACET]
    where = [{FACET: f} if f is not None else {} for f in facets]
    label = [f"{FACET} {f}" if f is not None else "" for f in facets]
    if len(axes) == 2:
        polar = tuple(sorted(axes)) == tuple(sorted(POLAR))
        fig = plt.figure(figsize=(4.2 * len(facets), 4.0))
        for i, (w, lab) in enumerate(zip(where, label)):
            if polar:
                ax = fig.add_subplot(1, len(facets), i + 1, projection="polar")
                ds, ps, z = grid_values(records, POLAR[0], POLAR[1], value, w)
                mesh = polar_map(ax, [_number(d) for d in ds], [_number(p) for p in ps], z, cmap="viridis")
            else:
                ax = fig.add_subplot(1, len(facets), i + 1)
                xs, ys, z = grid_values(records, axes[1], axes[0], value, w)
                mesh = ax.pcolormesh(np.arange(len(xs) + 1), np.arange(len(ys) + 1), z, cmap="viridis")
                ax.set_xticks(np.arange(len(xs)) + 0.5, [str(x) for x in xs], rotation=45, fontsize=7)
                ax.set_yticks(np.arange(len(ys)) + 0.5, [str(y) for y in ys], fontsize=7)
                ax.set_xlabel(axes[1])
                ax.set_ylabel(axes[0])
            ax.set_title(lab, fontsize=9)
            fig.colorbar(mesh, ax=ax, shrink=0.75, label=value)
        name = "map_polar.png" if polar else "map_heat.png"
    elif len(axes) == 1:
        fig, ax = plt.subplots(figsize=(5.0, 3.5))
        for w, lab in zip(where, label):
            rows = [r for r in records if all(r["params"].get(k) == v for k, v in w.items())]
            xs = [r["params"][axes[0]] for r in rows]
            ys = [_number(r["metrics"].get(value)) for r in rows]
            numeric = all(isinstance(x, (int, float)) for x in xs)
            ax.plot(xs if numeric else [str(x) for x in xs], ys, marker="o", label=lab or None)
        ax.set_xlabel(axes[0])
        ax.set_ylabel(value)
        if any(label):
            ax.legend()
        name = "map_line.png"
    else:
        return []
    fig.tight_layout()
    path = _save(fig, folder / name)
    plt.close(fig)
    return [path]
