"""The text table of ``amlip-qp bench harness`` (:func:`amlip_qp.experiments.bench_harness.run`'s report)."""

from __future__ import annotations

#: What each tracker's timed parts of ``compute`` are, in the report's words.
_QP_PARTS = "the problem's build, the solver's call"
_PBC_PARTS = "the IK, the swing compensation, the constrained dynamics' assembly and solve"


def format_report(r: dict) -> str:
    """The report as a table."""
    ref = r["reference"]
    lines = [
        f"closed-loop tick, {r['scenario']}, {r['duration_s']:g} s x {r['repeats']} per row, interleaved "
        "(medians, µs per tick; per MuJoCo step: means; per step alone: medians of the walks' ratios)",
        f"  {'tracker/log':19s} {'controller':>10s} {'MuJoCo':>8s} {'harness':>8s} {'sum':>8s} {'realtime':>9s}"
        f" {'tick/MJ':>8s} {'harn/MJ':>8s} {'at ref.':>8s} {'alone':>6s} {'tick/al':>8s} {'harn/al':>8s}",
    ]
    for key, row in r["runs"].items():
        lines.append(
            f"  {key:19s} {row['controller_us_per_tick']:10.1f} {row['mujoco_us_per_tick']:8.1f} "
            f"{row['harness_us_per_tick']:8.1f} {row['sum_us_per_tick']:8.1f} {row['realtime_factor']:8.2f}x"
            f" {row['tick_per_mujoco']:8.2f} {row['harness_per_mujoco']:8.2f}"
            f" {row['realtime_factor_at_reference']:7.2f}x {row['step_alone_us']:6.2f} {row['tick_per_step']:8.2f}"
            f" {row['harness_per_step']:8.2f}" + (" (FELL)" if row["fell"] else "")
        )
    lines.append(
        "  in MuJoCo steps (each step timed alone, replayed after every walk; the walks' tick medians over the"
        " step medians, median over the walks): step µs, controller tick, tracker's own work (kinematics update"
        " + compute); the same two over MuJoCo's step in the same tick of the loop (medians over the ticks);"
        " goals (on the step in the loop)"
    )
    for key, row in r["runs"].items():
        verdicts = []
        for name, g in row["speed_goals"].items():
            unit = "x real time" if name == "realtime_factor" else " steps"
            sign = ">=" if name == "realtime_factor" else "<="
            label = {"controller_steps": "tick", "tracker_steps": "tracker", "realtime_factor": "walk"}[name]
            verdicts.append(f"{label} {sign} {g['goal']:g}{unit}: " + ("met" if g["met"] else "NOT met"))
        lines.append(
            f"  {key:19s} {row['step_median_us']:6.1f} {row['controller_per_step']:6.2f}"
            f" {row['tracker_per_step']:6.2f}   {row['controller_per_loop_step']:6.2f}"
            f" {row['tracker_per_loop_step']:6.2f}   " + ("; ".join(verdicts) if verdicts else "no goal")
        )
    ticked = {key: row["controller_parts_per_loop_step"] for key, row in r["runs"].items()}
    if any(ticked.values()):
        lines.append(
            "  the controller's tick in its parts, over MuJoCo's step in the same tick of the loop (medians over"
            " the ticks): the estimate (state, step clock, speed correction), the planner's update, the"
            " tracker's own work, the rest of the tick"
        )
        for key, p in ticked.items():
            if p:
                lines.append(
                    f"  {key:19s} estimate   {p['estimate']:5.2f}  plan  {p['plan']:5.2f}"
                    f"  tracker {p['tracker']:5.2f}  rest {p['rest']:5.2f}"
                )
    parted = {key: row["tracker_parts_per_loop_step"] for key, row in r["runs"].items()}
    for part, what in (("build", _QP_PARTS), ("ik", _PBC_PARTS)):
        rows = {key: p for key, p in parted.items() if part in p}
        if not rows:
            continue
        lines.append(
            "  the tracker's own work in its parts, over MuJoCo's step in the same tick of the loop (medians over"
            f" the ticks): the kinematics update, {what}, the rest of compute"
        )
        for key, p in rows.items():
            named = "  ".join(f"{name} {value:5.2f}" for name, value in p.items())
            lines.append(f"  {key:19s} {named}")
    same = ", ".join(f"{t}: {'yes' if ok else 'NO'}" for t, ok in r["same_summary"].items())
    lines.append(f"  same summary in both log modes: {same}")
    lines.append(
        f"  reference machine state: a {ref['scenario']} {ref['tracker']} walk of "
        f"{ref['tick_per_mujoco']:.2f} MuJoCo steps of wall time per tick (harness {ref['harness_per_mujoco']:.2f}) "
        f"ran at {ref['realtime_factor']:g}x real time"
    )
    for key, ok in r["qp_meets_realtime_goal"].items():
        lines.append(
            f"  {key} walk at >= {r['goal_realtime_factor']:g}x real time on that machine state "
            f"(<= {r['goal_tick_per_mujoco']:.2f} MuJoCo steps per tick): " + ("met" if ok else "NOT met")
        )
    if not r["harness_meets_goal"]:
        lines.append(f"  no verdict on the goals: they are set for {ref['scenario']} {ref['tracker']} walks")
        return "\n".join(lines)
    met = [key for key, ok in r["harness_meets_goal"].items() if ok]
    lines.append(
        f"  harness <= {r['goal_harness_per_mujoco']:.2f} MuJoCo steps per tick: "
        + (f"met by {', '.join(met)}" if met else "NOT met")
    )
    return "\n".join(lines)
