"""The comparison's experiments: settings, scenario builders, and the robustness searches."""

from __future__ import annotations

import math

import numpy as np
import pytest

from amlip_qp.exceptions import InputError
from amlip_qp.experiments.robustness import (
    PUSH_DURATION_S,
    QUICK,
    CompareSettings,
    compare_ranges,
    highest_steady_speed,
    largest_surviving,
    max_survived_impulse,
    nominal_scenario,
    push_scenario,
    ramp_scenario,
)
from amlip_qp.sim.loop.run_types import RunResult
from amlip_qp.sim.scenarios.named import get_scenario

DT = 0.01
N = 1000  # 10 s


def _ramp_result(cmd: np.ndarray, measured_vx: np.ndarray) -> RunResult:
    """A synthetic run at heading 0 with commanded and measured forward speeds (m/s)."""
    t = np.arange(N) * DT
    log = {
        "t": t,
        "com_vel": np.stack([measured_vx, 0 * t, 0 * t], axis=1),
        "heading": np.zeros(N),
        "cmd_vx": cmd,
    }
    return RunResult("cassie", "stand-in", 10.0, 10.0, 1.0, False, float("nan"), log, [], np.ones(N), 0)


def test_highest_steady_speed_on_a_synthetic_ramp():
    t = np.arange(N) * DT
    cmd = np.clip(0.2 * t, 0.0, None)  # 0 -> 2 m/s over 10 s
    meas = np.minimum(cmd, 1.2)  # the walker saturates at 1.2 m/s
    v = highest_steady_speed(_ramp_result(cmd, meas), window_s=2.0, tolerance=0.1)
    # the 2-s mean command c with mean measurement m = c - (excess over 1.2) stays within 10% up to ~1.3 m/s
    assert 1.2 < v < 1.4
    assert highest_steady_speed(_ramp_result(cmd, cmd.copy())) == pytest.approx(
        np.convolve(cmd, np.ones(200) / 200, "valid").max()
    )
    # never within tolerance (walking backwards): 0
    assert highest_steady_speed(_ramp_result(cmd, -cmd)) == 0.0


def test_bisection_finds_the_threshold():
    calls = []

    def survives(impulse):
        calls.append(impulse)
        return impulse <= 23.0

    value, capped = max_survived_impulse(survives, 64.0, 6)
    assert not capped and 22.0 <= value <= 23.0 and len(calls) == 7
    assert max_survived_impulse(lambda i: True, 10.0, 3) == (10.0, True)
    assert max_survived_impulse(lambda i: False, 10.0, 0) == (0.0, False)
    with pytest.raises(InputError, match="max_impulse_Ns > 0"):
        max_survived_impulse(lambda i: True, math.inf, 3)


def test_ramp_scenario_reaches_the_profile_speed():
    settings = CompareSettings()
    sc = ramp_scenario("cassie", settings)
    v_end = compare_ranges("cassie").ramp_end_mps
    assert sc.robot == "cassie" and sc.duration_s == pytest.approx(1.0 + 7.0 + 1.5)
    assert sc.vx(0.5) == 0.0 and sc.vx(1.0 + 3.5) == pytest.approx(0.5 * v_end) and sc.vx(8.5) == v_end
    assert sc.vx.final_mps == v_end


def test_push_scenario_force_gives_the_impulse():
    nominal = get_scenario("cassie-1mps")
    sc = push_scenario(nominal, 12.0, 1, QUICK)
    (push,) = sc.pushes
    assert push.force_N == (0.0, 12.0 / PUSH_DURATION_S, 0.0) and push.impulse_Ns == pytest.approx(12.0)
    assert push.t_s == QUICK.push_time_s
    assert sc.duration_s == pytest.approx(QUICK.push_time_s + PUSH_DURATION_S + QUICK.push_survive_s)
    assert sc.vx == nominal.vx
    assert push_scenario(nominal, 0.0, 0, QUICK).pushes == ()


def test_nominal_scenario_is_the_profiles_or_the_given_one_capped():
    default = nominal_scenario("rabbit", [], CompareSettings())
    assert default.name == compare_ranges("rabbit").nominal_scenario and default.duration_s == 10.0
    chosen = nominal_scenario("cassie", ["rabbit-0.5mps", "cassie-push"], QUICK)
    assert chosen.name == "cassie-push" and chosen.duration_s == QUICK.nominal_duration_s
    uncapped = nominal_scenario("rabbit", [], CompareSettings(nominal_duration_s=None))
    assert uncapped.duration_s == get_scenario("rabbit-0.5mps").duration_s
    with pytest.raises(InputError, match="at most one --scenario per robot"):
        nominal_scenario("cassie", ["cassie-1mps", "cassie-push"], QUICK)


# ------------------------------------------------ the bisection (the sweep's and compare's)
@pytest.mark.parametrize("edge", [0.7, 17.3, 41.9999, 59.5])
def test_bisection_brackets_a_monotone_edge(edge):
    value, capped, trials = largest_surviving(lambda v: v <= edge, 0.0, 60.0, 6)
    assert not capped and value <= edge < value + 60.0 / 2**6
    assert trials[0] == (60.0, False) and len(trials) == 7
    assert all(ok == (v <= edge) for v, ok in trials)


def test_bisection_known_steps_and_cap():
    assert largest_surviving(lambda v: v < 20.0, 0.0, 60.0, 2) == (
        15.0,
        False,
        [(60.0, False), (30.0, False), (15.0, True)],
    )
    assert largest_surviving(lambda v: True, 10.0, 60.0, 5) == (60.0, True, [(60.0, True)])
    assert largest_surviving(lambda v: False, 0.0, 8.0, 3)[:2] == (0.0, False)


def test_bisection_refuses_an_empty_interval():
    with pytest.raises(InputError):
        largest_surviving(lambda v: True, 5.0, 5.0, 3)
