"""Predicting ``L_y(T-)`` vs predicting ``v_x(T-)`` on Cassie and Rabbit (paper, Fig. "LIP prediction").

Along each step the LIP predicts the end-of-step value from the current state:

- angular momentum (paper eq. LIP_AM_Preiction, second row):
  ``L_hat = m H l sinh(l tau) p_x + cosh(l tau) L_y``;
- velocity (paper eq. LIP_original_Preiction, the velocity-based LIP):
  ``v_hat = l sinh(l tau) p_x + cosh(l tau) v_x``,

with ``p_x`` the CoM minus stance contact, ``tau`` the time left in the step
(the planner's horizon), ``H`` the commanded CoM height and ``m`` the mass.
Both go through :func:`amlip_qp.alip.lip.flow`: the velocity LIP is the same
flow applied to ``(p_x, m H v_x)`` (:func:`amlip_qp.alip.formulas.L_from_velocity`).
A perfect predictor is constant along a step. The score per variable is the
within-step spread of the prediction, ``std / |mean|`` of the predicted
end-of-step value over the step's ticks, averaged over the steps (the first
step is skipped: it starts from standing). It is reported over all steps and
over the steady steps (starting after the speed ramp), since steps whose mean
is near zero (the start of the ramp) inflate the ratio of either variable.

Usage: ``python examples/prediction_study.py [--out DIR] [--tracker qp|pbc|auto]``
Writes ``DIR/prediction_<robot>.png`` and ``DIR/prediction_study.json``.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from amlip_qp.sim.reports.gl import prefer_offscreen_gl

prefer_offscreen_gl()

import matplotlib  # noqa: E402

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from amlip_qp.alip import formulas, lip  # noqa: E402
from amlip_qp.exceptions import InputError  # noqa: E402
from amlip_qp.sim.reports.summary import heading_frame_xy, to_jsonable  # noqa: E402
from amlip_qp.sim.scenarios import factory  # noqa: E402
from amlip_qp.sim.scenarios.named import get_scenario  # noqa: E402

#: Forward-walking scenario per robot (the ratio std/|mean| needs a mean away from 0).
SCENARIOS = {"cassie": "cassie-1mps", "rabbit": "rabbit-0.5mps"}


def predictions(result, mass_kg: float, H_m: float):
    """Per tick: ``(L_y, L_hat, v_x, v_hat)``, sagittal in the heading frame (kg m^2/s, m/s)."""
    log = result.log
    p_x = heading_frame_xy(log["p_st"], log["heading"])[:, 0]
    L_h = heading_frame_xy(log["L_meas"], log["heading"])  # (L_x', L_y') in the heading frame
    L_y = L_h[:, 1]
    v_x = heading_frame_xy(log["com_vel"], log["heading"])[:, 0]
    tau = log["t_remaining"]
    _, L_hat = lip.flow(p_x, L_y, tau, mass_kg, H_m)
    _, Lv_hat = lip.flow(p_x, formulas.L_from_velocity(v_x, mass_kg, H_m), tau, mass_kg, H_m)
    return L_y, L_hat, v_x, Lv_hat / (mass_kg * H_m)


def spread(result, pred: np.ndarray, t_from_s: float = 0.0) -> tuple[float, list[float]]:
    """Mean over steps of ``std / |mean|`` of ``pred`` within each completed step.

    The first step is skipped, and so are steps starting before ``t_from_s`` (s).
    """
    t = result.log["t"]
    ratios = []
    for st in result.steps[1:]:
        if st.t_start_s < t_from_s:
            continue
        sel = (t >= st.t_start_s - 1e-12) & (t < st.t_end_s - 1e-12)
        if sel.sum() < 10:
            continue
        mean = float(np.mean(pred[sel]))
        ratios.append(float(np.std(pred[sel]) / abs(mean)) if mean != 0 else float("inf"))
    return (float(np.mean(ratios)) if ratios else float("nan")), ratios


def run_robot(robot: str, tracker: str, duration_s: float, min_steps: int):
    """Run the robot's scenario with ``tracker`` (``auto``: the first of qp, pbc that completes ``min_steps``)."""
    candidates = ["qp", "pbc"] if tracker == "auto" else [tracker]
    scenario = get_scenario(SCENARIOS[robot]).with_(duration_s=duration_s)
    best = None
    for name in candidates:
        try:
            res = factory.run_scenario(scenario, name, progress=True)
        except InputError as exc:
            print(f"  {robot}/{name}: {exc}", file=sys.stderr)
            continue
        print(f"  {robot}/{name}: {len(res.steps)} steps, fell={res.fell}", file=sys.stderr)
        if best is None or len(res.steps) > len(best.steps):
            best = res
        if len(res.steps) >= min_steps + 1:
            break
    return scenario, best


def plot(robot: str, result, L_y, L_hat, v_x, v_hat, path: Path) -> None:
    t = result.log["t"]
    fig, axes = plt.subplots(2, 1, figsize=(10, 6), sharex=True)
    axes[0].plot(t, L_y, "C0", lw=0.8, label="$L_y(t)$ about the stance contact")
    axes[0].plot(t, L_hat, "C3", lw=0.8, label=r"$\hat L_y(T^-)$ predicted (ALIP)")
    axes[0].set_ylabel("kg m²/s")
    axes[1].plot(t, v_x, "C0", lw=0.8, label="$v_x(t)$ CoM")
    axes[1].plot(t, v_hat, "C3", lw=0.8, label=r"$\hat v_x(T^-)$ predicted (velocity LIP)")
    axes[1].set_ylabel("m/s")
    axes[1].set_xlabel("time [s]")
    for ax in axes:
        for st in result.steps:
            ax.axvline(st.t_end_s, color="0.85", lw=0.5, zorder=0)
        ax.legend(loc="upper left", fontsize=8)
    fig.suptitle(f"{robot} / {result.tracker}: end-of-step predictions along each step")
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="out", help="output folder (default ./out)")
    ap.add_argument("--tracker", choices=["auto", "qp", "pbc"], default="auto")
    ap.add_argument("--duration", type=float, default=7.0, help="simulated time per robot, s (default 7)")
    ap.add_argument("--min-steps", type=int, default=10, help="steps wanted per robot (default 10)")
    args = ap.parse_args(argv)
    out = Path(args.out)
    report = {}
    for robot in ("cassie", "rabbit"):
        scenario, res = run_robot(robot, args.tracker, args.duration, args.min_steps)
        if res is None:
            report[robot] = {"error": "no tracker available"}
            continue
        robot_model = factory.load(robot)
        H = scenario.gait_settings.com_height_m
        L_y, L_hat, v_x, v_hat = predictions(res, robot_model.mass_kg, H)
        sL, rL = spread(res, L_hat)
        sv, rv = spread(res, v_hat)
        t_steady = scenario.vx.times_s[-1]
        sL_st, rL_st = spread(res, L_hat, t_steady)
        sv_st, _ = spread(res, v_hat, t_steady)
        plot(robot, res, L_y, L_hat, v_x, v_hat, out / f"prediction_{robot}.png")
        report[robot] = {
            "tracker": res.tracker,
            "scenario": scenario.name,
            "fell": res.fell,
            "steps_used": len(rL),
            "L_hat_spread": sL,
            "v_hat_spread": sv,
            "steady_from_s": t_steady,
            "steady_steps_used": len(rL_st),
            "L_hat_spread_steady": sL_st,
            "v_hat_spread_steady": sv_st,
            "L_hat_spread_per_step": rL,
            "v_hat_spread_per_step": rv,
        }
        print(
            f"{robot}/{res.tracker}: {len(rL)} steps; "
            "within-step spread std/|mean| of the predicted end-of-step value: "
            f"all steps L_y {sL:.3f}, v_x {sv:.3f}; {len(rL_st)} steady steps (t >= {t_steady:g} s) "
            f"L_y {sL_st:.3f}, v_x {sv_st:.3f}" + (" (fell)" if res.fell else "")
        )
        if len(rL) < args.min_steps:
            print(
                f"  note: only {len(rL)} usable steps (< {args.min_steps}); "
                f"the {res.tracker} tracker did not walk long enough"
            )
    out.mkdir(parents=True, exist_ok=True)
    (out / "prediction_study.json").write_text(json.dumps(to_jsonable(report), indent=2) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
