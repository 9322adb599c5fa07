"""``examples/walk_{cassie,rabbit,h1}.py``: each walks its robot through ``amlip_qp.MujocoLoop``, shortened."""

from __future__ import annotations

import importlib.util
import pathlib
import re

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]


def _example(name: str):
    spec = importlib.util.spec_from_file_location(name, ROOT / "examples" / f"{name}.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _numbers(line: str) -> list[float]:
    return [float(x) for x in re.findall(r"[-+]?\d+\.\d+|\d+", line)]


def test_h1_walks_forward_with_the_qp_tracker(capsys):
    assert _example("walk_h1").main(["--duration", "1.5"]) == 0
    line = capsys.readouterr().out.strip()
    assert line.startswith("H1 walked") and line.endswith("upright")
    forward, sideways, t = _numbers(line)[1:4]
    # measured: 0.28 m forward, 0.21 m to the right (the first steps) in 1.5 s, the command ramping to 0.5 m/s
    assert t == 1.5 and 0.15 < forward < 0.45 and abs(sideways) < 0.35


def test_rabbit_stands_then_speeds_up_with_the_pbc_tracker(capsys):
    assert _example("walk_rabbit").main(["--duration", "3", "--tracker", "pbc"]) == 0
    *seconds, last = capsys.readouterr().out.strip().splitlines()
    speeds = [_numbers(line)[1] for line in seconds]
    # measured: -0.17, 0.02, 0.21 m/s (stepping in place, then the 0.2 m/s^2 ramp from t = 1 s)
    assert len(speeds) == 3 and abs(speeds[0]) < 0.3 and abs(speeds[1]) < 0.15 and 0.1 < speeds[2] < 0.35
    assert last.startswith("Rabbit walked") and last.endswith("8 steps (pbc)")


def test_cassie_walks_with_the_pbc_tracker_without_a_video(capsys, tmp_path):
    assert (
        _example("walk_cassie").main(["--duration", "1.5", "--tracker", "pbc", "--no-video", "--out", str(tmp_path)])
        == 0
    )
    line = capsys.readouterr().out.strip()
    walked, t, speed = _numbers(line)[:3]
    # measured: 0.34 m in 1.5 s, 0.33 m/s over the last second (the 1 m/s command ramping at 0.5 m/s^2), 4 steps
    assert line.startswith("Cassie walked") and t == 1.5 and 0.2 < walked < 0.5 and 0.2 < speed < 0.5
    assert line.endswith("4 steps") and not any(tmp_path.iterdir())  # no video


@pytest.mark.parametrize("name", ["walk_h1", "walk_rabbit", "walk_cassie"])
def test_a_bad_duration_exits_2_in_one_line_before_any_walk(name, capsys):
    with pytest.raises(SystemExit) as exit_:
        _example(name).main(["--duration", "-1"])
    assert exit_.value.code == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "argument --duration: expected a number in (0, 600] s, got '-1'" in err


def test_raised_starts_differ_in_the_last_bits_and_are_counted(capsys):
    """Start k raises the base by k * 1e-12 m: the walks differ (a pass by luck of the bits would show), and
    the table counts those that walked."""
    module = _example("raised_starts")
    runs = [module.walk_from(("rabbit-1mps", "qp", "one-step", 0.5, k)) for k in (0, 1)]
    assert not any(fell for _, fell, _, _ in runs)
    # measured: -0.2120 and -0.2127 m/s (Rabbit's first steps from rest)
    assert runs[0][3] != runs[1][3] and abs(runs[0][3] - runs[1][3]) < 0.01
    assert module.main(["--scenario", "rabbit-1mps", "--duration", "0.5", "--starts", "2"]) == 0
    assert capsys.readouterr().out.strip().endswith("rabbit-1mps / qp / one-step: 2 of 2 starts walked")
    assert (
        module.main(["--scenario", "rabbit-1mps", "--duration", "0.5", "--starts", "1", "--planner", "one-step,mpc"])
        == 0
    )
    header, rule, row, *counts = [line for line in capsys.readouterr().out.splitlines() if line]
    assert header.count("one-step:") == 2 and header.count("mpc:") == 2 and rule.count("---") == 5
    assert row.startswith("| 0 | no | ") and row.count("| no |") == 2  # both planners walked the 0.5 s
    assert counts == [
        "rabbit-1mps / qp / one-step: 1 of 1 starts walked",
        "rabbit-1mps / qp / mpc: 1 of 1 starts walked",
    ]
    with pytest.raises(SystemExit) as info:
        module.main(["--starts", "0"])
    assert info.value.code == 2
    with pytest.raises(SystemExit) as info:
        module.main(["--planner", "one-step,deadbeat"])
    assert info.value.code == 2
