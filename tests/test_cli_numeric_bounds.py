"""Every numeric option of every ``amlip-qp`` command refuses absurd values (huge, NaN, infinite)
with exit status 2 and one line, before anything is simulated or written."""

from __future__ import annotations

import argparse

import pytest

from amlip_qp import cli
from amlip_qp.exceptions import InputError
from cli_bad_input_support import run_main

#: How each command is given the option under test (enough for it to reach its checks, nothing written).
COMMANDS = {
    "walk": ["walk"],
    "compare": ["compare", "--no-plot"],
    "sweep": ["sweep", "--grid", "vx=0.5", "--out", "{tmp}/sweep"],
    "codegen": ["codegen", "--out", "{tmp}/gen"],
    "bench codegen": ["bench", "codegen"],
    "bench qp": ["bench", "qp"],
    "bench ekf": ["bench", "ekf"],
    "bench harness": ["bench", "harness"],
    "bench sweep": ["bench", "sweep"],
}
#: Options whose error names the quantity instead of the option (the robot's CommandBounds).
QUANTITY = {"--vx": "forward speed", "--vy": "lateral speed", "--turn-rate": "turn rate", "--duration": "duration"}


def numeric_options(command: list[str]) -> list[tuple[str, bool]]:
    """``(option, takes an int)`` for every option of ``command`` whose value type reads a number.

    argparse keeps a parser's options in ``_actions`` and has no public accessor for them.
    """
    parser = cli.build_parser()
    for word in command:
        sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
        parser = sub.choices[word]
    out = []
    for action in parser._actions:
        if not action.option_strings or action.type is None or action.nargs == 0:
            continue
        try:
            value = action.type("1")
        except (argparse.ArgumentTypeError, ValueError, TypeError, InputError):
            continue  # a text value (a list of names, a push spec)
        if isinstance(value, (int, float)):
            out.append((action.option_strings[-1], isinstance(value, int)))
    return out


def test_the_audit_sees_every_numeric_option():
    found = {name: [o for o, _ in numeric_options(name.split())] for name in COMMANDS}
    assert found["walk"] == [
        "--vx", "--vy", "--turn-rate", "--duration", "--accel-limit", "--seed", "--clearance",
        "--plant-mass-scale", "--plant-spring-scale", "--friction", "--actuator-delay", "--video-fps",
    ]  # fmt: skip
    assert found["compare"] == [
        "--push-iterations", "--seed", "--clearance", "--plant-mass-scale", "--plant-spring-scale", "--friction",
        "--actuator-delay", "--jobs",
    ]  # fmt: skip
    assert found["sweep"] == ["--duration", "--workers"]
    assert found["codegen"] == []
    assert (found["bench codegen"], found["bench qp"], found["bench ekf"]) == (["--calls"], ["--ticks"], ["--duration"])
    assert found["bench harness"] == ["--duration", "--repeats"]
    assert found["bench sweep"] == ["--cells", "--duration", "--repeats"]


CASES = [
    (name, option, value)
    for name, command in COMMANDS.items()
    for option, is_int in numeric_options(name.split())
    for value in ((str(10**30), str(-(10**30))) if is_int else ("1e300", "-1e300", "nan", "inf"))
]


@pytest.mark.parametrize("name, option, value", CASES, ids=[f"{n} {o} {v}" for n, o, v in CASES])
def test_every_numeric_option_refuses_absurd_values_in_one_line(name, option, value, tmp_path, capsys, no_simulation):
    argv = [a.format(tmp=tmp_path) for a in COMMANDS[name]]
    code, out, err = run_main([*argv, f"{option}={value}"], capsys)
    lines = err.strip().splitlines()
    assert code == 2 and len(lines) == 1 and out == "", err
    assert (QUANTITY.get(option, option) if "argument" not in lines[0] else option) in lines[0]
    assert not any(tmp_path.iterdir())  # nothing written (codegen's and sweep's folders not even created)
