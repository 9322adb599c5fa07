"""amlip_qp.sim.scenarios.options: one walk's options, typed and checked, made a scenario by one constructor
for the command line and a sweep cell alike."""

from __future__ import annotations

import pytest

from amlip_qp.cli import build_parser
from amlip_qp.exceptions import InputError
from amlip_qp.experiments.walk import options_from_args, scenario_from_args
from amlip_qp.sim.scenarios.from_options import scenario_from_options
from amlip_qp.sim.scenarios.options import WalkOptions
from amlip_qp.sweep.run_cell import walk_run

#: A sweep cell's parameters and the ``walk`` command line that says the same.
CELLS_AND_COMMAND_LINES = [
    ({"vx": 0.75, "duration": 4.0}, ["--vx", "0.75", "--duration", "4"]),
    ({"vx": -0.5, "vy": -0.25, "turn_rate": -30}, ["--vx=-5e-1", "--vy=-0.25", "--turn-rate=-30"]),
    ({"speed_profile": "0:0,5:2.1"}, ["--speed-profile", "0:0,5:2.1"]),
    (
        {"robot": "rabbit", "vx": 0.5, "terrain": "slope:5", "terrain_aware": True},
        ["--robot", "rabbit", "--vx", "0.5", "--terrain", "slope:5", "--terrain-aware"],
    ),
    (
        {"plant_mass_scale": 1.1, "payload": 5, "plant_spring_scale": 0.9, "friction": 0.6, "actuator_delay": 2},
        [
            "--plant-mass-scale",
            "1.1",
            "--payload",
            "5",
            "--plant-spring-scale",
            "0.9",
            "--friction",
            "0.6",
            "--actuator-delay",
            "2",
        ],
    ),  # fmt: skip
    (
        {"scenario": "cassie-1mps", "sensors": "robot", "estimator": "ekf", "clearance": 0.12},
        ["--scenario", "cassie-1mps", "--sensors", "robot", "--estimator", "ekf", "--clearance", "0.12"],
    ),
    (
        {"tracker": "pbc", "planner": "mpc", "seed": 7, "noise": True},
        ["--tracker", "pbc", "--planner", "mpc", "--seed", "7", "--noise"],
    ),  # fmt: skip
    (
        {"scenario": "cassie-stairs-10cm", "terrain_aware": False},
        ["--scenario", "cassie-stairs-10cm", "--no-terrain-aware"],
    ),  # fmt: skip
    ({"robot": "rabbit", "accel_limit": 0.25}, ["--robot", "rabbit", "--accel-limit", "0.25"]),
    ({"no_command_shaping": True, "push": "1:100,0,0:0.2"}, ["--no-command-shaping", "--push", "1:100,0,0:0.2"]),
]


@pytest.mark.parametrize("params, argv", CELLS_AND_COMMAND_LINES)
def test_a_sweep_cell_and_the_command_line_build_the_same_walk(params, argv):
    args = build_parser().parse_args(["walk", *argv])
    cli_scenario = scenario_from_args(args)
    options = options_from_args(args)
    run = walk_run(params, seed=0)
    assert run.scenario == cli_scenario
    assert (run.tracker, run.planner, run.seed, run.noise) == (
        options.tracker,
        options.planner,
        options.seed,
        options.noise,
    )
    assert WalkOptions.from_mapping({**params, "seed": run.seed}) == options


def test_the_options_apply_what_they_say():
    sc = scenario_from_options(WalkOptions.from_mapping({"vx": 0.5, "turn_rate": 30.0, "duration": 3}))
    assert (sc.name, sc.robot, sc.duration_s, sc.vx(2.0)) == ("custom", "cassie", 3.0, 0.5)
    assert sc.turn_rate_radps == pytest.approx(0.5235987755982988) and sc.turn_start_s == 0.0
    sc = scenario_from_options(WalkOptions.from_mapping({"scenario": "cassie-1mps", "friction": "0.7"}))
    assert sc.name == "cassie-1mps+options" and sc.setting.modifiers.friction == 0.7
    assert scenario_from_options(WalkOptions()).name == "custom"


def test_every_value_is_checked_in_one_line_naming_its_option():
    for values, needle in [
        ({"speed": 1.0}, "unknown walk option 'speed'; known: robot, tracker, planner"),
        ({"duration": 0}, "duration: expected a positive number, got 0"),
        ({"duration": None}, None),
        ({"tracker": None}, "tracker: expected one of pbc, qp, got None"),
        ({"clearance": -0.1}, "clearance: expected a number >= 0, got -0.1"),
        ({"robot": "atlas"}, "robot: unknown robot 'atlas'"),
        ({"sensors": "perfect"}, "sensors: expected one of ideal, robot, got 'perfect'"),
        ({"push": 5}, "push: expected pushes T:FX,FY,FZ:DUR"),
        ({"push": ["1:0,0,0:-1"]}, "push: a push needs T >= 0 s and DUR > 0 s"),
        ({"accel_limit": 1e3}, "accel_limit: expected a number in (0, 100] m/s^2, got 1000.0"),
        ({"terrain": ["flat"]}, "terrain: expected a text value, got ['flat']"),
    ]:
        if needle is None:
            assert WalkOptions.from_mapping(values).duration is None
            continue
        with pytest.raises(InputError) as err:
            WalkOptions.from_mapping(values)
        assert needle in str(err.value) and "\n" not in str(err.value), (values, str(err.value))


def test_pushes_are_taken_as_text_or_as_their_tuples():
    one = WalkOptions.from_mapping({"push": "6:100,0,-5.5:0.2"}).push
    assert one == ((6.0, (100.0, 0.0, -5.5), 0.2),)
    assert WalkOptions.from_mapping({"push": [(6, [100, 0, -5.5], 0.2), "1:0,0,0:1"]}).push == (
        *one,
        (1.0, (0.0, 0.0, 0.0), 1.0),
    )


def test_the_command_line_types_are_the_options_checks(capsys):
    with pytest.raises(SystemExit):
        build_parser().parse_args(["walk", "--actuator-delay", "1.5"])
    assert "argument --actuator-delay: expected a whole number, got '1.5'" in capsys.readouterr().err
    with pytest.raises(InputError, match="actuator_delay: expected a whole number, got '1.5'"):
        WalkOptions.from_mapping({"actuator_delay": "1.5"})
