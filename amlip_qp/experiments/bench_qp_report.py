"""The numbers and the table of ``amlip-qp bench qp``: time statistics, agreement with the reference.

The agreement of a solver is measured on its own solutions against the
reference solutions (ProxQP re-initialised at a tight tolerance, see
:func:`amlip_qp.experiments.bench_qp.reference_solutions`): the largest
``|x - x_ref|`` over all variables and problems, the largest constraint
violation of its ``x`` (equalities, inequalities, box), and the largest
excess of its cost over the reference's. The tracker's cost is nearly flat in
some directions (its smallest curvature, 1e-6, lies along the split of the
contact forces between the contact points), so two solutions that both meet a
tolerance can differ there by far more than their costs do: read
``|x - x_ref|`` together with the cost excess.
"""

from __future__ import annotations

import numpy as np

from amlip_qp.qp.problem import QPProblem


def time_stats(times_us: list[float]) -> dict:
    """``{"median_us", "p99_us", "n"}`` of solve times (µs)."""
    t = np.asarray(times_us, dtype=float)
    return {"median_us": float(np.median(t)), "p99_us": float(np.percentile(t, 99)), "n": int(t.size)}


def agreement(problems: list[QPProblem], xs: list, refs: list[np.ndarray]) -> dict:
    """``{"max_dx", "max_violation", "max_cost_excess"}`` of the solutions ``xs`` (``None``: no
    solution, skipped) against ``refs``; NaN when there is no solution at all."""
    dx, viol, excess = [], [], []
    for p, x, ref in zip(problems, xs, refs):
        if x is None:
            continue
        dx.append(float(np.max(np.abs(x - ref))))
        viol.append(max(p.residuals(x).values()))
        excess.append(p.objective(x) - p.objective(ref))
    nan = float("nan")
    return {
        "max_dx": max(dx, default=nan),
        "max_violation": max(viol, default=nan),
        "max_cost_excess": max(excess, default=nan),
    }


def _g(v: float) -> str:
    return f"{v:.1e}" if np.isfinite(v) else "-"


def format_report(report: dict) -> str:
    """A human-readable table of :func:`amlip_qp.experiments.bench_qp.run`'s (or ``bench_solvers``') report."""
    step = report.get("mujoco_step_us")
    lines = [f"{report['n_problems']} tracker QPs replayed from {report['scenario']}"] if "scenario" in report else []
    lines.append(
        f"{'solver':<16}{'median µs':>10}{'p99 µs':>10}{'x warm':>8}{'steps':>9}"
        f"{'max|dx|':>9}{'max viol':>10}{'cost+':>9}{'fails':>6}"
    )
    for name, s in report["solvers"].items():
        steps = f"{s['median_us'] / step:>9.2f}" if step else f"{'-':>9}"
        lines.append(
            f"{name:<16}{s['median_us']:>10.1f}{s['p99_us']:>10.1f}{s['ratio_to_warm']:>8.2f}{steps}"
            f"{_g(s['max_dx']):>9}{_g(s['max_violation']):>10}{_g(s['max_cost_excess']):>9}{s['failures']:>6d}"
        )
    lines.append(
        "x warm: median over proxsuite-warm's median; steps: median in MuJoCo steps "
        + (f"(one mj_step alone: {step:.1f} µs, measured in every block)" if step else "(no yardstick measured)")
    )
    lines.append(f"max|dx|, max viol, cost+: against {report['reference']}, over all problems")
    lines.append("timed per problem (the solver's own format is built before the timed call):")
    for name, s in report["solvers"].items():
        lines.append(f"  {name}: {s['timed']}; start: {s['start']}")
        if "update_median_us" in s:
            lines.append(
                f"    of it, timed apart (medians): DAQP's update (H's Cholesky factor and its inverse, the"
                f" rows through it, the working set factored again) {s['update_median_us']:.1f} µs, its solve"
                f" {s['solve_median_us']:.1f} µs"
            )
    versions = report.get("versions")
    if versions:
        lines.append("versions: " + ", ".join(f"{k} {v}" for k, v in versions.items()))
    t = report.get("tick_us")
    if t:
        lines.append(
            f"controller tick (estimate, plan, build, solve): median {t['median']:.1f} µs, p99 {t['p99']:.1f} µs"
        )
    lines.extend(report.get("missing", []))
    return "\n".join(lines)
