"""``examples/speed_against.py``: interleaved walks of two checkouts, timed the same way."""

from __future__ import annotations

import importlib.util
import json
import pathlib

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def speed_against():
    spec = importlib.util.spec_from_file_location("speed_against", ROOT / "examples" / "speed_against.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_a_checkout_against_itself_splits_each_walk_and_compares_the_pairs(speed_against, tmp_path, capsys):
    out = tmp_path / "speed.json"
    argv = ["--reference", str(ROOT), "--pairs", "2", "--duration", "0.1", "--scenario", "rabbit-0.5mps"]
    assert speed_against.main([*argv, "--json", str(out)]) == 0
    report = json.loads(out.read_text())
    assert len(report["pairs"]) == 2
    for pair in report["pairs"]:
        for rec in pair.values():
            assert pathlib.Path(rec["package"]).resolve().is_relative_to(ROOT)  # the checkout's own package ran
            assert rec["ticks"] == 200 and not rec["fell"]
            # the three timed parts fit in the loop's wall time, none counted twice
            assert rec["mujoco_us"] > 0.0 and rec["controller_us"] > 0.0 and rec["harness_us"] > 0.0
            assert rec["realtime_factor"] == pytest.approx(500.0 / rec["wall_us"])  # 0.5 ms ticks
            # the yardstick: MuJoCo's step alone, one step a tick here
            assert rec["step_alone_us"] > 0.0 and rec["steps_per_tick"] == 1.0
            assert rec["wall_per_step"] == pytest.approx(rec["wall_us"] / rec["step_alone_us"])
            assert rec["harness_per_mujoco"] == pytest.approx(rec["harness_us"] / rec["mujoco_us"])
    ratio = report["ratios"]["wall_per_step"]
    pairs = [p["this"]["wall_per_step"] / p["reference"]["wall_per_step"] for p in report["pairs"]]
    assert ratio == pytest.approx(sorted(pairs)[0] + (sorted(pairs)[1] - sorted(pairs)[0]) / 2)  # the median
    assert "medians over 2 pairs" in capsys.readouterr().out
    assert not any(rec["gathered"] for pair in report["pairs"] for rec in pair.values())


def test_gathered_walks_this_checkout_with_the_build_that_gathers_its_inputs(speed_against, tmp_path, capsys):
    out = tmp_path / "speed.json"
    argv = ["--reference", str(ROOT), "--pairs", "1", "--duration", "0.05", "--scenario", "rabbit-0.5mps", "--gathered"]
    assert speed_against.main([*argv, "--json", str(out)]) == 0
    (pair,) = json.loads(out.read_text())["pairs"]
    assert pair["this"]["gathered"] and not pair["reference"]["gathered"]
    assert speed_against.main(["--reference", str(ROOT), "--gathered", "--tracker", "pbc"]) == 2
    assert "--gathered is an option of the qp tracker" in capsys.readouterr().out.splitlines()[-1]


def test_bad_input_exits_2_in_one_line_before_any_walk(speed_against, tmp_path, capsys):
    assert speed_against.main(["--reference", str(tmp_path)]) == 2
    assert capsys.readouterr().out.count("\n") == 1
    assert speed_against.main(["--reference", str(ROOT), "--pairs", "0"]) == 2
    capsys.readouterr()
    bad = [
        ("--scenario", "nowhere", "unknown scenario"),
        ("--tracker", "lqr", "--tracker lqr: unknown"),
        ("--log", "verbose", "--log verbose: unknown"),
        ("--json", str(tmp_path / "missing" / "x.json"), "--json"),
        ("--duration", "nan", "--duration a finite number"),
    ]
    for option, value, message in bad:
        assert speed_against.main(["--reference", str(ROOT), option, value]) == 2
        out = capsys.readouterr().out
        assert out.count("\n") == 1 and message in out
