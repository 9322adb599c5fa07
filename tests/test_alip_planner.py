"""Tests of amlip_qp.alip.planner: the Planner API, its dense packing and its validation."""

import math

import numpy as np
import pytest

from alip_cases import OUT2, OUT3, H, T, cmd, est
from amlip_qp.alip import Planner, StepClock, desired, kernels, lip
from amlip_qp.exceptions import InputError
from amlip_qp.messages import PlannerOutput

M, G = 31.0, 9.81
H0 = np.array([0.01, -0.02, 0.03, -0.04, 0.9, -0.15, 0.12, 0.88, 0.0])


def started(robot=OUT3, h0=H0, **kw):
    p = Planner(robot, M, G, **kw)
    p.start_step("left", 2.0, h0)
    return p


def test_update_matches_the_validated_lip_functions():
    p = started()
    e, c = est(), cmd()
    out = p.update(e, c)
    assert isinstance(out, PlannerOutput)
    t_rem = T - 0.1
    px, Ly = lip.predict_end_of_step(0.03, 12.0, t_rem, M, H, G)
    py, Lt = lip.predict_end_of_step(-0.1, -1.5, t_rem, M, H, G)
    np.testing.assert_allclose(out.L_hat_Nms, [-Lt, Ly], rtol=1e-12)
    np.testing.assert_allclose(out.p_hat_m, [px, py], rtol=1e-12)
    vx_end = desired.end_of_step_velocity(0.5, T, H, G)
    vy_end = desired.end_of_step_velocity(0.1, T, H, G)
    L_des = desired.desired_L_world(vx_end, vy_end, 0.2, T, M, H, "right", 0.0, G)
    np.testing.assert_allclose(out.L_des_Nms, L_des, rtol=1e-12)
    p_sw_x = lip.foot_placement_vz(L_des[1], Ly, px, 0.05, T, M, H, G)
    p_sw_y = lip.foot_placement_vz(-L_des[0], Lt, py, 0.05, T, M, H, G)
    np.testing.assert_allclose(out.p_sw_des_world_m, [p_sw_x, p_sw_y], rtol=1e-12)
    r_st = np.array([1.0, 0.5, H]) - np.array([0.03, -0.1, H])
    np.testing.assert_allclose(
        out.swing_target_world_m, [r_st[0] + px - p_sw_x, r_st[1] + py - p_sw_y, 0.0], atol=1e-12
    )
    assert out.s == pytest.approx(0.1 / T) and out.t_remaining_s == pytest.approx(t_rem)
    assert out.h_d.shape == out.dh_d.shape == out.ddh_d.shape == (9,)
    assert p.output_names[5] == "com_x_over_swing" and p.n_outputs == 9


def test_end_of_step_speed_reference_is_the_papers_L_des():
    out = started(speed_reference="end_of_step").update(est(), cmd(vy_mps=0.0, step_width_m=0.0))
    np.testing.assert_allclose(out.L_des_Nms, [0.0, M * H * 0.5], atol=1e-12)


def test_injected_kernels_receive_the_dense_layouts_and_outputs_are_unpacked():
    seen = {}

    def plan_fn(u):
        seen["plan"] = np.array(u)
        return np.arange(8.0)

    def reference_fn(u):
        seen["ref"] = np.array(u)
        return np.arange(30.0)

    p = started(plan_fn=plan_fn, reference_fn=reference_fn)
    e = est()
    out = p.update(e, cmd(turn_rate_radps=0.5))
    u = dict(zip(kernels.ALIP_PLAN_INPUTS, seen["plan"]))
    assert u["p_st_x"] == 0.03 and u["p_st_y"] == -0.1 and u["L_x"] == 1.5 and u["L_y"] == 12.0
    assert u["t_rem"] == pytest.approx(0.2) and u["v_z"] == 0.05 and u["next_stance_sign"] == -1.0
    assert u["vx_des"] == pytest.approx(desired.end_of_step_velocity(0.5, T, H, G))
    assert u["heading_next"] == pytest.approx(0.15) and (u["m"], u["H"], u["T"], u["W"], u["g"]) == (M, H, T, 0.2, G)
    np.testing.assert_allclose(out.L_hat_Nms, [0, 1])
    np.testing.assert_allclose(out.p_hat_m, [2, 3])
    np.testing.assert_allclose(out.L_des_Nms, [4, 5])
    np.testing.assert_allclose(out.p_sw_des_world_m, [6, 7])
    np.testing.assert_allclose(out.h_d, np.arange(9.0))
    np.testing.assert_allclose(out.ddh_d, np.arange(20.0, 29.0))
    r = dict(zip(kernels.SWING_REFERENCE_INPUTS, seen["ref"]))
    assert (r["stance_yaw0"], r["swing_yaw0"], r["x0"], r["y0"]) == (0.03, -0.04, -0.15, 0.12)
    assert (r["p_sw_des_x"], r["p_sw_des_y"], r["dD"]) == (6.0, 7.0, pytest.approx(0.15))
    np.testing.assert_allclose(out.swing_target_world_m, [1.0 - 0.03 + 2 - 6, 0.5 + 0.1 + 3 - 7, 0.0])


def test_heading_advances_at_start_step_and_targets_are_in_the_step_frame():
    p = Planner(OUT3, M, G, heading_rad=0.4)
    p.start_step("left", 0.0, H0)
    c = cmd(turn_rate_radps=1.0)
    out = p.update(est(t_in_step_s=T), c)
    assert out.heading_rad == 0.4 and out.heading_next_rad == pytest.approx(0.4 + T)
    assert out.turn_rad == pytest.approx(T)
    assert p.heading_next_rad == pytest.approx(0.4 + T)
    # At s = 1: hip yaws at -+dD/2 and the swing targets are p_sw_des rotated into D_k.
    assert out.h_d[2] == pytest.approx(-T / 2) and out.h_d[3] == pytest.approx(T / 2)
    c4, s4 = math.cos(0.4), math.sin(0.4)
    x, y = out.p_sw_des_world_m
    np.testing.assert_allclose(out.p_sw_des_heading_m, [c4 * x + s4 * y, -s4 * x + c4 * y], atol=1e-12)
    np.testing.assert_allclose(out.h_d[5:7], out.p_sw_des_heading_m, atol=1e-12)
    p.start_step("right", T, H0)
    assert p.heading_rad == pytest.approx(0.4 + T) and p.step_count == 2 and p.stance == "right"
    p.start_step("left", 2 * T, H0, heading_rad=-1.0)
    assert p.heading_rad == -1.0
    assert p.clock.t_start_s == pytest.approx(2 * T) and p.clock.time_in_step(2 * T + 0.05) == pytest.approx(0.05)


def test_the_planner_starts_its_steps_on_the_clock_it_is_given():
    """One step clock: the planner keeps no stance or step start of its own."""
    clock = StepClock()
    p = Planner(OUT3, M, G, clock=clock)
    assert p.clock is clock and p.stance is None
    p.start_step("right", 1.5, H0)
    assert (clock.stance, clock.t_start_s) == ("right", 1.5) and p.stance == "right"
    # The turn-rate integral runs on the clock's step start: 0.1 s into the step at 1 rad/s.
    out = p.update(est(stance="right", t_in_step_s=0.1), cmd(turn_rate_radps=1.0))
    assert out.heading_next_rad == pytest.approx(0.1 + (T - 0.1))
    p.reset()
    assert clock.stance is None and clock.t_start_s == 0.0
    assert Planner(OUT3, M).clock is not Planner(OUT3, M).clock


@pytest.mark.parametrize("early", [0.9, 1.0, 1.07])
def test_a_turn_command_turns_by_its_time_integral_whatever_the_step_timing(early):
    """Steps that end early (or late) must not add or lose heading: after the
    command stops, the heading is the integral of the commanded rate (a per-step
    increment of rate * T would give n_steps * rate * T instead)."""
    p = Planner(OUT3, M, G, heading_rad=0.2)
    dt, rate, t_turn_end = 0.0005, 0.6, 1.234
    stance, t_start = "left", 0.0
    p.start_step(stance, t_start, H0)
    for i in range(1, int(3.0 / dt)):
        t = i * dt
        if t - t_start >= early * T:  # touchdown
            stance, t_start = ("right" if stance == "left" else "left"), t
            p.start_step(stance, t_start, H0)
        c = cmd(turn_rate_radps=rate if t < t_turn_end else 0.0)
        out = p.update(est(t_in_step_s=t - t_start, stance=stance), c)
    # The rate commanded at a tick holds until the next one (the first update's
    # rate holds from the step start, t = 0): ticks 0, dt, ... before t_turn_end.
    n_ticks = sum(1 for i in range(int(3.0 / dt)) if i * dt < t_turn_end)
    turned = rate * n_ticks * dt
    assert out.heading_next_rad == pytest.approx(0.2 + turned, abs=1e-9)
    assert p.heading_rad == pytest.approx(0.2 + turned, abs=1e-9)


def test_reset_starts_a_new_walk_and_a_new_turn_integral():
    p = Planner(OUT3, M, G)
    p.start_step("left", 5.0, H0)
    p.update(est(t_in_step_s=0.2), cmd(turn_rate_radps=1.0))
    p.start_step("right", 5.3, H0)
    assert p.heading_rad == pytest.approx(0.3) and p.step_count == 2
    p.reset(heading_rad=0.1)
    assert (p.heading_rad, p.heading_next_rad, p.step_count, p.stance) == (0.1, 0.1, 0, None)
    # A new run from t = 0: the integral restarts (times before the old run's are not skipped).
    p.start_step("left", 0.0, H0)
    out = p.update(est(t_in_step_s=0.1), cmd(turn_rate_radps=1.0))
    assert out.heading_next_rad == pytest.approx(0.1 + T)
    with pytest.raises(InputError):
        p.reset(heading_rad=float("nan"))


def test_start_of_step_references_equal_the_measured_outputs():
    out = started().update(est(t_in_step_s=0.0), cmd())
    np.testing.assert_allclose(out.h_d[[2, 3, 5, 6]], H0[[2, 3, 5, 6]], atol=1e-15)
    np.testing.assert_allclose(out.h_d[[0, 1, 4, 7, 8]], [0, 0, H, H, 0], atol=1e-15)


def test_late_touchdown_holds_phase_and_horizon():
    out = started().update(est(t_in_step_s=T + 0.07), cmd())
    assert out.s == 1.0 and out.t_remaining_s == 0.0
    np.testing.assert_allclose(out.p_hat_m, [0.03, -0.1], atol=1e-15)
    np.testing.assert_allclose(out.dh_d[5:7], 0.0, atol=1e-12)


def test_vz_clamp_and_switch():
    limit = lip.vz_limit(T, H, G)
    out = started().update(est(v_z_mps=5.0), cmd())
    assert out.v_z_used_mps == pytest.approx(0.5 * limit) and np.all(np.isfinite(out.p_sw_des_world_m))
    out = started().update(est(v_z_mps=-5.0), cmd())
    assert out.v_z_used_mps == pytest.approx(-0.5 * limit)
    out0 = started(vz_correction=False).update(est(v_z_mps=0.3), cmd())
    ref = started().update(est(v_z_mps=0.0), cmd())
    assert out0.v_z_used_mps == 0.0
    np.testing.assert_allclose(out0.p_sw_des_world_m, ref.p_sw_des_world_m, atol=1e-15)


def test_rabbit_ignores_lateral_terms():
    h0 = np.array([0.02, 0.9, -0.15, 0.88])
    p = Planner(OUT2, 32.0, G, heading_rad=1.0)
    p.start_step("left", 0.0, h0, heading_rad=0.7)
    out = p.update(est(), cmd(turn_rate_radps=2.0, vy_mps=0.4, step_width_m=0.3))
    assert p.output_names == ("torso_pitch", "com_z_over_stance", "com_x_over_swing", "com_z_over_swing")
    assert out.h_d.shape == (4,) and out.heading_rad == 0.0 and out.heading_next_rad == 0.0
    assert (
        out.L_hat_Nms[0] == 0.0 and out.p_hat_m[1] == 0.0 and out.L_des_Nms[0] == 0.0 and out.p_sw_des_world_m[1] == 0.0
    )
    _, Ly = lip.predict_end_of_step(0.03, 12.0, T - 0.1, 32.0, H, G)
    assert out.L_hat_Nms[1] == pytest.approx(Ly, rel=1e-12)
    s = 0.1 / T
    np.testing.assert_allclose(out.h_d[[0, 1, 3]], [0.0, H, 4 * 0.1 * (s - 0.5) ** 2 + H - 0.1], atol=1e-12)
    blend = 0.5 * ((1 + math.cos(math.pi * s)) * -0.15 + (1 - math.cos(math.pi * s)) * out.p_sw_des_world_m[0])
    assert out.h_d[2] == pytest.approx(blend, abs=1e-12)


def test_bad_planner_use_raises_input_error():
    with pytest.raises(InputError, match="unknown output 'atlas'"):
        Planner((*OUT3, "atlas"), M)
    with pytest.raises(InputError, match="a sequence of output names"):
        Planner("torso_pitch", M)
    with pytest.raises(InputError, match="must include com_x_over_swing"):
        Planner(("torso_pitch", "com_z_over_stance", "com_z_over_swing"), M)
    with pytest.raises(InputError, match="planar robot has no lateral output: drop torso_roll"):
        Planner((*OUT2, "torso_roll"), M)
    with pytest.raises(InputError, match="mass_kg must be > 0"):
        Planner(OUT3, 0.0)
    with pytest.raises(InputError, match="mass_kg must be finite"):
        Planner(OUT3, float("nan"))
    with pytest.raises(InputError, match=r"g \(gravity magnitude\) must be > 0"):
        Planner(OUT3, M, g=-9.81)
    with pytest.raises(InputError, match="speed_reference must be one of"):
        Planner(OUT3, M, speed_reference="avg")
    with pytest.raises(InputError, match="plan_fn must be callable"):
        Planner(OUT3, M, plan_fn=3)
    with pytest.raises(InputError, match="clock must be a StepClock, got str"):
        Planner(OUT3, M, clock="left")
    p = Planner(OUT3, M)
    with pytest.raises(InputError, match="before start_step"):
        p.update(est(), cmd())
    with pytest.raises(InputError, match="stance must be 'left' or 'right'"):
        p.start_step("up", 0.0, H0)
    with pytest.raises(InputError, match=r"h0_start must have shape \(9,\)"):
        p.start_step("left", 0.0, H0[:4])
    with pytest.raises(InputError, match="h0_start must be finite"):
        p.start_step("left", 0.0, np.full(9, np.nan))
    with pytest.raises(InputError, match="t_start_s must be finite"):
        p.start_step("left", np.nan, H0)
    p.start_step("left", 0.0, H0)
    with pytest.raises(InputError, match="estimate.stance='right' but the current step has stance 'left'"):
        p.update(est(stance="right"), cmd())
    with pytest.raises(InputError, match="needs a StateEstimate and a Command"):
        p.update(est(), {"vx_mps": 1.0})


def test_outputs_are_independent_of_the_kernels_shared_buffers():
    """The generated kernels return one shared output buffer; each PlannerOutput owns its data."""
    shared8, shared30 = np.zeros(8), np.zeros(30)

    def plan_fn(u):
        shared8[:] = kernels.alip_plan(u)
        return shared8

    def reference_fn(u):
        shared30[:] = kernels.swing_reference(u)
        return shared30

    p = started(plan_fn=plan_fn, reference_fn=reference_fn)
    first = p.update(est(), cmd())
    fields = ("L_hat_Nms", "p_hat_m", "L_des_Nms", "p_sw_des_world_m", "h_d", "dh_d", "ddh_d")
    kept = {k: np.array(getattr(first, k)) for k in fields}
    p.update(est(t_in_step_s=0.2, L_Nms=[-3.0, 5.0, 0.0]), cmd(vx_mps=-0.4))
    for k, value in kept.items():
        np.testing.assert_array_equal(getattr(first, k), value)
        assert not np.shares_memory(getattr(first, k), shared8) and not np.shares_memory(getattr(first, k), shared30)


def test_kernels_with_the_wrong_output_size_are_input_errors():
    with pytest.raises(InputError, match="plan_fn returned 7 values"):
        started(plan_fn=lambda u: np.zeros(7)).update(est(), cmd())
    with pytest.raises(InputError, match="reference_fn returned 20 values"):
        started(reference_fn=lambda u: np.zeros(20)).update(est(), cmd())


def _same_bits(a, b):
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    return np.array_equal(a, b) and np.array_equal(np.signbit(a), np.signbit(b))


@pytest.mark.parametrize("robot, h0", [(OUT3, H0), (OUT2, np.array([0.02, 0.9, -0.15, 0.88]))])
def test_no_terrain_and_flat_terrain_give_the_same_bits(robot, h0):
    from amlip_qp.messages import TerrainPrediction

    for t_in in (0.0, 0.13, T, T + 0.05):
        a = started(robot, h0).update(est(t_in_step_s=t_in), cmd())
        b = started(robot, h0).update(est(t_in_step_s=t_in), cmd(), TerrainPrediction())
        for f in PlannerOutput.__slots__:
            assert _same_bits(getattr(a, f), getattr(b, f)), f


def test_terrain_reaches_the_kernels_and_the_swing_target():
    from amlip_qp.messages import TerrainPrediction

    seen = {}

    def plan_fn(u):
        seen["plan"] = np.array(u)
        return kernels.alip_plan(u)

    def reference_fn(u):
        seen["ref"] = np.array(u)
        return kernels.swing_reference(u)

    terrain = TerrainPrediction(dz_next_m=0.09, dz_sw_m=0.1, dz_sw0_m=-0.05, slope_pitch_rad=-0.2, slope_pitch0_rad=0.1)
    p = started(plan_fn=plan_fn, reference_fn=reference_fn)
    out = p.update(est(), cmd(), terrain)
    assert dict(zip(kernels.ALIP_PLAN_INPUTS, seen["plan"]))["dz_next"] == 0.09
    r = dict(zip(kernels.SWING_REFERENCE_INPUTS, seen["ref"]))
    assert (r["dz_sw0"], r["dz_sw"], r["slope_pitch0"], r["slope_pitch"]) == (-0.05, 0.1, 0.1, -0.2)
    flat = started().update(est(), cmd())
    stance_z = 0.0  # est(): com z = H, p_st z = H
    assert out.swing_target_world_m[2] == pytest.approx(stance_z + 0.1)
    # Stepping up: the placement with the height transfer differs from the flat one (the v_z law is unchanged).
    assert not np.allclose(out.p_sw_des_world_m, flat.p_sw_des_world_m, atol=1e-4)
    rabbit = Planner(OUT2, 32.0, G)
    rabbit.start_step("left", 0.0, np.array([0.02, 0.9, -0.15, 0.88]))
    h_end = rabbit.update(est(t_in_step_s=T), cmd(), terrain).h_d
    assert h_end[3] == pytest.approx(H - 0.1)  # CoM over swing ends at H - dz_sw


def test_late_descent_continues_the_swing_foot_down():
    base = started().update(est(t_in_step_s=T), cmd())
    i = 7  # com_z_over_swing
    landing = base.dh_d[i]
    assert landing > 0.0  # the foot descends at touchdown
    late = started(late_descent="landing").update(est(t_in_step_s=T + 0.04), cmd())
    assert late.h_d[i] == pytest.approx(base.h_d[i] + 0.04 * landing, abs=1e-12)
    assert late.dh_d[i] == pytest.approx(landing) and late.ddh_d[i] == 0.0
    fixed = started(late_descent=0.4).update(est(t_in_step_s=T + 0.05), cmd())
    assert fixed.h_d[i] == pytest.approx(base.h_d[i] + 0.02, abs=1e-12) and fixed.dh_d[i] == 0.4
    others = [k for k in range(9) if k != i]
    np.testing.assert_array_equal(fixed.h_d[others], base.h_d[others])
    held = started().update(est(t_in_step_s=T + 0.05), cmd())  # default: hold
    assert held.h_d[i] == base.h_d[i]
    on_time = started(late_descent=0.4).update(est(t_in_step_s=0.1), cmd())
    assert _same_bits(on_time.h_d, started().update(est(t_in_step_s=0.1), cmd()).h_d)


def test_bad_terrain_raises_input_error():
    from amlip_qp.messages import TerrainPrediction

    with pytest.raises(InputError, match="terrain must be a TerrainPrediction or None, got dict"):
        started().update(est(), cmd(), {"dz_next_m": 0.1})
    with pytest.raises(InputError, match=r"terrain.dz_next_m=0.95 m must be smaller in size than H"):
        started().update(est(), cmd(), TerrainPrediction(dz_next_m=0.95))
    with pytest.raises(InputError, match="swing foot path too high"):
        started().update(est(), cmd(), TerrainPrediction(dz_sw_m=0.85))
    for bad in ("up", -0.1, 0.0, True):
        with pytest.raises(InputError, match="late_descent"):
            Planner(OUT3, M, late_descent=bad)


def test_a_foothold_hook_moves_the_swing_target_and_the_placement():
    from amlip_qp.messages import TerrainPrediction

    terrain = TerrainPrediction(dz_next_m=0.1, dz_sw_m=0.1)
    free = started().update(est(t_in_step_s=0.1), cmd(), terrain)
    seen = []

    def keep(x, y, heading, s):
        seen.append((x, y, heading, s))
        return x, y

    kept = started().update(est(t_in_step_s=0.1), cmd(), terrain, keep)
    # the hook gets the law's target, the next heading and the phase; returning it changes no bit
    assert seen == [(*free.swing_target_world_m[:2].tolist(), free.heading_next_rad, pytest.approx(0.1 / T))]
    for f in PlannerOutput.__slots__:
        assert _same_bits(getattr(free, f), getattr(kept, f)), f
    moved = started().update(est(t_in_step_s=0.1), cmd(), terrain, lambda x, y, h, s: (x - 0.07, y + 0.01))
    assert moved.swing_target_world_m[:2] - free.swing_target_world_m[:2] == pytest.approx([-0.07, 0.01])
    # p_sw (CoM minus swing contact at touchdown) moves the other way, in world and heading axes
    assert moved.p_sw_des_world_m - free.p_sw_des_world_m == pytest.approx([0.07, -0.01])
    assert moved.p_sw_des_heading_m - free.p_sw_des_heading_m == pytest.approx([0.07, -0.01])
    i = started().output_names.index("com_x_over_swing")
    assert moved.h_d[i] > free.h_d[i]  # the swing foot aims shorter


def test_a_foothold_hook_that_is_not_one_is_refused_with_the_reason():
    from amlip_qp.messages import TerrainPrediction

    terrain = TerrainPrediction(dz_next_m=0.1, dz_sw_m=0.1)
    bad_hooks = {
        "must be a function": "left",
        "must return two numbers": lambda x, y, h, s: (x,),
        "non-finite foothold": lambda x, y, h, s: (x, math.nan),
    }
    for reason, hook in bad_hooks.items():
        with pytest.raises(InputError, match=reason):
            started().update(est(t_in_step_s=0.1), cmd(), terrain, hook)
