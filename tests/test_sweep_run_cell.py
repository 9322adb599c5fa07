"""A sweep cell -> walk options -> scenario and push; the bisection plumbing of run_cell (no simulation)."""

from __future__ import annotations

import math

import pytest

from amlip_qp.exceptions import InputError
from amlip_qp.sweep import run_cell as rc

#: ``walk``'s options that are not parameters of a walk: its outputs, the progress bar, the handler.
NOT_PARAMETERS = {"command", "func", "json", "log", "plot", "video", "video_fps", "no_progress"}


def test_every_walk_option_but_the_outputs_is_a_parameter():
    """A new ``walk`` option cannot be left unsweepable: the parameters are the CLI's options minus its outputs."""
    from amlip_qp.cli import build_parser
    from amlip_qp.sim.scenarios.options import WalkOptions

    cli_options = set(vars(build_parser().parse_args(["walk"]))) - NOT_PARAMETERS
    names = rc.parameter_names()
    assert set(WalkOptions.names()) == cli_options
    assert names == (*WalkOptions.names(), *rc.PUSH_DEFAULTS) and len(set(names)) == len(names)
    assert {"tracker", "vx", "turn_rate", "plant_mass_scale", "noise", "seed", "push_impulse_Ns", "push_phase"} <= set(
        names
    )
    # the defaults are the dataclass's, and the command line's are the same
    assert rc.walk_defaults() == {n: getattr(WalkOptions(), n) for n in WalkOptions.names()}
    assert WalkOptions.from_namespace(build_parser().parse_args(["walk"])) == WalkOptions()


def test_a_cells_flags_and_negative_values_are_typed_options():
    run = rc.walk_run({"vx": -0.5, "noise": True, "no_command_shaping": False, "tracker": "pbc", "push_phase": 0.2}, 0)
    assert (run.tracker, run.noise, run.scenario.vx(3.0), run.scenario.shaping) == ("pbc", True, -0.5, None)
    assert rc.walk_run({"vx": "-0.25"}, 0).scenario.vx(1.0) == -0.25  # a number as text, as on a command line


def test_walk_run_builds_the_scenario_with_the_push():
    run = rc.walk_run(
        {"robot": "cassie", "vx": 1.0, "duration": 4.0, "push_impulse_Ns": 20.0, "push_direction_deg": 90.0,
         "push_phase": 0.4, "push_time_s": 2.0},
        seed=11,
    )  # fmt: skip
    assert (run.tracker, run.seed, run.noise, run.scenario.duration_s) == ("qp", 11, False, 4.0)
    (push,) = run.scenario.pushes
    assert push.force_N == (0.0, 100.0, 0.0) and push.duration_s == 0.2 and push.phase == 0.4  # 20 N s / 0.2 s, +y
    assert push.impulse_Ns == pytest.approx(20.0)
    assert rc.walk_run({"robot": "cassie", "seed": 3}, seed=11).seed == 3
    assert run.planner == "one-step" and rc.walk_run({"planner": "mpc"}, seed=0).planner == "mpc"


def test_push_direction_is_the_angle_from_forward_towards_left():
    for deg, (cx, cy) in {0: (1, 0), 90: (0, 1), 180: (-1, 0), 225: (-math.sqrt(0.5), -math.sqrt(0.5))}.items():
        push = rc.make_push({"push_impulse_Ns": 10.0, "push_direction_deg": deg, "push_duration_s": 0.1})
        assert push.force_N[:2] == pytest.approx((100.0 * cx, 100.0 * cy)) and push.force_N[2] == 0.0
    assert rc.make_push({"push_impulse_Ns": 0.0, "push_direction_deg": 45.0}) is None
    # along +-x, FY is exactly 0 (a planar robot refuses any lateral force)
    assert rc.walk_run({"robot": "rabbit", "push_impulse_Ns": 5.0, "push_direction_deg": 180.0}, 0).scenario.pushes


@pytest.mark.parametrize(
    "params, needle",
    [
        ({"speed": 1.0}, "unknown parameter 'speed'; known: robot, tracker"),
        ({"vx": "fast"}, "vx: expected a number, got 'fast'"),
        ({"vx": True}, "vx: expected a number, got True"),
        ({"vx": 9.0}, "outside cassie's bounds"),
        ({"tracker": "lqr"}, "tracker: expected one of pbc, qp, got 'lqr'"),
        ({"noise": "yes"}, "noise: expected true or false, got 'yes'"),
        ({"seed": 2**32}, "seed: expected a seed in [0, 4294967295], got 4294967296"),
        ({"actuator_delay": 1.5}, "actuator_delay: expected a whole number, got 1.5"),
        ({"accel_limit": 0.5, "no_command_shaping": True}, "accel_limit (--accel-limit) and no_command_shaping"),
        ({"vx": 0.5, "speed_profile": "0:0,5:1"}, "vx (--vx) and speed_profile (--speed-profile) both set"),
        ({"push": "1:2,3:0.2"}, "push: expected T:FX,FY,FZ:DUR"),
        ({"push_impulse_Ns": -1.0}, "push_impulse_Ns >= 0"),
        ({"push_impulse_Ns": 5.0, "push_phase": 1.5}, "step phase must be in [0, 1)"),
        ({"push_impulse_Ns": 5.0, "push_phase": 0.5, "duration": 2.3}, "may start up to one step late"),
        ({"push_impulse_Ns": 5.0, "push_direction_deg": "left"}, "push_direction_deg must be a number"),
    ],
)
def test_bad_cells_say_what_to_fix(params, needle):
    with pytest.raises(InputError) as err:
        rc.walk_run(params, seed=0)
    assert needle in str(err.value) and "\n" not in str(err.value)


def test_run_cell_bisects_the_named_parameter(monkeypatch):
    """A stand-in walk that survives pushes up to 23 N s: the cell reports the bracket's lower end."""

    def fake_walk(run):
        return {"survived": sum(p.impulse_Ns for p in run.scenario.pushes) <= 23.0}

    monkeypatch.setattr(rc, "walk", fake_walk)
    task = {"index": 0, "id": "x", "seed": 1, "params": {"robot": "cassie", "duration": 5.0},
            "bisect": {"parameter": "push_impulse_Ns", "low": 0.0, "high": 40.0, "iterations": 4}}  # fmt: skip
    record = rc.run_cell(task)
    m = record["metrics"]
    assert m == {"max_push_impulse_Ns": 22.5, "max_push_impulse_Ns_capped": False, "bisect_walks": 5}
    assert record["params"] == task["params"] and record["wall_s"] >= 0.0 and record["error"] is None


def test_a_cell_whose_walk_raises_is_recorded_not_raised(monkeypatch):
    def failing_walk(run):
        raise FloatingPointError("the plant diverged\nsecond line")

    monkeypatch.setattr(rc, "walk", failing_walk)
    task = {"index": 3, "id": "y", "seed": 2, "params": {"robot": "cassie", "duration": 1.0}, "bisect": None}
    record = rc.run_cell(task)
    assert record["metrics"] == {} and record["error"] == "FloatingPointError: the plant diverged"
    assert {k: record[k] for k in task} == task
    assert rc.error_text(RuntimeError("x" * 400)) == "RuntimeError: " + "x" * 283 + "..."
    assert len(rc.error_text(RuntimeError("x" * 400))) == 300 and rc.error_text(ValueError()) == "ValueError"


def test_a_false_on_off_option_turns_it_off_and_a_missing_one_keeps_the_scenarios():
    stairs = {"scenario": "cassie-stairs-10cm"}
    assert rc.walk_run(stairs, 0).scenario.setting.terrain_aware
    assert not rc.walk_run({**stairs, "terrain_aware": False}, 0).scenario.setting.terrain_aware
    assert rc.walk_run({"terrain": "slope:5", "terrain_aware": True}, 0).scenario.setting.terrain_aware
    assert not rc.walk_run({"noise": False}, 0).noise  # a plain flag: false is its default


def test_a_crashed_cell_has_no_metrics_and_says_its_worker_died():
    task = {"index": 3, "id": "c3", "seed": 7, "params": {"vx": 1.0}, "bisect": None}
    rec = rc.crashed_record(task, deaths=2)
    assert {k: rec[k] for k in task} == task
    assert rec["metrics"] == {} and rec["error"].startswith("WorkerDied: the worker process died 2 times")
