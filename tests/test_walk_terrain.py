"""Closed-loop acceptance on uneven ground: the QP tracker on Cassie.

Each test is one run of a named terrain scenario (:data:`amlip_qp.sim.scenarios.named.TERRAIN_SCENARIOS`,
with their own durations and speeds): slopes of 10 and 15 degrees up and down at 0.5 m/s
for 15 s, blind and terrain-aware; stairs of 10 cm rise and 30 cm run up and down at 0.4 m/s
(terrain-aware); rough ground of +-4 cm at 0.75 m/s for 20 s (blind); waves 30 cm high with a
4 m wavelength at 0.75 m/s with 20 cm clearance (blind). "Without falling" also means the mean
speed over the last 3 s, horizontal along the heading (the summary's ``mean_velocity``), is within
0.15 m/s of the command. The 22 degree slope and the PBC tracker are reported
(``examples/terrain_table.py``), not required. The stairs are also walked from other starts, and
with 15 cm risers (the 10 cm scenario on ``stairs:0.15:0.3``; by the step-timing MPC too), and the
steeper slopes are walked (``cassie-slope-26-up``, blind, and ``cassie-slope-30-up-aware``).
"""

from __future__ import annotations

import pytest

pytestmark = pytest.mark.slow

#: The scenarios the QP tracker must walk.
REQUIRED = (
    "cassie-slope-10-up",
    "cassie-slope-10-up-aware",
    "cassie-slope-10-down",
    "cassie-slope-10-down-aware",
    "cassie-slope-15-up",
    "cassie-slope-15-up-aware",
    "cassie-slope-15-down",
    "cassie-slope-15-down-aware",
    "cassie-stairs-10cm",
    "cassie-rough-4cm",
    "cassie-waves-30cm",
)
#: Largest |mean speed over the last 3 s - command|, m/s.
SPEED_TOLERANCE_MPS = 0.15


@pytest.mark.parametrize("name", REQUIRED)
def test_qp_walks_the_terrain_at_the_commanded_speed(name):
    from amlip_qp.sim.reports.summary import summarize
    from amlip_qp.sim.scenarios.factory import run_scenario
    from amlip_qp.sim.scenarios.named import SCENARIOS

    scenario = SCENARIOS[name]
    s = summarize(run_scenario(scenario, "qp", log="summary"))
    assert s["terrain"] == scenario.setting.terrain
    assert not s["fell"], f"{name}: fell at {s['fall_time_s']} s"
    assert s["sim_time_s"] == pytest.approx(scenario.duration_s)
    vx, vy = s["mean_velocity"]
    assert abs(vx - scenario.vx.final_mps) <= SPEED_TOLERANCE_MPS, f"{name}: mean speed {vx:.3f} m/s"
    assert abs(vy) <= SPEED_TOLERANCE_MPS, f"{name}: lateral drift {vy:.3f} m/s"
    assert s["fallback_ticks"] == 0


#: Starts of the stairs walk other than the scenario's own: moved forward (world x, m) and raised (m), as
#: ``examples/raised_starts.py --forward 0.04`` (k = 1, 7) and without it (k = 13) make them.
STAIRS_STARTS = ((1 * 0.04, 0.0), (7 * 0.04, 0.0), (0.0, 13 * 1e-12))


@pytest.mark.parametrize(("forward_m", "raised_m"), STAIRS_STARTS)
def test_qp_walks_the_stairs_from_other_starts_with_its_steps_timed(forward_m, raised_m):
    """The stairs from a start that meets the edges with another phase of the gait: no fall, the speed
    within the band, and steps onto a tread further than the law wanted take longer than ``T`` (the step
    timing of a moved foothold, :mod:`amlip_qp.alip.step_timing`)."""
    from amlip_qp.sim.reports.summary import mean_velocity_heading
    from amlip_qp.sim.scenarios.factory import build_simulation
    from amlip_qp.sim.scenarios.named import SCENARIOS

    scenario = SCENARIOS["cassie-stairs-10cm"]
    sim = build_simulation(scenario, "qp")
    sim.data.qpos[0] += forward_m
    sim.data.qpos[2] += raised_m
    res = sim.run(scenario.duration_s, log="summary")
    assert not res.fell, f"fell at {res.fall_time_s} s"
    vx = float(mean_velocity_heading(res, 3.0)[0])
    assert abs(vx - scenario.vx.final_mps) <= SPEED_TOLERANCE_MPS, f"mean speed {vx:.3f} m/s"
    T = 0.3  # Cassie's step time at 0.4 m/s
    durations = [s.t_end_s - s.t_start_s for s in res.steps]
    # with the step time fixed at T (StepTiming(1.0, 1.0)) the scenario's own walk has none over 0.32 s
    assert max(durations) > 1.15 * T


def test_qp_walks_15_cm_stairs_down_as_well_as_up():
    """The stairs with 15 cm risers (``stairs:0.15:0.3``: 4 up, the landing, 3 down), terrain-aware,
    the one-step law: no fall, the speed over the last 3 s within the band of the 0.4 m/s command,
    and the last step ends 3 x 15 cm below the landing, back on the floor. On the way down the CoM
    takes half of each step's drop before the touchdown (``DOWNHILL_COM_SHARE``), so the swing leg
    reaches the next tread; held at ``H`` over the upper tread, it fell there (at 6.69 s)."""
    from dataclasses import replace

    from amlip_qp.sim.reports.summary import mean_velocity_heading
    from amlip_qp.sim.scenarios.factory import build_simulation
    from amlip_qp.sim.scenarios.named import SCENARIOS

    base = SCENARIOS["cassie-stairs-10cm"]
    scenario = base.with_(setting=replace(base.setting, terrain="stairs:0.15:0.3"))
    res = build_simulation(scenario, "qp").run(scenario.duration_s, log="summary")
    assert not res.fell, f"fell at {res.fall_time_s} s"
    assert res.fallback_ticks == 0
    vx = float(mean_velocity_heading(res, 3.0)[0])
    assert abs(vx - scenario.vx.final_mps) <= SPEED_TOLERANCE_MPS, f"mean speed {vx:.3f} m/s"
    landed = [s.swing_actual_m[2] - res.steps[0].swing_actual_m[2] for s in res.steps]  # over the floor
    assert max(landed) == pytest.approx(4 * 0.15, abs=0.03)  # the landing, 4 risers up
    assert landed[-1] == pytest.approx(0.0, abs=0.03)  # back on the floor


def test_the_mpc_walks_15_cm_stairs_with_no_step_shorter_than_t():
    """The step-timing MPC on the 15 cm stairs, terrain-aware: in that mode it plans no step shorter
    than the command's ``T`` (the one-step planner's rule there), so each swing has the time to climb
    its riser. No fall, the speed within the band, up to the landing and back on the floor; with its
    own shortest step, 0.6 ``T``, it shortened steps to 0.10-0.15 s and fell on the way up (6.61 s)."""
    from dataclasses import replace

    from amlip_qp.sim.reports.summary import mean_velocity_heading
    from amlip_qp.sim.scenarios.factory import build_simulation
    from amlip_qp.sim.scenarios.named import SCENARIOS

    base = SCENARIOS["cassie-stairs-10cm"]
    scenario = base.with_(setting=replace(base.setting, terrain="stairs:0.15:0.3"))
    sim = build_simulation(scenario, "qp", planner="mpc")
    assert sim.controller.planner.settings.step_time_min == 1.0
    res = sim.run(scenario.duration_s, log="summary")
    assert not res.fell, f"fell at {res.fall_time_s} s"
    assert res.fallback_ticks == 0
    vx = float(mean_velocity_heading(res, 3.0)[0])
    assert abs(vx - scenario.vx.final_mps) <= SPEED_TOLERANCE_MPS, f"mean speed {vx:.3f} m/s"
    T = 0.3  # Cassie's step time at 0.4 m/s
    assert min(s.t_end_s - s.t_start_s for s in res.steps) > 0.8 * T  # touchdowns may come a little early
    landed = [s.swing_actual_m[2] - res.steps[0].swing_actual_m[2] for s in res.steps]
    assert max(landed) == pytest.approx(4 * 0.15, abs=0.04)
    assert landed[-1] == pytest.approx(0.0, abs=0.03)


@pytest.mark.parametrize(("name", "degrees"), [("cassie-slope-26-up", 26.0), ("cassie-slope-30-up-aware", 30.0)])
def test_qp_walks_up_steep_slopes_with_the_com_parallel_to_the_ground(name, degrees):
    """26 degrees blind and 30 degrees terrain-aware, 15 s at 0.5 m/s, the CoM rising over each step at
    the step's own rise (``formulas.com_rise``). No fall, no fallback, the speed over the last 3 s
    within the band, and the walk climbs: the last foothold is ``tan(a)`` times its distance up the
    slope above the first. With the CoM held at rest at both ends of each step (a half-cosine from
    ``H + dz_sw0`` to ``H``), both fell within 10 s."""
    import math

    from amlip_qp.sim.reports.summary import mean_velocity_heading
    from amlip_qp.sim.scenarios.factory import build_simulation
    from amlip_qp.sim.scenarios.named import SCENARIOS

    scenario = SCENARIOS[name]
    assert scenario.setting.terrain == f"slope:{degrees:g}"
    res = build_simulation(scenario, "qp").run(scenario.duration_s, log="summary")
    assert not res.fell, f"fell at {res.fall_time_s} s"
    assert res.fallback_ticks == 0
    vx = float(mean_velocity_heading(res, 3.0)[0])
    assert abs(vx - scenario.vx.final_mps) <= SPEED_TOLERANCE_MPS, f"mean speed {vx:.3f} m/s"
    last = res.steps[-1].swing_actual_m
    assert last[0] > 5.0  # metres up the slope, which starts 1 m ahead
    assert last[2] - res.steps[0].swing_actual_m[2] == pytest.approx(
        math.tan(math.radians(degrees)) * (last[0] - 1.0), rel=0.05
    )


def test_qp_walks_up_30_degrees_with_the_ekf_taking_the_blades_flat_on_the_slope():
    """30 degrees terrain-aware on the closed-chain plant with the robot's sensors and the EKF, noise
    seed 1, 15 s: no fall and the speed band. The EKF takes a blade foot as a fixed contact while it lies
    flat on the ground the controller knows (``set_ground_pitch``); against the horizontal, as on level
    ground, no stance on the slope counted, the estimated forward velocity fell 0.23 m/s behind the
    truth by 8.5 s and the walk fell at 8.72 s."""
    from dataclasses import replace

    from amlip_qp.sim.reports.summary import mean_velocity_heading
    from amlip_qp.sim.scenarios.factory import build_simulation
    from amlip_qp.sim.scenarios.named import SCENARIOS

    base = SCENARIOS["cassie-slope-30-up-aware"]
    setting = replace(base.setting, plant="cassie-closed-chain", sensors="robot", estimator="ekf")
    scenario = base.with_(setting=setting)
    res = build_simulation(scenario, "qp", seed=1).run(scenario.duration_s, log="summary")
    assert not res.fell, f"fell at {res.fall_time_s} s"
    vx = float(mean_velocity_heading(res, 3.0)[0])
    assert abs(vx - scenario.vx.final_mps) <= SPEED_TOLERANCE_MPS, f"mean speed {vx:.3f} m/s"
