"""The run summary on a synthetic RunResult with known numbers."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from amlip_qp.control.walking.controller import StepRecord
from amlip_qp.exceptions import InputError
from amlip_qp.sim.loop.run_types import RunResult
from amlip_qp.sim.reports.summary import dumps, heading_frame_xy, step_velocities, summarize, to_jsonable

DT = 0.01
N = 1000  # 10 s
HEADING = math.pi / 2
V_WORLD = np.array([1.0, 0.5, 0.0])  # heading frame (yaw 90 deg): vx = 0.5, vy = -1.0


def _result(fell=False) -> RunResult:
    t = np.arange(N) * DT
    log = {
        "t": t,
        "com": np.outer(t, V_WORLD) + [0.0, 0.0, 0.8],
        "com_vel": np.tile(V_WORLD, (N, 1)),
        "heading": np.full(N, HEADING),
        "cmd_vx": np.full(N, 0.4),
        "cmd_vy": np.full(N, -1.0),
        "base_yaw": (np.angle(np.exp(1j * (3.0 + t / t[-1])))),  # crosses +pi: unwrapping needed
        "h": np.zeros((N, 2)),
        "h_d": np.zeros((N, 2)),
        "tau": np.full((N, 2), 3.0),
        "tracker_ok": np.ones(N),
    }
    log["h"][:, 0] = 0.1
    log["h"][:, 1] = np.where(np.arange(N) % 2, 0.2, -0.2)
    log["tau"][5, 0] = -10.0
    log["tracker_ok"][:4] = 0.0
    steps = []
    for k in range(20):  # 0.5 s steps
        t0, t1 = 0.5 * k, 0.5 * (k + 1)
        target = np.array([1.0, 2.0, 0.0]) * k
        L_end = np.array([10.0, 20.0]) + k
        steps.append(
            StepRecord(
                t_start_s=t0,
                t_end_s=min(t1, t[-1]),
                stance="left" if k % 2 == 0 else "right",
                swing_target_m=target,
                swing_actual_m=target + [0.03, 0.04, 0.01],
                L_end_Nms=L_end,
                L_target_Nms=np.full(2, np.nan) if k == 0 else L_end - [3.0, 4.0],
                com_vel_end_mps=V_WORLD.copy(),
                heading_rad=HEADING,
            )
        )
    return RunResult(
        robot="cassie",
        tracker="stand-in",
        duration_s=10.0,
        sim_time_s=10.0,
        wall_time_s=5.0,
        fell=fell,
        fall_time_s=9.99 if fell else float("nan"),
        log=log,
        steps=steps,
        tick_time_us=np.arange(1.0, N + 1.0),
        fallback_ticks=3,
        info={
            "output_names": ("a", "b"),
            "actuator_names": ("m0", "m1"),
            "scenario": "synthetic",
            "seed": 4,
            "noise": False,
        },
    )


def test_summary_fields_have_the_known_values():
    s = summarize(_result())
    assert s["robot"] == "cassie" and s["tracker"] == "stand-in" and s["scenario"] == "synthetic"
    assert s["duration_s"] == 10.0 and s["sim_time_s"] == 10.0
    assert s["fell"] is False and s["fall_time_s"] is None
    assert s["steps"] == 20
    assert s["commanded_velocity"] == [0.4, -1.0]
    assert s["mean_velocity"] == pytest.approx([0.5, -1.0])
    assert s["velocity_error_rms"] == pytest.approx(0.1)  # |(0.5, -1) - (0.4, -1)|
    assert s["heading_change_deg"] == pytest.approx(math.degrees(1.0))
    assert s["foot_placement_error_rms_m"] == pytest.approx(0.05)  # horizontal only: |(0.03, 0.04)|
    assert s["L_end_of_step_error_rms"] == pytest.approx(5.0)  # first step (NaN target) skipped
    assert s["L_end_of_step_error_rms_xy"] == pytest.approx([3.0, 4.0])
    assert s["output_tracking_rms"] == pytest.approx({"a": 0.1, "b": 0.2})
    assert s["torque_peak_Nm"] == pytest.approx({"m0": 10.0, "m1": 3.0})
    assert s["torque_rms_Nm"]["m0"] == pytest.approx(math.sqrt((999 * 9.0 + 100.0) / 1000))
    assert s["tick_time_us"]["median"] == pytest.approx(500.5)
    assert s["tick_time_us"]["p99"] == pytest.approx(np.percentile(np.arange(1.0, N + 1.0), 99))
    assert s["realtime_factor"] == pytest.approx(2.0)
    assert s["fallback_ticks"] == 3 and s["tracker_failed_ticks"] == 4


def test_velocity_error_ignores_steps_before_settling():
    res = _result()
    res.log["cmd_vx"][: int(2.0 / DT)] = 5.0  # wild command only during settling
    assert summarize(res)["velocity_error_rms"] == pytest.approx(0.1)
    assert summarize(res, settle_s=0.0)["velocity_error_rms"] > 1.0


def test_step_velocities_are_displacement_over_duration_in_heading_frame():
    t0, vm, vc = step_velocities(_result())
    assert t0.size == 20
    assert np.allclose(vm, [0.5, -1.0])
    assert np.allclose(vc, [0.4, -1.0])


def test_mean_velocity_uses_the_last_window():
    res = _result()
    res.log["com_vel"][: int(7.0 / DT) - 1] = 0.0  # only the last 3 s move
    assert summarize(res)["mean_velocity"] == pytest.approx([0.5, -1.0])


def test_json_has_no_nan_and_round_trips():
    res = _result(fell=True)
    for st in res.steps:
        st.L_target_Nms = np.full(2, np.nan)
    text = dumps(summarize(res))
    data = json.loads(text)
    assert data["fell"] is True and data["fall_time_s"] == pytest.approx(9.99)
    assert data["L_end_of_step_error_rms"] is None
    assert to_jsonable({"x": np.float64("inf"), "y": np.arange(2)}) == {"x": None, "y": [0, 1]}


def test_summary_rejects_bad_settings():
    with pytest.raises(InputError):
        summarize(_result(), settle_s=-1.0)


def test_heading_frame_rotation():
    assert np.allclose(heading_frame_xy(np.array([1.0, 0.0, 0.0]), math.pi / 2), [0.0, -1.0])
