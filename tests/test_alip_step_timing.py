"""Tests of amlip_qp.alip.step_timing: the step's duration that brings the one-step law's target to a
moved foothold, and the planner's use of it (``Planner.update(..., timing=...)``)."""

import math

import numpy as np
import pytest

from alip_cases import OUT3, H, T, cmd, est
from amlip_qp.alip import Planner, kernels
from amlip_qp.alip.step_timing import StepTiming, time_left_bounds, time_left_for_step
from amlip_qp.exceptions import InputError
from amlip_qp.messages import PlannerOutput, TerrainPrediction

M, G = 31.0, 9.81
H0 = np.array([0.01, -0.02, 0.03, -0.04, 0.9, -0.15, 0.12, 0.88, 0.0])
#: A step along x: CoM 5 cm behind the stance contact, 0.4 m/s of momentum, a 10 cm rise ahead.
P, L, VZ, DZ = -0.05, 31.0 * H * 0.4, 0.02, 0.1


def law_step(tau_s: float, vx_mps: float = 0.4) -> tuple[float, float]:
    """The one-step law's step along x (target minus stance contact, m) with ``tau_s`` left, and its
    ``L_des_y``, from the numpy ``ALIP_PLAN``."""
    u = np.array([P, 0.0, 0.0, L, tau_s, VZ, vx_mps, 0.0, 0.0, 1.0, M, H, T, 0.2, G, DZ])
    y = kernels.alip_plan(u)
    return float(y[2] - y[6]), float(y[5])


def solve(step_m: float, tau_lo: float, tau_hi: float, tau_nom: float) -> float:
    L_des = law_step(tau_nom)[1]
    return time_left_for_step(P, L, step_m, L_des, T, M, H, VZ, G, DZ, tau_lo, tau_hi, tau_nom)


def test_the_laws_own_step_keeps_the_nominal_time():
    tau_nom = 0.2
    step, _ = law_step(tau_nom)
    assert solve(step, 0.05, 0.4, tau_nom) == pytest.approx(tau_nom, abs=1e-12)


@pytest.mark.parametrize("moved_m", [-0.05, -0.02, 0.03, 0.1])
def test_a_moved_foothold_is_the_laws_target_at_the_planned_time(moved_m):
    """Within the bounds the law, planned with the returned time left, steps exactly to the foothold:
    a foothold ahead takes longer, one behind less."""
    tau_nom = 0.2
    step = law_step(tau_nom)[0] + moved_m
    tau = solve(step, 0.05, 0.4, tau_nom)
    assert law_step(tau)[0] == pytest.approx(step, abs=1e-12)
    assert (tau > tau_nom) == (moved_m > 0.0)


def test_out_of_reach_the_bound_nearer_the_foothold():
    tau_nom = 0.2
    far, near = law_step(0.4)[0] + 0.2, law_step(0.05)[0] - 0.2
    assert solve(far, 0.05, 0.4, tau_nom) == 0.4
    assert solve(near, 0.05, 0.4, tau_nom) == 0.05
    assert solve(far, 0.2, 0.2, tau_nom) == 0.2  # a kept end


def test_bounds_in_units_of_T_and_a_near_end_kept():
    timing = StepTiming(step_time_min=1.0, step_time_max=1.4, min_time_left_s=0.05)
    assert time_left_bounds(timing, 0.3, 0.1, None) == pytest.approx((0.2, 0.32))
    assert time_left_bounds(timing, 0.3, 0.28, None) == pytest.approx((0.05, 0.14))
    assert time_left_bounds(timing, 0.3, 0.1, 0.4) == pytest.approx((0.2, 0.32))
    assert time_left_bounds(timing, 0.3, 0.37, 0.4) == pytest.approx((0.03, 0.03))
    assert time_left_bounds(timing, 0.3, 0.45, 0.4) == (0.0, 0.0)
    for bad in ({"step_time_min": 0.0}, {"step_time_min": 1.2, "step_time_max": 1.1}, {"min_time_left_s": -1}):
        with pytest.raises(InputError, match="StepTiming"):
            StepTiming(**bad)


def started() -> Planner:
    p = Planner(OUT3, M, G)
    p.start_step("left", 2.0, H0)
    return p


def test_the_planner_ends_the_step_when_its_target_is_the_moved_foothold():
    terrain = TerrainPrediction(dz_next_m=DZ, dz_sw_m=DZ)
    timing = StepTiming()
    free = started().update(est(), cmd(), terrain)
    # a hook that moves nothing and no plan on the clock: the same bits as without timing
    p = started()
    same = p.update(est(), cmd(), terrain, lambda x, y, h, s: (x, y), timing=timing)
    assert p.clock.planned_step_time_s is None
    for f in PlannerOutput.__slots__:
        a, b = getattr(free, f), getattr(same, f)
        assert np.array_equal(a, b) if isinstance(a, np.ndarray) else a == b, f
    for moved_m in (0.04, -0.04):
        p = started()
        out = p.update(est(), cmd(), terrain, lambda x, y, h, s: (x + moved_m, y), timing=timing)
        T_plan = p.clock.planned_step_time_s
        assert (T_plan > T) == (moved_m > 0.0)
        assert out.t_remaining_s == pytest.approx(T_plan - 0.1) and out.s == pytest.approx(0.1 / T_plan)
        # the foothold along the heading is the hook's, and it is the law's own target at the planned end
        assert out.swing_target_world_m[0] == pytest.approx(free.swing_target_world_m[0] + moved_m, abs=1e-12)
        retimed = started().update(est(t_in_step_s=0.1 - (T_plan - T)), cmd(), terrain)
        assert retimed.swing_target_world_m[:2] == pytest.approx(out.swing_target_world_m[:2], abs=1e-12)
        assert math.isfinite(out.h_d.sum())
