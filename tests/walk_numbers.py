"""The numbers the walking acceptance tests judge a run by (not a test module)."""

import numpy as np


def walk_numbers(sc, res) -> dict:
    """A run's numbers over its last 3 s (heading frame) and its end state, picklable.

    Args:
        sc: The scenario run (its duration and commands).
        res: Its :class:`~amlip_qp.sim.loop.run_types.RunResult`.
    """
    log = res.log
    last = log["t"] > log["t"][-1] - 3.0
    D = log["heading"][last]
    vel = log["com_vel"][last]
    return {
        "duration_s": float(sc.duration_s),
        "final_vx_mps": float(sc.vx.final_mps),
        "cmd_vy_mps": float(sc.vy_mps),
        "fell": bool(res.fell),
        "sim_time_s": float(res.sim_time_s),
        "vx_mps": float(np.mean(vel[:, 0] * np.cos(D) + vel[:, 1] * np.sin(D))),
        "vy_mps": float(np.mean(-vel[:, 0] * np.sin(D) + vel[:, 1] * np.cos(D))),
        "drift_m": float(np.linalg.norm(log["com"][-1, :2] - log["com"][0, :2])),
        "travel_dir_rad": float(np.arctan2(np.mean(vel[:, 1]), np.mean(vel[:, 0]))),
        "world_speed_mps": float(np.linalg.norm(np.mean(vel[:, :2], axis=0))),
        "vx_last_1_5s_mps": float(np.mean(log["com_vel"][log["t"] > log["t"][-1] - 1.5, 0])),
        "heading_end_rad": float(log["heading"][-1]),
        "yaw_end_rad": float(np.unwrap(log["base_yaw"])[-1]),
        "fallback_ticks": int(res.fallback_ticks),
        "ticks": int(len(log["t"])),
        "tau_finite": bool(np.all(np.isfinite(log["tau"]))),
    }
