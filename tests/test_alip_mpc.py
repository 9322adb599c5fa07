"""The step-timing MPC (amlip_qp.alip.step_mpc, amlip_qp.alip.mpc_planner) on the point-mass ALIP.

Undisturbed, its minimum is the one-step deadbeat law's step at the nominal duration; pushed
beyond what a reach-limited one-step law with a fixed step time recovers from, it recovers by
shortening steps and spreading the correction over the horizon.
"""

import math

import numpy as np
import pytest

from alip_cases import OUT3, cmd, est
from alip_point_mass import LAM, OUTPUTS, REACH_M, G, H, M, T, Walk, reach_clip_hook
from amlip_qp.alip import Planner, StepClock
from amlip_qp.alip import step_mpc as S
from amlip_qp.alip.mpc_planner import MPCPlanner, MPCSettings
from amlip_qp.alip.step_timing import StepTiming
from amlip_qp.exceptions import InputError, QPError
from amlip_qp.messages import Command
from amlip_qp.qp.small_qp import SmallQPSolver

COMMAND = Command(step_time_s=T, com_height_m=H, clearance_m=0.1, vx_mps=0.5, step_width_m=0.25)
SETTINGS = MPCSettings()
assert REACH_M == (SETTINGS.reach_x * H, SETTINGS.reach_out * H)


def mpc_planner(**kw):
    return MPCPlanner(OUTPUTS, M, SmallQPSolver(S.N_VAR, S.N_ROWS, S.SOFT_ROWS), G, **kw)


def test_qp_minimum_is_the_one_step_law_at_the_nominal_time():
    """One tick from the shared planner case: the QP's first step is the law's target, sigma = exp(l (T - t))."""
    one, mpc = Planner(OUT3, 31.0), MPCPlanner(OUT3, 31.0, SmallQPSolver(S.N_VAR, S.N_ROWS, S.SOFT_ROWS))
    for p in (one, mpc):
        p.start_step("left", 0.0, np.zeros(9))
    c, e = cmd(step_time_s=0.3, com_height_m=0.9), est(v_z_mps=0.05, t_in_step_s=0.1)
    a, b = one.update(e, c), mpc.update(e, c)
    np.testing.assert_allclose(b.swing_target_world_m, a.swing_target_world_m, atol=1e-10)
    np.testing.assert_allclose(b.p_sw_des_world_m, a.p_sw_des_world_m, atol=1e-10)
    assert mpc.last_plan.step_time_s == 0.3 and mpc.clock.step_time_s(0.3) == 0.3  # nominal: exactly T


def test_undisturbed_walk_reproduces_the_one_step_law():
    one = Walk(Planner(OUTPUTS, M, G), COMMAND).run(2.4)
    mpc = Walk(mpc_planner(), COMMAND).run(2.4)
    assert len(one.steps) == len(mpc.steps) == 8
    for a, b in zip(one.steps, mpc.steps):
        assert b[1] - b[0] == a[1] - a[0] == pytest.approx(T, abs=1e-9)  # the nominal step time, tick for tick
        np.testing.assert_allclose(b[2], a[2], atol=1e-10)  # the same footholds
    assert mpc.planner.failures == 0
    # and the walk is the commanded one: the last stride's mean forward speed is 0.5 m/s
    (_, t0, _, _, c0, _), (_, t1, _, _, c1, _) = mpc.steps[-3], mpc.steps[-1]
    assert (c1[0] - c0[0]) / (t1 - t0) == pytest.approx(0.5, abs=1e-6)


PUSH = (0.95, np.array([2.6, 0.0]))  # 0.05 s into the fourth step, +2.6 m/s forward


def test_push_that_the_reach_limited_one_step_law_cannot_recover_from():
    one = Walk(Planner(OUTPUTS, M, G), COMMAND, reach_m=REACH_M)
    one.hook = reach_clip_hook(one, REACH_M)
    one.run(3.0, push=PUSH)
    assert one.fell and one.t_s < 2.5
    # after the push every step of the law is at the reach limit (it wanted more)
    assert all(abs(s[2][0] - s[4][0]) == pytest.approx(REACH_M[0], abs=1e-9) for s in one.steps[4:])

    mpc = Walk(mpc_planner(), COMMAND, reach_m=REACH_M).run(3.0, push=PUSH)
    assert not mpc.fell
    durations = [t1 - t0 for t0, t1, *_ in mpc.steps]
    # the pushed step and the next ones are shortened to the bound 0.6 T, then back to T
    assert durations[3] == pytest.approx(0.6 * T, abs=1e-9)
    assert durations[-1] == pytest.approx(T, abs=1e-9)
    assert max(s[3] for s in mpc.steps) < 1e-4  # every foothold within reach (to the 2 ms tick)
    assert mpc.planner.failures == 0
    # back on the commanded gait: the end-of-step velocity is the undisturbed walk's (the lateral
    # one up to its sign, which alternates with the stance leg)
    calm = Walk(mpc_planner(), COMMAND).run(3.0)
    np.testing.assert_allclose(np.abs(mpc.steps[-1][5]), np.abs(calm.steps[-1][5]), atol=1e-3)


def test_a_shortest_step_in_seconds_bounds_the_shortened_steps_and_never_lengthens_the_nominal_one():
    """``step_time_min_s`` (a tracker's shortest step): the pushed steps end at it, not at 0.6 T; above T
    it does not lengthen the undisturbed steps."""
    bounded = Walk(mpc_planner(settings=MPCSettings(step_time_min_s=0.25)), COMMAND, reach_m=REACH_M)
    bounded.run(1.6, push=PUSH)
    durations = [t1 - t0 for t0, t1, *_ in bounded.steps]
    assert durations[3] == pytest.approx(0.25, abs=1e-9)  # the pushed step: at the bound, not 0.6 T = 0.18 s
    assert min(durations) == pytest.approx(0.25, abs=1e-9)
    one = Walk(Planner(OUTPUTS, M, G), COMMAND).run(2.4)
    above_T = Walk(mpc_planner(settings=MPCSettings(step_time_min_s=0.5)), COMMAND).run(2.4)
    assert len(above_T.steps) == len(one.steps) == 8
    for a, b in zip(one.steps, above_T.steps):
        assert b[1] - b[0] == a[1] - a[0] == pytest.approx(T, abs=1e-9)
        np.testing.assert_allclose(b[2], a[2], atol=1e-10)


#: The lateral limits the MPC had before crossover steps (docs/TUNING.md, "The step-timing MPC"):
#: the feet 0.05 H apart at least, the landing foot 0.1 H inside and 0.5 H outside the CoM, steps of 0.75 H.
NO_CROSSING = MPCSettings(width_min=0.05, reach_in=0.1, reach_out=0.5, step_out=0.75)
#: 0.05 s into the fourth step (right stance, the left foot swinging), 2 m/s to the right.
LATERAL_PUSH = (0.95, np.array([0.0, -2.0]))


def test_lateral_push_towards_the_stance_foot_is_recovered_with_a_crossover_step():
    """Pushed towards its stance side, the swing foot can catch the CoM only by crossing the stance foot."""
    old = Walk(mpc_planner(settings=NO_CROSSING), COMMAND, reach_m=(0.55 * H, 0.5 * H)).run(4.0, push=LATERAL_PUSH)
    assert old.fell  # the law's own step would cross: without it the MPC falls (its largest push here: 1.13 m/s)
    mpc = Walk(mpc_planner(), COMMAND, reach_m=REACH_M).run(4.0, push=LATERAL_PUSH)
    assert not mpc.fell and mpc.planner.failures == 0
    assert max(s[3] for s in mpc.steps) < 1e-3  # every foothold within reach (to the 2 ms tick)
    # the pushed step's left foot lands right of the right stance foot: a crossover step
    (_, _, r_right, *_), (_, _, r_left, *_) = mpc.steps[2], mpc.steps[3]
    assert r_left[1] < r_right[1] - 0.05
    # back on the commanded gait within 3 s of the push
    calm = Walk(mpc_planner(), COMMAND).run(4.0)
    np.testing.assert_allclose(np.abs(mpc.steps[-1][5]), np.abs(calm.steps[-1][5]), atol=0.02)


def test_foothold_region_is_respected():
    """A box that excludes the law's first foothold: the MPC lands in it, at the box's edge."""
    probe = MPCPlanner(OUT3, 31.0, SmallQPSolver(S.N_VAR, S.N_ROWS, S.SOFT_ROWS))
    probe.start_step("left", 0.0, np.zeros(9))
    c, e = cmd(step_time_s=0.3, com_height_m=0.9, vy_mps=0.0), est(t_in_step_s=0.05, v_z_mps=0.0)
    free = probe.update(e, c).swing_target_world_m
    x_hi = free[0] - 0.08
    far = (-1e3, 1e3, -1e3, 1e3, 0.0)
    probe.start_step("left", 0.0, np.zeros(9))
    out = probe.update(e, c, regions=[(x_hi - 0.3, x_hi, -1e3, 1e3, 0.0), far, far, far])
    assert out.swing_target_world_m[0] == pytest.approx(x_hi, abs=1e-6)
    assert probe.last_plan.solved


def _qp_inputs(**vals) -> np.ndarray:
    """MPC_QP's inputs: ``vals`` by name, no foothold boxes, the rest 0."""
    names = S.MPC_QP_INPUTS
    u = np.zeros(len(names))
    for k, v in vals.items():
        u[names.index(k)] = v
    u[names.index("x_lo_1") :: 4] = -S.NO_BOUND
    u[names.index("x_hi_1") :: 4] = S.NO_BOUND
    u[names.index("y_lo_1") :: 4] = -S.NO_BOUND
    u[names.index("y_hi_1") :: 4] = S.NO_BOUND
    return u


LINEARISED = dict(p_st_x=0.05, p_st_y=-0.1, L_x=1.5, L_y=20.0, m=M, H=H, T=T, W=0.2, g=G, next_stance_sign=1.0,
                  tau_nom=0.2, tau_lo=0.1, tau_hi=0.3, tau_bar=0.17, reach_x=1.0, reach_out=1.0, reach_in=1.0,
                  step_x=1.0, width_min=0.0, step_out=1.0, w_time=0.0, w_terminal=1.0, T_lo=0.6 * T, w_time_later=0.0,
                  T_hi=1.4 * T)  # fmt: skip


def test_linearisation_is_exact_at_its_point():
    """The QP's affine prediction of the CoM over the next foot at sigma = sigma_bar equals the flow."""
    u = _qp_inputs(**LINEARISED, **{f"T_bar_{j}": T for j in range(1, S.MPC_STEPS + 1)})
    Hq, g, Cq, lower, upper = S.split_qp(S.mpc_qp(u))
    lb, hi, ub = lower[: S.N_VAR], upper[S.N_VAR :], upper[: S.N_VAR]
    # row 0 is p_sw,x of touchdown 1 in the heading frame (heading 0) minus d_1x: at d = 0 and
    # sigma = sigma_bar, C x + (the constant moved into the bounds) = p(T-) from the flow
    sigma = math.exp(LAM * 0.17)
    x = np.zeros(S.N_VAR)
    x[0] = sigma
    p_end = math.cosh(LAM * 0.17) * 0.05 + math.sinh(LAM * 0.17) / (M * H * LAM) * 20.0
    assert Cq[0] @ x + (1.0 - hi[0]) == pytest.approx(p_end, abs=1e-12)  # reach_x = 1 bound
    assert lb[0] == pytest.approx(math.exp(LAM * 0.1)) and ub[0] == pytest.approx(math.exp(LAM * 0.3))
    assert lb[S.I_SIGMA_LATER] == pytest.approx(math.exp(LAM * 0.6 * T))
    assert ub[-1] == pytest.approx(math.exp(LAM * 1.4 * T))
    np.testing.assert_allclose(Hq, Hq.T, atol=1e-12)
    # the steps' block is positive definite (the L errors); the later durations' needs w_time > 0
    steps = slice(1, S.I_SIGMA_LATER)
    assert np.all(np.linalg.eigvalsh(Hq[steps, steps]) > 0.0)


def _touchdown_2_prediction(T_1: float, d_1x: float) -> tuple[float, float]:
    """(the QP's p(T_2-) - d_2x at d_2 = 0, the flow's) after the current step of 0.17 s at its
    linearisation point, touchdown 1 with the step (d_1x, 0.1) and a step of duration ``T_1``,
    the QP linearised about T_bar_1 = 0.25 s and d_bar_1 = (0.2, 0.1)."""
    u = _qp_inputs(**LINEARISED, T_bar_1=0.25, d_bar_x_1=0.2, d_bar_y_1=0.1,
                   **{f"T_bar_{j}": T for j in range(2, S.MPC_STEPS + 1)})  # fmt: skip
    _, _, Cq, _, upper = S.split_qp(S.mpc_qp(u))
    x = np.zeros(S.N_VAR)
    x[0], x[1], x[2], x[S.I_SIGMA_LATER] = math.exp(LAM * 0.17), d_1x, 0.1, math.exp(LAM * T_1)
    c, s_ = math.cosh(LAM * 0.17), math.sinh(LAM * 0.17)
    p1 = c * 0.05 + s_ / (M * H * LAM) * 20.0 - d_1x  # after touchdown 1 (v_z = 0, flat)
    L1 = M * H * LAM * s_ * 0.05 + c * 20.0
    p2 = math.cosh(LAM * T_1) * p1 + math.sinh(LAM * T_1) / (M * H * LAM) * L1
    row = S.ROWS_PER_STEP  # touchdown 2's reach row: p_sw,x = p(T_2-) - d_2x (reach_x = 1)
    return float(Cq[row] @ x + (1.0 - upper[S.N_VAR + row])), p2


def test_later_step_linearisation_is_exact_at_its_duration_and_second_order_about_it():
    """A later step's flow: exact where sigma_1 = sigma_bar_1, whatever the steps; at the last
    plan's steps its error is second order in the duration's change."""
    for d_1x in (0.2, 0.31, -0.1):
        got, want = _touchdown_2_prediction(0.25, d_1x)
        assert got == pytest.approx(want, abs=1e-12)
    errors = [abs(np.subtract(*_touchdown_2_prediction(0.25 + dt, 0.2))) for dt in (0.04, 0.02)]
    assert errors[0] > 1e-6 and errors[0] / errors[1] == pytest.approx(4.0, rel=0.1)


def test_a_late_step_keeps_its_planned_duration():
    """After the planned end the duration stays (the phase holds at 1, the touchdown test sees it late)."""
    p = MPCPlanner(OUT3, 31.0, SmallQPSolver(S.N_VAR, S.N_ROWS, S.SOFT_ROWS))
    p.start_step("left", 0.0, np.zeros(9))
    c = cmd(step_time_s=0.3, com_height_m=0.9)
    p.update(est(t_in_step_s=0.1), c)
    assert p.last_plan.step_time_s == pytest.approx(0.3, abs=1e-12)
    for t_in in (0.29, 0.31, 0.4):
        out = p.update(est(t_in_step_s=t_in), c)
        assert (
            p.last_plan.step_time_s == pytest.approx(0.3, abs=1e-12)
            and p.clock.step_time_s(c.step_time_s) == p.last_plan.step_time_s
        )
    assert out.s == 1.0 and out.t_remaining_s == 0.0
    assert p.clock.phase_unclipped(0.4, p.clock.step_time_s(0.3)) == pytest.approx(0.4 / 0.3)


def test_step_clock_takes_a_planned_duration():
    clock = StepClock()
    clock.start("left", 1.0)
    assert clock.step_time_s(0.3) == 0.3 and clock.planned_step_time_s is None
    clock.plan_step_time(0.25)
    assert clock.step_time_s(0.3) == 0.25
    clock.start("right", 1.25)
    assert clock.step_time_s(0.3) == 0.3
    for bad in (0.0, -1.0, math.inf, math.nan, "0.3", True):
        with pytest.raises(InputError, match="planned step time"):
            clock.plan_step_time(bad)


@pytest.mark.parametrize(
    "kw, match",
    [
        (dict(step_time_min=0.0), "step_time_min"),
        (dict(step_time_min=1.2, step_time_max=1.0), "step_time_max"),
        (dict(step_time_min_s=-0.1), "step_time_min_s"),
        (dict(step_time_min_s=math.inf), "step_time_min_s"),
        (dict(width_min=math.nan), "width_min"),
        (dict(step_out=0.01, width_min=0.05), "step_out"),
        (dict(iterations=0), "iterations"),
        (dict(weight_time=math.nan), "weight_time"),
    ],
)
def test_bad_settings_raise(kw, match):
    with pytest.raises(InputError, match=match):
        MPCSettings(**kw)


def test_bad_planner_arguments_raise():
    with pytest.raises(InputError, match="solve_fn"):
        MPCPlanner(OUT3, 31.0, None)
    p = MPCPlanner(OUT3, 31.0, SmallQPSolver(S.N_VAR, S.N_ROWS))
    p.start_step("left", 0.0, np.zeros(9))
    with pytest.raises(InputError, match="regions must hold 4"):
        p.update(est(), cmd(), regions=[(0, 1, 0, 1, 0)])
    with pytest.raises(InputError, match="x_lo <= x_hi"):
        p.update(est(), cmd(), regions=[(1, 0, 0, 1, 0)] * 4)
    with pytest.raises(InputError, match="plans the step's duration itself"):
        p.update(est(), cmd(), timing=StepTiming())


def test_a_failed_solve_falls_back_to_the_one_step_law():
    def failing(*args):
        raise QPError("no")

    one, p = Planner(OUT3, 31.0), MPCPlanner(OUT3, 31.0, failing)
    for q in (one, p):
        q.start_step("left", 0.0, np.zeros(9))
    a, b = one.update(est(), cmd()), p.update(est(), cmd())
    np.testing.assert_array_equal(a.swing_target_world_m, b.swing_target_world_m)
    assert p.failures == 1 and not p.last_plan.solved and p.clock.planned_step_time_s is None
