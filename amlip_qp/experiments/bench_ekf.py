"""``amlip-qp bench ekf``: the invariant EKF's cost inside the closed loop, against the QP tracker's tick.

The goal: the EKF runs inside the 2 kHz tick and costs at most 15 %
of the QP tracker's tick, median. :func:`run` walks a scenario on the
hardware-like setting (default ``cassie-1mps-cc-ekf``: closed-chain plant,
robot sensors, the EKF) with the QP tracker and times, on every tick, the
controller's whole ``step`` and, inside it, the base estimator's ``fill``
(leg kinematics, propagation, correction, base state). Both times come from
the same ticks, so the machine's speed drifts (up to 1.6x within minutes on
the shared development machine) affect both alike; the ratio is
``median(fill) / median(step - fill)``: the EKF against the rest of the tick
(planner and QP tracker), as it would be added to a controller without it.

Recording needs the plant, so the benchmark lives in ``sim``.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from amlip_qp.estimation.base_estimator import BaseStateEstimator
from amlip_qp.exceptions import InputError
from amlip_qp.profiles import DEFAULT_EKF_SCENARIO
from amlip_qp.sim.scenarios.factory import build_simulation
from amlip_qp.sim.scenarios.named import get_scenario

#: The goal: EKF median cost as a fraction of the rest of the QP tracker's tick.
GOAL_FRACTION = 0.15


class _TimedEstimator:
    """A :class:`BaseStateEstimator` that wraps another and records the wall time of each ``fill``, µs."""

    def __init__(self, inner: BaseStateEstimator):
        self.inner = inner
        self.diverged = inner.diverged
        self.times_us: list[float] = []

    def reset(self) -> None:
        self.inner.reset()
        self.diverged = self.inner.diverged

    def set_ground_pitch(self, pitch_rad: float) -> None:
        self.inner.set_ground_pitch(pitch_rad)

    def fill(self, measurement):
        t0 = time.perf_counter_ns()
        out = self.inner.fill(measurement)
        self.times_us.append((time.perf_counter_ns() - t0) * 1e-3)
        self.diverged = self.inner.diverged
        return out


def run(scenario: str = DEFAULT_EKF_SCENARIO, duration_s: float = 4.0) -> dict:
    """Walk ``scenario`` for ``duration_s`` with the QP tracker; the EKF's and the tick's costs (µs) and their ratio.

    Raises:
        InputError: A scenario whose estimator is not the EKF.
    """
    sc = get_scenario(scenario)
    if sc.setting.estimator != "ekf":
        raise InputError(f"bench ekf needs a scenario with the EKF estimator; {scenario!r} uses {sc.setting.estimator}")
    sim = build_simulation(sc.with_(duration_s=duration_s), "qp")
    timed = _TimedEstimator(sim.controller.base_estimator)
    sim.controller.base_estimator = timed
    result = sim.run(duration_s)
    tick = np.asarray(result.tick_time_us)
    ekf = np.asarray(timed.times_us[: tick.size])
    rest = tick - ekf
    report: dict = {
        "scenario": scenario,
        "ticks": int(tick.size),
        "fell": bool(result.fell),
        "ekf_fill_us": {"median": float(np.median(ekf)), "p99": float(np.percentile(ekf, 99))},
        "tick_without_ekf_us": {"median": float(np.median(rest)), "p99": float(np.percentile(rest, 99))},
        "tick_us": {"median": float(np.median(tick)), "p99": float(np.percentile(tick, 99))},
        "ratio_median": float(np.median(ekf) / np.median(rest)),
        "goal_ratio": GOAL_FRACTION,
    }
    report["meets_goal"] = bool(report["ratio_median"] <= GOAL_FRACTION)
    return report


def format_report(r: dict) -> str:
    """The report as a few lines of text."""
    return "\n".join(
        [
            f"EKF inside the QP tracker's tick, {r['scenario']}, {r['ticks']} ticks" + (" (FELL)" if r["fell"] else ""),
            f"  EKF fill:             median {r['ekf_fill_us']['median']:7.1f} µs, "
            f"p99 {r['ekf_fill_us']['p99']:8.1f} µs",
            f"  tick without the EKF: median {r['tick_without_ekf_us']['median']:7.1f} µs, "
            f"p99 {r['tick_without_ekf_us']['p99']:8.1f} µs",
            f"  ratio of medians: {100 * r['ratio_median']:.1f} % (goal <= {100 * r['goal_ratio']:.0f} %: "
            + ("met)" if r["meets_goal"] else "NOT met)"),
        ]
    )


def run_bench(args: argparse.Namespace) -> int:
    """``amlip-qp bench ekf``: print the report (and write JSON)."""
    from amlip_qp.output_paths import check_output_path, emit_report

    target = getattr(args, "json", None)
    check_output_path("--json", target)
    report = run(scenario=args.scenario, duration_s=args.duration)
    emit_report(format_report(report), report, target)
    return 0
