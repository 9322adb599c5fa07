"""The ground predictions of the walking controller: flat, blind (footholds) and terrain-aware."""

from __future__ import annotations

import math

import numpy as np
import pytest

from amlip_qp.control.walking.ground import MAX_DZ_M, MAX_PITCH_RAD, GroundPredictor
from amlip_qp.exceptions import InputError

#: A blade foot, from its contact point along the heading: 0.12 m ahead, 0.08 m behind, m (Cassie's).
BLADE_M = (0.12, 0.08)

SLOPE_RAD = math.radians(10.0)


def slope(x_m: float, y_m: float) -> float:
    """A 10 degree slope up along +x from x = 1 m (flat before)."""
    return max(x_m - 1.0, 0.0) * math.tan(SLOPE_RAD)


def test_modes_and_their_height_function_are_checked():
    assert not GroundPredictor().active
    assert GroundPredictor("blind").active and GroundPredictor("aware", slope).active
    with pytest.raises(InputError, match="ground mode"):
        GroundPredictor("seeing")
    with pytest.raises(InputError, match="height function"):
        GroundPredictor("aware")
    with pytest.raises(InputError, match="height function"):
        GroundPredictor("blind", slope)


def test_aware_prediction_reads_the_height_and_pitch_at_the_target():
    g = GroundPredictor("aware", slope)
    g.touchdown(np.array([2.0, 0.1, 7.0]), 0.0)  # the measured z is not used: the height function's is
    assert g.stance_pitch_rad == pytest.approx(-SLOPE_RAD)  # uphill: negative pitch
    p = g.predict(np.array([2.3, -0.1]), 0.0)
    assert p.dz_next_m == p.dz_sw_m == pytest.approx(0.3 * math.tan(SLOPE_RAD))
    assert p.slope_pitch_rad == pytest.approx(-SLOPE_RAD) and p.dz_sw0_m == 0.0
    # walking the other way, the same slope descends ahead
    assert g.predict(np.array([1.7, 0.0]), math.pi).slope_pitch_rad == pytest.approx(SLOPE_RAD)
    g.touchdown(np.array([2.3, -0.1, 0.0]), math.pi)
    assert g.stance_pitch_rad == pytest.approx(SLOPE_RAD)
    p = g.predict(np.array([2.0, 0.1]), math.pi)
    assert p.dz_sw0_m == pytest.approx(-0.3 * math.tan(SLOPE_RAD))  # lifted off below the stance
    assert p.slope_pitch0_rad == pytest.approx(-SLOPE_RAD)


def test_aware_prediction_is_clipped_and_survives_missing_ground():
    wall = GroundPredictor("aware", lambda x, y: 0.0 if x < 1.0 else (5.0 if x < 3.0 else math.nan))
    wall.touchdown(np.array([0.8, 0.0, 0.0]), 0.0)
    p = wall.predict(np.array([1.2, 0.0]), 0.0)
    assert p.dz_sw_m == MAX_DZ_M and abs(p.slope_pitch_rad) <= MAX_PITCH_RAD
    p = wall.predict(np.array([4.0, 0.0]), 0.0)  # no ground there: the stance's height
    assert p.dz_sw_m == 0.0 and p.slope_pitch_rad == 0.0


def test_blind_prediction_learns_the_slope_from_the_footholds():
    g = GroundPredictor("blind")
    xs = [2.0, 2.3, 2.6, 2.9]
    g.touchdown(np.array([xs[0], 0.1, slope(xs[0], 0.0)]), 0.0)
    p = g.predict(np.array([2.3, -0.1]), 0.0)
    assert p.dz_sw_m == 0.0 and p.slope_pitch_rad == 0.0  # one foothold: level
    for i, x in enumerate(xs[1:]):
        g.touchdown(np.array([x, 0.1 if i % 2 else -0.1, slope(x, 0.0)]), 0.0)
    p = g.predict(np.array([3.2, 0.1]), 0.0)
    assert p.slope_pitch_rad == pytest.approx(-SLOPE_RAD, abs=1e-9)
    assert p.dz_next_m == pytest.approx(0.3 * math.tan(SLOPE_RAD), abs=1e-9)
    assert p.dz_sw0_m == pytest.approx(-0.3 * math.tan(SLOPE_RAD), abs=1e-9)
    assert g.stance_pitch_rad == pytest.approx(-SLOPE_RAD, abs=1e-9)
    g.reset()
    g.touchdown(np.array([xs[-1], 0.1, slope(xs[-1], 0.0)]), 0.0)
    p = g.predict(np.array([3.2, 0.1]), 0.0)
    assert p.slope_pitch_rad == 0.0 and p.dz_sw_m == 0.0 and p.dz_sw0_m == 0.0  # forgotten: level again


def test_the_controller_plans_for_its_ground_mode():
    from amlip_qp.control.walking.controller import WalkingController
    from amlip_qp.control.wbc.tracker import QPTracker
    from amlip_qp.robots import RobotKinematics
    from amlip_qp.sim.scenarios.factory import load

    robot = load("cassie")

    def make(**kw):
        kin = RobotKinematics(robot)  # the Python output map
        return WalkingController(robot, QPTracker(robot), kin, planner_backend="numpy", **kw)

    flat = make()
    assert flat.ground.mode == "flat" and flat.planner.late_descent is None
    aware = make(terrain_height_fn=slope)
    assert aware.ground.mode == "aware" and aware.planner.late_descent == "landing"
    assert make(ground_mode="blind").planner.late_descent == "landing"


def test_aware_pitch_beside_a_stair_edge_is_the_treads():
    def stairs(x_m: float, y_m: float) -> float:
        return 0.1 * math.floor(x_m / 0.3) if x_m > 0.0 else 0.0

    g = GroundPredictor("aware", stairs, BLADE_M)
    g.touchdown(np.array([0.15, 0.0, 0.0]), 0.0)
    for x in (0.28, 0.32, 0.45):  # just before an edge, just after it, mid-tread
        assert g.predict(np.array([x, 0.0]), 0.0).slope_pitch_rad == 0.0
    assert g.predict(np.array([0.32, 0.0]), 0.0).dz_sw_m == pytest.approx(0.1)


def test_a_clearance_too_high_for_the_step_is_lowered_to_keep_the_swing_apex_below_the_com():
    from amlip_qp.alip.outputs import check_ground
    from amlip_qp.control.walking.ground import APEX_MARGIN_M, fit_clearance
    from amlip_qp.messages import Command, TerrainPrediction

    cmd = Command(step_time_s=0.3, com_height_m=0.8, clearance_m=0.7)
    up = TerrainPrediction(dz_next_m=0.2, dz_sw_m=0.2)
    fitted = fit_clearance(up, cmd)
    # apex = 0.2 + z_cl + 0.2 / 8 must stay APEX_MARGIN_M below the CoM at 0.8 m
    assert fitted.clearance_m == pytest.approx(0.8 - 0.2 - 0.025 - APEX_MARGIN_M)
    ground = (up.dz_sw0_m, up.dz_sw_m, 0.0, 0.0)
    check_ground(ground, 0.8, fitted.clearance_m)  # the planner accepts it ...
    with pytest.raises(InputError, match="swing foot path too high"):
        check_ground(ground, 0.8, cmd.clearance_m)  # ... and would have refused the given one
    assert (fitted.vx_mps, fitted.com_height_m) == (cmd.vx_mps, cmd.com_height_m)
    # a clearance that fits is the same object (flat ground and the named scenarios); never below 0 m
    assert (
        fit_clearance(TerrainPrediction(), Command(step_time_s=0.3, com_height_m=0.8, clearance_m=0.1)).clearance_m
        == 0.1
    )
    small = Command(step_time_s=0.3, com_height_m=0.8, clearance_m=0.1)
    assert fit_clearance(up, small) is small
    deep = TerrainPrediction(dz_next_m=0.25, dz_sw_m=0.25, dz_sw0_m=-0.7)
    assert fit_clearance(deep, small).clearance_m == 0.0


def stairs_up(x_m: float, y_m: float) -> float:
    """Stairs of 0.1 m rise and 0.3 m run up along +x from x = 1 m."""
    return 0.0 if x_m < 1.0 else 0.1 * (1 + math.floor((x_m - 1.0) / 0.3))


def test_only_the_aware_mode_has_a_foothold_hook():
    assert GroundPredictor().foothold() is None and GroundPredictor("blind").foothold() is None
    g = GroundPredictor("aware", stairs_up, BLADE_M)
    g.touchdown(np.array([0.7, 0.0, 0.0]), 0.0)
    hook = g.foothold()
    assert hook is not None
    assert hook(0.98, 0.1, 0.0, 0.2) == pytest.approx((1.08, 0.1))  # off the first edge, onto the tread


def test_a_step_over_an_edge_gets_the_rise_as_extra_clearance():
    from amlip_qp.messages import Command

    cmd = Command(step_time_s=0.3, com_height_m=0.8, clearance_m=0.1)
    g = GroundPredictor("aware", stairs_up, BLADE_M)
    g.touchdown(np.array([0.6, 0.0, 0.0]), 0.0)
    g.touchdown(np.array([0.85, 0.2, 0.0]), 0.0)  # the swing foot lifts off at x = 0.6 m
    p = g.predict(np.array([0.78, 0.0]), 0.0)  # on the floor: no edge between
    assert g.edge_rise_m == 0.0 and g.fit(p, cmd) is cmd
    p = g.predict(np.array([1.1, 0.0]), 0.0)  # up onto the first tread
    assert g.edge_rise_m == pytest.approx(0.1)
    assert g.fit(p, cmd).clearance_m == pytest.approx(0.2)
    g.touchdown(np.array([1.1, 0.0, 0.0]), math.pi)  # turned round on the first tread
    g.touchdown(np.array([1.15, 0.2, 0.0]), math.pi)  # the swing foot lifts off at 1.1 m, to land down the riser
    p = g.predict(np.array([0.8, 0.0]), math.pi)
    assert p.dz_sw_m == pytest.approx(-0.1) and g.edge_rise_m == pytest.approx(0.1)
    # a smooth slope has no edge: the clearance stays
    s = GroundPredictor("aware", slope)
    s.touchdown(np.array([2.0, 0.0, 0.0]), 0.0)
    s.touchdown(np.array([2.2, 0.2, 0.0]), 0.0)
    p = s.predict(np.array([2.5, 0.0]), 0.0)
    assert p.dz_sw_m - p.dz_sw0_m > 0.05 and s.edge_rise_m == 0.0 and s.fit(p, cmd) is cmd


def test_mpc_regions_are_the_treads_less_the_footprint():
    """Cassie's blade (0.12 m ahead of the contact, 0.08 m behind) and 0.03 m from a riser ahead, on 0.3 m treads."""
    g = GroundPredictor("aware", stairs_up, BLADE_M)
    g.touchdown(np.array([0.7, 0.0, 0.0]), 0.0)
    regions = g.regions(np.array([[1.2, 0.1], [1.45, -0.1], [0.5, 0.1]]), 0.0)
    (a0, b0, c0, d0, z0), (a1, b1, _, _, z1), (a2, b2, _, _, z2) = regions
    assert (a0, b0, z0) == pytest.approx((1.08, 1.15, 0.1), abs=0.006)
    assert (a1, b1, z1) == pytest.approx((1.38, 1.45, 0.2), abs=0.006)
    assert b2 == pytest.approx(1.0 - 0.15, abs=0.006) and z2 == 0.0 and a2 < 0.5 - 0.3  # the floor before the stairs
    assert c0 < -100.0 and d0 > 100.0  # unbounded across the heading
    # a foothold on a stretch found before gets that region again, without sampling the terrain
    calls = []
    g.height_fn = lambda x, y: calls.append(x) or stairs_up(x, y)
    assert g.regions(np.array([[1.1, 0.0], [1.4, 0.3]]), 0.0) == regions[:2] and calls == []
    # on the floor 0.4 m behind the first floor foothold: found afresh, both ends the search reach's (0.53 m)
    far = g.regions(np.array([[0.1, 0.0]]), 0.0)[0]
    assert calls and far[:2] == pytest.approx((0.1 - 0.53, 0.1 + 0.53), abs=0.006)
    # along y the boxes turn; far from an axis, and in the other modes, there are none
    turned = g.regions(np.array([[1.2, 0.1]]), 0.5 * math.pi)
    assert turned[0][0] < -100.0 and turned[0][1] > 100.0
    assert g.regions(np.array([[1.2, 0.1]]), math.radians(45.0)) is None
    assert GroundPredictor("blind").regions(np.array([[1.2, 0.1]]), 0.0) is None


def test_the_one_step_planner_times_its_steps_only_in_the_aware_mode():
    """Flat and blind ground give the planner no timing (their walks are the one-step law's at ``T``);
    the aware mode gives the one-step planner the step timing of a moved foothold, and the MPC none (it
    plans its own duration)."""
    from amlip_qp.alip import Planner, StepClock
    from amlip_qp.control.mpc import make_mpc_planner
    from amlip_qp.control.walking.planners import FOOTHOLD_TIMING, extra

    names = ("torso_pitch", "com_z_over_stance", "com_x_over_swing", "com_z_over_swing")
    one = Planner(names, 31.0)
    assert extra(one, GroundPredictor()) == extra(one, GroundPredictor("blind")) == {}
    assert extra(one, GroundPredictor("aware", stairs_up, BLADE_M)) == {"timing": FOOTHOLD_TIMING}
    assert FOOTHOLD_TIMING.step_time_min == 1.0 and FOOTHOLD_TIMING.step_time_max > 1.0
    mpc = make_mpc_planner(names, 31.0, backend="numpy", clock=StepClock())
    assert extra(mpc, GroundPredictor("aware", stairs_up, BLADE_M)) == {}  # no plan yet: no regions either


def test_the_mpc_plans_no_step_shorter_than_t_in_the_aware_mode():
    """The walking loop's MPC in the aware mode: its shortest step raised to the one-step planner's there
    (``T``); elsewhere its own (0.6 ``T``); a longer shortest step of the caller's is kept."""
    from amlip_qp.alip import StepClock
    from amlip_qp.alip.mpc_planner import MPCSettings
    from amlip_qp.control.walking.planners import FOOTHOLD_TIMING, make_planner

    names = ("torso_pitch", "com_z_over_stance", "com_x_over_swing", "com_z_over_swing")

    def shortest(aware: bool, settings: MPCSettings | None = None) -> float:
        planner = make_planner("mpc", names, 31.0, StepClock(), "numpy", None, settings, 0.2, aware=aware)
        assert planner.settings.step_time_min_s == 0.2  # the tracker's shortest step, s, either way
        return planner.settings.step_time_min

    assert shortest(False) == MPCSettings().step_time_min == 0.6
    assert shortest(True) == FOOTHOLD_TIMING.step_time_min == 1.0
    assert shortest(True, MPCSettings(step_time_min=1.2)) == 1.2
    with pytest.raises(InputError, match="step_time_max must be >= 1.0"):
        shortest(True, MPCSettings(step_time_max=0.9))
