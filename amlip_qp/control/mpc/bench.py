"""``amlip-qp bench mpc``: the step-timing MPC's cost per control tick.

A point mass (32 kg at ``H = 0.8 m``, ``T = 0.3 s``, 0.5 m/s, step width 0.25 m) walks on the
exact ALIP flow at 2 kHz with the MPC planner on its fast path
(:func:`~amlip_qp.control.mpc.make_mpc_planner`: the generated-C ``alip_mpc_qp`` kernel and a
hot-started DAQP), pushed forward by 1.5 m/s at 1.0 s and sideways by 0.6 m/s at 2.5 s so
that the step time and reach limits become active. Each tick is timed, in microseconds:

- ``mpc_solve``: the MPC's QP, its matrices (generated C) and its solves, every linearisation
  (:attr:`MPCPlanner.last_solve_us <amlip_qp.alip.mpc_planner.MPCPlanner.last_solve_us>`);
- ``mpc_update``: the whole planner tick (the QP, then the one-step planner's tick with the
  planned ``T`` and foothold);
- ``one_step_update``: the one-step planner's tick (on the generated C) on the same states.

Each entry has ``median_us`` and ``p99_us``; also the shortest planned step, the failures
(ticks that fell back to the one-step law) and the mean linearisations per tick. ``amlip-qp bench
mpc`` (:mod:`amlip_qp.experiments.bench_mpc`) times the QP tracker's own solve in turns with it.
"""

from __future__ import annotations

import math
import platform
import time
from collections.abc import Callable

import numpy as np

from amlip_qp.alip.planner import Planner
from amlip_qp.codegen import load_kernels
from amlip_qp.control.mpc.factory import make_mpc_planner
from amlip_qp.messages import Command, StateEstimate

M_KG, H_M, G, T_S, DT_S = 32.0, 0.8, 9.81, 0.3, 0.0005
OUTPUTS = (
    "torso_pitch", "torso_roll", "stance_hip_yaw", "swing_hip_yaw", "com_z_over_stance",
    "com_x_over_swing", "com_y_over_swing", "com_z_over_swing", "swing_toe_pitch",
)  # fmt: skip
PUSHES = ((1.0, (1.5, 0.0)), (2.5, (0.0, 0.6)))


def _stats(samples_us) -> dict[str, float]:
    a = np.asarray(samples_us, dtype=float)
    return {"median_us": float(np.median(a)), "p99_us": float(np.percentile(a, 99))}


def run_benchmark(
    duration_s: float = 4.0, between_blocks: Callable[[], None] | None = None, block_ticks: int = 50
) -> dict:
    """Walk the point mass for ``duration_s`` s (module doc); return the JSON-ready result.

    ``between_blocks``, if given, is called (untimed) after every ``block_ticks`` ticks: a caller
    timing another solver in turns with the MPC (``amlip-qp bench mpc``'s QP tracker solve).
    """
    lam = math.sqrt(G / H_M)
    cmd = Command(step_time_s=T_S, com_height_m=H_M, clearance_m=0.1, vx_mps=0.5, step_width_m=0.25)
    mpc = make_mpc_planner(OUTPUTS, M_KG, g=G)
    kernels = load_kernels()
    one = Planner(OUTPUTS, M_KG, G, plan_fn=kernels.alip_plan, reference_fn=kernels.swing_reference)
    c, v, r = np.array([0.0, -0.1, H_M]), np.zeros(3), np.zeros(3)
    stance, t, t_start = "left", 0.0, 0.0
    h0 = np.array([0.0, 0.0, 0.0, 0.0, H_M, 0.0, -0.25, H_M, 0.0])
    for planner in (mpc, one):
        planner.start_step(stance, 0.0, h0)
    solve, update, update_one, iterations, shortest = [], [], [], [], math.inf
    clock = time.perf_counter_ns
    n_ticks = int(round(duration_s / DT_S))
    for i_tick in range(n_ticks):
        if between_blocks is not None and i_tick and i_tick % block_ticks == 0:
            between_blocks()
        est = StateEstimate(stance=stance, p_st_m=c - r, L_Nms=np.cross(c - r, M_KG * v), v_z_mps=0.0,
                            t_in_step_s=t - t_start, com_m=c.copy())  # fmt: skip
        t0 = clock()
        out = mpc.update(est, cmd)
        update.append((clock() - t0) * 1e-3)
        solve.append(mpc.last_solve_us)
        iterations.append(mpc.last_plan.iterations if mpc.last_plan else 0)
        t0 = clock()
        one.update(est, cmd)
        update_one.append((clock() - t0) * 1e-3)
        for t_push, dv in PUSHES:
            if abs(t - t_push) < 0.5 * DT_S:
                v[:2] += dv
        p = c[:2] - r[:2]
        ch, sh = math.cosh(lam * DT_S), math.sinh(lam * DT_S)
        c[:2], v[:2] = r[:2] + p * ch + v[:2] / lam * sh, p * lam * sh + v[:2] * ch
        t += DT_S
        T_now = mpc.clock.step_time_s(T_S)
        if t - t_start >= T_now - 1e-9:
            shortest = min(shortest, t - t_start)
            r = np.array([*out.swing_target_world_m[:2], 0.0])
            stance = "right" if stance == "left" else "left"
            t_start = t
            for pl in (mpc, one):
                pl.start_step(stance, t, h0)
    return {
        "mpc_solve": _stats(solve),
        "mpc_update": _stats(update),
        "one_step_update": _stats(update_one),
        "ticks": n_ticks,
        "mean_linearisations": float(np.mean(iterations)),
        "failures": mpc.failures,
        "shortest_step_s": shortest,
        "fell": bool(np.linalg.norm(c[:2] - r[:2]) > 1.5),
        "python": platform.python_version(),
        "machine": platform.machine(),
    }


def format_table(result: dict) -> str:
    """A readable table of :func:`run_benchmark`'s result."""
    lines = [
        f"amlip-qp bench mpc: {result['ticks']} ticks of a pushed point-mass walk at 2 kHz "
        f"(mean {result['mean_linearisations']:.2f} linearisations a tick, {result['failures']} failures, "
        f"shortest step {result['shortest_step_s']:.3f} s)",
        f"{'what':<18}{'median_us':>11}{'p99_us':>11}",
    ]
    for key in ("mpc_solve", "mpc_update", "one_step_update"):
        s = result[key]
        lines.append(f"{key:<18}{s['median_us']:>11.2f}{s['p99_us']:>11.2f}")
    return "\n".join(lines)
