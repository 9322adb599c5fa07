"""The comparison's rows and table: one row per (robot, tracker, planner) of :mod:`~amlip_qp.experiments.compare`.

A row gathers what the experiments of one (robot, tracker, planner) measured
(:func:`make_row`); :func:`format_table` prints the rows as a fixed-width
table whose tracker column reads ``tracker / planner`` (e.g. ``qp / mpc``).
The planners are the walking controller's foot-placement planners
(:data:`~amlip_qp.control.walking.planners.PLANNERS`): the one-step law and
the step-timing MPC (docs/ALIP_MPC.md).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from amlip_qp.control.walking.planners import PLANNERS
from amlip_qp.exceptions import InputError
from amlip_qp.sim.reports.plots import AT_UPPER_BOUND, series_label

#: The planners a comparison runs unless told otherwise: the one-step law only (the MPC doubles the
#: time of every experiment it is added to; ``--planners one-step,mpc`` adds it, docs/COMMANDS.md).
DEFAULT_PLANNERS: tuple[str, ...] = ("one-step",)


def check_planners(planners: Sequence[str]) -> list[str]:
    """The planners of a comparison, in order and without repeats.

    Raises:
        InputError: No planner, or one that is not in :data:`~amlip_qp.control.walking.planners.PLANNERS`.
    """
    names = list(dict.fromkeys(planners))
    bad = [p for p in names if p not in PLANNERS]
    if not names or bad:
        raise InputError(f"planners must be a non-empty list from {', '.join(PLANNERS)}, got {list(planners)}")
    return names


def make_row(robot: str, tracker: str, planner: str, parts: list[dict[str, Any]]) -> dict[str, Any]:
    """The row of one (robot, tracker, planner): the fields its experiments returned, the nominal walk's
    :mod:`~amlip_qp.sim.reports.summary` metrics flattened."""
    row: dict[str, Any] = {"robot": robot, "tracker": tracker, "planner": planner}
    for p in parts:
        row.update({k: v for k, v in p.items() if k not in ("nominal", "_wall_s", "_cpu_s")})
        if "nominal" in p:
            n = p["nominal"]
            track = [v for v in n["output_tracking_rms"].values() if v is not None and math.isfinite(v)]
            row.update(
                scenario=n["scenario"],
                fell=n["fell"],
                steps=n["steps"],
                velocity_error_rms=n["velocity_error_rms"],
                foot_placement_error_rms_m=n["foot_placement_error_rms_m"],
                L_end_of_step_error_rms=n["L_end_of_step_error_rms"],
                output_tracking_rms=n["output_tracking_rms"],
                output_tracking_rms_mean=float(np.mean(track)) if track else None,
                torque_peak_Nm=n["torque_peak_Nm"],
                torque_rms_Nm=n["torque_rms_Nm"],
                torque_peak_max_Nm=max(n["torque_peak_Nm"].values()) if n["torque_peak_Nm"] else None,
                torque_rms_mean_Nm=float(np.mean(list(n["torque_rms_Nm"].values()))) if n["torque_rms_Nm"] else None,
                tick_time_median_us=n["tick_time_us"]["median"],
                tick_time_p99_us=n["tick_time_us"]["p99"],
                realtime_factor=n["realtime_factor"],
                fallback_ticks=n["fallback_ticks"],
            )
    row.setdefault("max_lateral_impulse_Ns", None)
    return row


#: (row key, column header, format) of the printed table; the tracker column is :func:`series_label`.
TABLE_COLUMNS: tuple[tuple[str, str, str], ...] = (
    ("robot", "robot", "s"),
    ("tracker", "tracker", "s"),
    ("fell", "fell", "s"),
    ("velocity_error_rms", "v err m/s", ".3f"),
    ("foot_placement_error_rms_m", "foot err m", ".3f"),
    ("L_end_of_step_error_rms", "L err Nms", ".2f"),
    ("output_tracking_rms_mean", "track rms", ".4f"),
    ("torque_peak_max_Nm", "tau pk Nm", ".1f"),
    ("torque_rms_mean_Nm", "tau rms Nm", ".1f"),
    ("highest_steady_speed_mps", "v max m/s", ".2f"),
    ("max_sagittal_impulse_Ns", "push x Ns", ".1f"),
    ("max_lateral_impulse_Ns", "push y Ns", ".1f"),
    ("tick_time_median_us", "tick med us", ".0f"),
    ("tick_time_p99_us", "tick p99 us", ".0f"),
)


def table_cell(row: dict[str, Any], key: str, fmt: str) -> str:
    """One cell of the table: the row's value at ``key`` in ``fmt``, "-" when missing, ">=" at a search's top."""
    if key == "tracker":
        return series_label(row)
    v = row.get(key)
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return "-"
    if isinstance(v, bool):
        return "yes" if v else "no"
    text = format(v, fmt)
    if key in AT_UPPER_BOUND and row.get(AT_UPPER_BOUND[key]):
        text = ">=" + text
    return text


def format_table(rows: list[dict[str, Any]]) -> str:
    """A fixed-width text table, one line per row (robot, ``tracker / planner``)."""
    header = [h for _, h, _ in TABLE_COLUMNS]
    body = [[table_cell(r, k, f) for k, _, f in TABLE_COLUMNS] for r in rows]
    widths = [max(len(c) for c in col) for col in zip(header, *body)]
    lines = [
        "  ".join(c.rjust(w) if i > 1 else c.ljust(w) for i, (c, w) in enumerate(zip(line, widths)))
        for line in [header, *body]
    ]
    lines.insert(1, "-" * len(lines[0]))
    return "\n".join(lines)
