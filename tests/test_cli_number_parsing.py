"""Numbers on ``amlip-qp``'s command line: negative numbers in exponent form are values, an option
after a value-taking flag stays an option, and commands inside the robot's bounds pass the check."""

from __future__ import annotations

import pytest

from amlip_qp import cli
from cli_bad_input_support import run_main


@pytest.mark.parametrize(
    "argv, attribute, value",
    [
        (["walk", "--vx", "-1e-1"], "vx", -0.1),
        (["walk", "--vx=-1e-1"], "vx", -0.1),
        (["walk", "--turn-rate", "-5E0"], "turn_rate", -5.0),
        (["walk", "--vy", "-.25"], "vy", -0.25),
        (["walk", "--vx", "-2.5e+0"], "vx", -2.5),
    ],
)
def test_negative_numbers_in_exponent_form_are_values(argv, attribute, value):
    assert getattr(cli.build_parser().parse_args(argv), attribute) == value


def test_an_option_is_still_an_option_after_a_value_taking_flag(capsys):
    code, _, err = run_main(["walk", "--vx", "--json", "-"], capsys)
    assert code == 2 and "expected one argument" in err


def test_commands_inside_the_bounds_pass_the_check():
    from amlip_qp.experiments.walk import scenario_from_args

    parser = cli.build_parser()
    for argv in (
        ["--vx", "2.5"],
        ["--vx", "-5e-1"],
        ["--vx", "-1", "--vy", "-0.5", "--turn-rate", "-60"],
        ["--robot", "rabbit", "--vx", "1.0"],
        ["--robot", "rabbit", "--vx", "0.5", "--push", "1:100,0,0:0.2"],
        ["--duration", "600", "--push", "599.8:500,0,0:0.2"],
    ):
        scenario = scenario_from_args(parser.parse_args(["walk", *argv]))
        assert scenario.duration_s > 0
