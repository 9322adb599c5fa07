"""A sweep cell -> walk options -> scenario and push; the bisection plumbing of run_cell (no simulation)."""

from __future__ import annotations

import math

import pytest

from amlip_qp.exceptions import InputError
from amlip_qp.sweep import run_cell as rc


def test_every_walk_option_but_the_outputs_is_a_parameter():
    names = rc.parameter_names()
    assert {"tracker", "vx", "turn_rate", "plant_mass_scale", "noise", "seed", "push_impulse_Ns", "push_phase"} <= set(
        names
    )
    assert not {"json", "log", "plot", "video", "no_progress", "func"} & set(names)


def test_walk_argv_takes_flags_and_negative_values():
    argv = rc.walk_argv({"vx": -0.5, "noise": True, "no_command_shaping": False, "tracker": "pbc", "push_phase": 0.2})
    assert argv == ["--vx=-0.5", "--noise", "--tracker=pbc"]


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
        ({"vx": "fast"}, "argument --vx: expected a number, got 'fast'"),
        ({"vx": 9.0}, "outside cassie's bounds"),
        ({"tracker": "lqr"}, "invalid choice: 'lqr'"),
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


def test_a_false_on_off_option_is_passed_as_its_no_form():
    assert rc.walk_argv({"terrain_aware": False}) == ["--no-terrain-aware"]
    assert rc.walk_argv({"terrain_aware": True}) == ["--terrain-aware"]
    assert rc.walk_argv({"noise": False}) == []  # a plain flag: false is its absence


def test_a_crashed_cell_has_no_metrics_and_says_its_worker_died():
    task = {"index": 3, "id": "c3", "seed": 7, "params": {"vx": 1.0}, "bisect": None}
    rec = rc.crashed_record(task, deaths=2)
    assert {k: rec[k] for k in task} == task
    assert rec["metrics"] == {} and rec["error"].startswith("WorkerDied: the worker process died 2 times")
