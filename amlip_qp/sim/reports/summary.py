"""The JSON summary of a walking run; every number is measured from the run.

The schema (field names, units, exact definitions) is documented in
``docs/SUMMARY_SCHEMA.md``; :func:`summarize` is its one implementation.
Undefined values (no completed step after the settling time, ...) are
``None`` in the JSON (NaN inside Python before :func:`to_jsonable`).
"""

from __future__ import annotations

import json
import math
from typing import Any

import numpy as np

from amlip_qp.alip.formulas import world_to_heading_xy
from amlip_qp.exceptions import InputError
from amlip_qp.sim.loop.run_types import RunResult

#: Steps that start before this time (s) are excluded from ``velocity_error_rms``.
DEFAULT_SETTLE_S = 2.0
#: Window (s) at the end of the run over which ``mean_velocity`` is averaged.
DEFAULT_MEAN_WINDOW_S = 3.0

#: The summary's wall-clock fields: they vary with the machine and its load, not with the run.
TIMING_FIELDS: tuple[str, ...] = (
    "tick_time_us", "realtime_factor", "controller_us_per_tick", "mujoco_us_per_tick", "harness_us_per_tick",
)  # fmt: skip


def heading_frame_xy(vec_world: np.ndarray, heading_rad: np.ndarray | float) -> np.ndarray:
    """Rotate the x, y components of world vectors into the heading frame (yaw ``heading_rad``).

    Args:
        vec_world: (..., >=2) world vectors (only x, y are used).
        heading_rad: Heading(s), rad, broadcastable to ``vec_world[..., 0]``.

    Returns:
        (..., 2) the components along ``x_D`` and ``y_D``.
    """
    v = np.asarray(vec_world, dtype=float)
    return np.stack(world_to_heading_xy(v[..., 0], v[..., 1], np.cos(heading_rad), np.sin(heading_rad)), axis=-1)


def _median(values) -> float | None:
    a = np.asarray(values, dtype=float)
    return float(np.median(a)) if a.size else None


def _rms(values) -> float:
    a = np.asarray(values, dtype=float)
    return float(np.sqrt(np.mean(a**2))) if a.size else float("nan")


def mean_velocity_heading(result: RunResult, window_s: float = DEFAULT_MEAN_WINDOW_S) -> np.ndarray:
    """Mean CoM velocity ``[vx, vy]`` (m/s, heading frame of each tick) over the last ``window_s`` seconds.

    The whole run is used when it is shorter than the window.
    """
    t = result.log["t"]
    if t.size == 0:
        return np.full(2, np.nan)
    sel = t >= t[-1] - window_s
    return heading_frame_xy(result.log["com_vel"][sel], result.log["heading"][sel]).mean(axis=0)


def step_velocities(result: RunResult) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per completed step: start times (s), measured and commanded mean velocities (m/s).

    The measured mean velocity of step ``k`` is the CoM displacement over the
    step divided by its duration, ``(c(t_end) - c(t_start)) / (t_end - t_start)``,
    rotated into the step's heading frame ``D_k``; the commanded one is the
    mean of the commanded ``(vx, vy)`` over the ticks of the step. Returns
    ``(t_start (n,), v_meas (n, 2), v_cmd (n, 2))``.
    """
    log = result.log
    t = log["t"]
    rows_t, rows_meas, rows_cmd = [], [], []
    for st in result.steps:
        dur = st.t_end_s - st.t_start_s
        if dur <= 0 or t.size == 0 or st.t_end_s > t[-1] + 1e-12:
            continue
        c0 = np.array([np.interp(st.t_start_s, t, log["com"][:, i]) for i in range(2)])
        c1 = np.array([np.interp(st.t_end_s, t, log["com"][:, i]) for i in range(2)])
        sel = (t >= st.t_start_s - 1e-12) & (t < st.t_end_s - 1e-12)
        if not np.any(sel):
            continue
        rows_t.append(st.t_start_s)
        rows_meas.append(heading_frame_xy((c1 - c0) / dur, st.heading_rad))
        rows_cmd.append([float(np.mean(log["cmd_vx"][sel])), float(np.mean(log["cmd_vy"][sel]))])
    return (
        np.asarray(rows_t, dtype=float),
        np.asarray(rows_meas, dtype=float).reshape(-1, 2),
        np.asarray(rows_cmd, dtype=float).reshape(-1, 2),
    )


def velocity_error_rms(result: RunResult, settle_s: float = DEFAULT_SETTLE_S) -> float:
    """RMS over the steps starting at or after ``settle_s`` of ``|v_meas - v_cmd|`` (m/s).

    See :func:`step_velocities`.
    """
    t0, vm, vc = step_velocities(result)
    keep = t0 >= settle_s
    return _rms(np.linalg.norm(vm[keep] - vc[keep], axis=1))


def foot_placement_errors(result: RunResult) -> np.ndarray:
    """Per step, the horizontal distance (m) between the swing contact at touchdown and the planner's target."""
    return np.array(
        [
            float(np.linalg.norm(np.asarray(s.swing_actual_m)[:2] - np.asarray(s.swing_target_m)[:2]))
            for s in result.steps
        ]
    )


def L_end_errors(result: RunResult) -> np.ndarray:
    """Per step with a target, ``L_end - L_target`` ((n, 2): x, y; kg m^2/s). The first step has no target."""
    rows = [
        np.asarray(s.L_end_Nms, dtype=float)[:2] - np.asarray(s.L_target_Nms, dtype=float)[:2]
        for s in result.steps
        if np.all(np.isfinite(s.L_target_Nms))
    ]
    return np.asarray(rows, dtype=float).reshape(-1, 2)


def base_estimate_errors(result: RunResult) -> tuple[float, float]:
    """``(base velocity error RMS m/s, final yaw error deg)`` of the controller's base state against the truth.

    The velocity error is ``|base_vel_est - base_vel_true|`` (world, m/s) over
    every tick; the yaw error is ``|yaw_est - yaw_true|`` (unwrapped) at the
    last tick, the drift of an estimator that cannot observe yaw. NaN without
    the logs (a planar robot) or with a non-finite estimate at the end.
    """
    log = result.log
    if "base_vel_est" not in log or log["t"].size == 0:
        return float("nan"), float("nan")
    dv = log["base_vel_est"] - log["base_vel_true"]
    yaw = np.unwrap(log["base_yaw_est"]) - np.unwrap(log["base_yaw_true"])
    return _rms(np.linalg.norm(dv, axis=1)), abs(math.degrees(float(yaw[-1])))


def summarize(
    result: RunResult,
    settle_s: float = DEFAULT_SETTLE_S,
    mean_window_s: float = DEFAULT_MEAN_WINDOW_S,
) -> dict[str, Any]:
    """The summary dictionary of ``result`` (schema: ``docs/SUMMARY_SCHEMA.md``).

    Args:
        result: A finished run.
        settle_s: Steps starting earlier are left out of ``velocity_error_rms``, s.
        mean_window_s: Averaging window of ``mean_velocity`` at the end of the run, s.
    """
    if not (math.isfinite(settle_s) and settle_s >= 0 and math.isfinite(mean_window_s) and mean_window_s > 0):
        raise InputError(f"settle_s must be >= 0 s and mean_window_s > 0 s, got {settle_s!r}, {mean_window_s!r}")
    log = result.log
    n = log["t"].size
    out_names = list(result.info.get("output_names") or [f"h{i}" for i in range(log["h"].shape[1])])
    act_names = list(result.info.get("actuator_names") or [f"u{i}" for i in range(log["tau"].shape[1])])
    h_err = log["h"] - log["h_d"]
    tau = log["tau"]
    L_err = L_end_errors(result)
    yaw = np.unwrap(log["base_yaw"]) if n else np.zeros(1)
    tick = np.asarray(result.tick_time_us, dtype=float)
    base_vel_err, yaw_err = base_estimate_errors(result)
    return {
        "robot": result.robot,
        "tracker": result.tracker,
        "scenario": result.info.get("scenario"),
        "seed": result.info.get("seed"),
        "noise": result.info.get("noise"),
        "duration_s": result.duration_s,
        "sim_time_s": result.sim_time_s,
        "fell": bool(result.fell),
        "fall_time_s": result.fall_time_s if result.fell else None,
        "steps": len(result.steps),
        "commanded_velocity": [float(log["cmd_vx"][-1]), float(log["cmd_vy"][-1])] if n else [None, None],
        "mean_velocity": mean_velocity_heading(result, mean_window_s).tolist(),
        "velocity_error_rms": velocity_error_rms(result, settle_s),
        "heading_change_deg": math.degrees(float(yaw[-1] - yaw[0])),
        "foot_placement_error_rms_m": _rms(foot_placement_errors(result)),
        "L_end_of_step_error_rms": _rms(np.linalg.norm(L_err, axis=1)),
        "L_end_of_step_error_rms_xy": [_rms(L_err[:, 0]), _rms(L_err[:, 1])],
        "output_tracking_rms": {name: _rms(h_err[:, i]) for i, name in enumerate(out_names)},
        "torque_peak_Nm": {name: float(np.max(np.abs(tau[:, i]))) if n else None for i, name in enumerate(act_names)},
        "torque_rms_Nm": {name: _rms(tau[:, i]) for i, name in enumerate(act_names)},
        "tick_time_us": {
            "median": float(np.median(tick)) if tick.size else None,
            "p99": float(np.percentile(tick, 99)) if tick.size else None,
        },
        "realtime_factor": result.sim_time_s / result.wall_time_s if result.wall_time_s > 0 else None,
        "controller_us_per_tick": _median(tick),
        "mujoco_us_per_tick": _median(result.mujoco_time_us),
        "harness_us_per_tick": _median(result.harness_time_us),
        "fallback_ticks": int(result.fallback_ticks),
        "tracker_failed_ticks": int(np.sum(log["tracker_ok"] == 0.0)),
        "settle_s": float(settle_s),
        "plant": result.info.get("plant"),
        "sensors": result.info.get("sensors"),
        "estimator": result.info.get("estimator"),
        "plant_modifiers": result.info.get("modifiers", {}),
        "terrain": result.info.get("terrain", "flat"),
        "safe_mode_ticks": int(result.safe_mode_ticks),
        "estimator_divergences": int(result.estimator_divergences),
        "base_velocity_error_rms_mps": base_vel_err,
        "yaw_estimate_error_deg": yaw_err,
    }


def to_jsonable(value: Any) -> Any:
    """Replace NaN/inf by ``None`` and numpy scalars/arrays by Python types, recursively."""
    if isinstance(value, dict):
        return {str(k): to_jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [to_jsonable(v) for v in value]
    if isinstance(value, np.ndarray):
        return to_jsonable(value.tolist())
    if isinstance(value, (np.bool_, bool)):
        return bool(value)
    if isinstance(value, (np.integer,)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        f = float(value)
        return f if math.isfinite(f) else None
    return value


def dumps(summary: dict[str, Any]) -> str:
    """The summary as indented JSON (NaN written as ``null``)."""
    return json.dumps(to_jsonable(summary), indent=2, allow_nan=False)
