"""Rabbit ramps to 1.5 m/s and holds it, with both trackers (``rabbit-ramp-1.5``).

The ramp runs from 0 at 1 s to 1.5 m/s at 8 s and holds it to 14 s. Above
1 m/s Rabbit's gait schedule (profile ``[shaping] gait_scale_by_speed``)
lengthens the step time to 0.40 s, lowers the CoM to 0.56 m and doubles the
clearance to 0.12 m; without it both trackers fell before 8 s (the numbers:
``docs/TUNING.md``, "Rabbit's gait schedule"). Measured when added (seed 0):
mean speed over the last 3 s 1.503 m/s (QP) and 1.488 m/s (PBC), foot
placement error rms 0.003 and 0.044 m. Each tracker's run happens once
(module-scoped fixture, two worker processes).
"""

from __future__ import annotations

from concurrent.futures import ProcessPoolExecutor

import numpy as np
import pytest

pytestmark = pytest.mark.slow

TRACKERS = ("pbc", "qp")
SCENARIO = "rabbit-ramp-1.5"


def _run(tracker: str) -> dict:
    """The ramp with one tracker: its numbers (picklable)."""
    from amlip_qp.sim.scenarios.factory import run_scenario
    from amlip_qp.sim.scenarios.named import SCENARIOS

    sc = SCENARIOS[SCENARIO]
    res = run_scenario(sc, tracker)
    log = res.log
    t, vel = log["t"], log["com_vel"]
    last = t > t[-1] - 3.0
    held = [s for s in res.steps if s.t_start_s > sc.duration_s - 3.0]
    return {
        "fell": bool(res.fell),
        "sim_time_s": float(res.sim_time_s),
        "duration_s": float(sc.duration_s),
        "final_cmd_mps": float(sc.vx.final_mps),
        "vx_mps": float(np.mean(vel[last, 0])),
        "tracker_ok_fraction": float(np.mean(log["tracker_ok"])),
        "held_step_durations_s": [s.t_end_s - s.t_start_s for s in held],
        "held_step_lengths_m": [float(b.swing_actual_m[0] - a.swing_actual_m[0]) for a, b in zip(held, held[1:])],
    }


@pytest.fixture(scope="module")
def results() -> dict:
    with ProcessPoolExecutor(max_workers=2) as pool:
        return dict(zip(TRACKERS, pool.map(_run, TRACKERS)))


@pytest.mark.parametrize("tracker", TRACKERS)
def test_rabbit_ramps_to_1_5mps_and_holds_it(results, tracker):
    r = results[tracker]
    assert not r["fell"], f"fell at t = {r['sim_time_s']:.2f} s"
    assert r["sim_time_s"] >= r["duration_s"] - 1e-6
    assert r["tracker_ok_fraction"] > 0.99
    assert r["final_cmd_mps"] == 1.5
    assert abs(r["vx_mps"] - 1.5) < 0.1, f"{r['vx_mps']:.3f} m/s over the last 3 s"


@pytest.mark.parametrize("tracker", TRACKERS)
def test_the_held_speed_walks_the_schedules_longer_steps(results, tracker):
    # At 1.5 m/s the schedule's step time is 0.40 s (0.35 s below 1 m/s): the steps take
    # about 0.40 s and are about 1.5 * 0.40 = 0.60 m long, beyond the 0.52 m the legs
    # reach at the gait's own CoM height.
    r = results[tracker]
    durations, lengths = np.array(r["held_step_durations_s"]), np.array(r["held_step_lengths_m"])
    assert len(durations) >= 6
    np.testing.assert_allclose(durations, 0.40, atol=0.015)
    np.testing.assert_allclose(np.mean(lengths), 0.60, atol=0.04)
