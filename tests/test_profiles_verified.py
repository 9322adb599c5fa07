"""The three zones of a command: verified (silent), physically possible (runs, one warning line), impossible (exit 2).

``[verified]`` of a profile (:class:`~amlip_qp.profiles.VerifiedEnvelope`) is
what the acceptance walks; ``[bounds]`` (:class:`~amlip_qp.profiles.CommandBounds`)
what the legs can do at all.
"""

from __future__ import annotations

import math
import warnings

import pytest

from amlip_qp import cli
from amlip_qp.exceptions import InputError, ProfileError, UnverifiedCommandWarning
from amlip_qp.profiles import VerifiedEnvelope, get_profile, read_profile


def _scenario(argv):
    from amlip_qp.experiments.walk import scenario_from_args

    return scenario_from_args(cli.build_parser().parse_args(["walk", *argv]))


@pytest.mark.parametrize(
    "argv",
    [
        ["--vx", "3.0"],
        ["--vx", "-0.5"],
        ["--vx", "1.0", "--vy", "-1.0", "--turn-rate", "45"],
        ["--robot", "rabbit", "--vx", "1.5"],
        ["--robot", "h1", "--vx", "1.5", "--vy", "0.2"],
    ],
)
def test_a_verified_command_runs_without_a_warning(argv):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert _scenario(argv).duration_s > 0


@pytest.mark.parametrize(
    "argv, needle",
    [
        (["--vx", "3.5"], "forward speed 3.5 m/s (verified -0.5 to 3 m/s)"),
        (["--vx", "-1.0"], "forward speed -1 m/s"),
        (["--speed-profile", "0:0,10:3.5,12:3.2"], "forward speed 3.5 m/s"),
        (["--vx", "1.0", "--vy", "1.2"], "lateral speed 1.2 m/s (verified |vy| <= 1 m/s)"),
        (["--vx", "1.0", "--turn-rate", "-60"], "turn rate -60 deg/s (verified <= 45 deg/s)"),
        (["--robot", "rabbit", "--vx", "1.6"], "inside rabbit's physical bounds but not verified"),
        (["--robot", "g1", "--vx", "1.0", "--turn-rate", "90"], "turn rate 90 deg/s"),
    ],
)
def test_an_unverified_command_inside_the_bounds_runs_with_one_warning(argv, needle):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        scenario = _scenario(argv)
    assert scenario.duration_s > 0
    assert [w.category for w in caught] == [UnverifiedCommandWarning]
    assert needle in str(caught[0].message)


@pytest.mark.parametrize(
    "argv, needle",
    [
        (["--vx", "4.2"], "forward speed 4.2 m/s is outside cassie's bounds [-4.14, 4.14] m/s"),
        (["--vx", "1.0", "--vy", "2.1"], "CommandBounds.vy_max_mps"),
        (["--turn-rate", "181"], "CommandBounds.turn_rate_max_radps"),
        (["--robot", "rabbit", "--vx", "1.8"], "outside rabbit's bounds [-1.73, 1.73] m/s"),
        (["--robot", "h1", "--vy", "1.3"], "outside h1's bound |vy| <= 1.21 m/s"),
    ],
)
def test_a_physically_impossible_command_is_refused(argv, needle):
    with pytest.raises(InputError) as info:
        _scenario(argv)
    assert needle in str(info.value)


def _walk(argv, capsys):
    code = cli.main(["walk", *argv, "--duration", "0.0005", "--log", "summary", "--no-progress"])
    return code, capsys.readouterr().err


def test_the_cli_says_unverified_in_one_stderr_line_and_runs(capsys):
    code, err = _walk(["--vx", "3.5"], capsys)
    assert code == 0
    assert err.splitlines() == [
        "amlip-qp: warning: forward speed 3.5 m/s (verified -0.5 to 3 m/s): inside cassie's physical bounds "
        "but not verified by its acceptance (profile [verified]); running it anyway"
    ]


def test_the_cli_is_silent_inside_the_envelope_and_exits_2_outside_the_bounds(capsys):
    code, err = _walk(["--vx", "1.0"], capsys)
    assert code == 0 and err == ""
    code, err = _walk(["--vx", "5"], capsys)
    assert code == 2 and err.count("\n") == 1 and err.startswith("amlip-qp: error: forward speed 5 m/s")


def test_bad_input_after_an_unverified_command_is_one_error_line_and_no_warning(tmp_path, capsys):
    bad = str(tmp_path / "missing" / "x.json")
    for argv in (["walk", "--vx", "3.5", "--json", bad], ["compare", "--robots", "rabbit", "--json", bad]):
        code = cli.main(argv)
        err = capsys.readouterr().err
        assert code == 2 and err.count("\n") == 1 and err.startswith("amlip-qp: error:"), err


def test_a_sweep_warns_once_for_all_its_unverified_cells(tmp_path, capsys):
    argv = ["sweep", "--grid", "vx=1.55,1.6,1.65", "--set", "robot=rabbit", "--set", "no_command_shaping=true"]
    code = cli.main([*argv, "--duration", "0.0005", "--no-progress", "--workers", "1", "--out", str(tmp_path / "o")])
    err = capsys.readouterr().err
    warned = [line for line in err.splitlines() if "warning" in line]
    assert code == 0
    assert len(warned) == 1, err
    assert warned[0].startswith("amlip-qp: warning: cell 0 (vx=1.55): forward speed 1.55 m/s")
    assert warned[0].endswith("(and 2 more walks outside the verified envelope)")


def test_a_comparison_warns_once_for_the_ramps_past_the_verified_envelope(monkeypatch):
    import dataclasses

    from amlip_qp.experiments import compare, robustness
    from amlip_qp.experiments.robustness import CompareSettings

    with warnings.catch_warnings():
        warnings.simplefilter("error")  # every robot's own ramp end is verified
        compare.build_tasks(["cassie", "rabbit", "h1", "g1"], ["qp"], [], CompareSettings())
    ranges = robustness.compare_ranges
    past = {"rabbit": 1.7, "h1": 1.7}  # 0.2 m/s past their verified 1.5 m/s, inside their physical bounds

    def ramps_past_the_envelope(robot):
        own = ranges(robot)
        return dataclasses.replace(own, ramp_end_mps=past.get(robot, own.ramp_end_mps))

    monkeypatch.setattr(robustness, "compare_ranges", ramps_past_the_envelope)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        compare.build_tasks(["cassie", "rabbit", "h1"], ["qp"], [], CompareSettings())
    assert [w.category for w in caught] == [UnverifiedCommandWarning]
    text = str(caught[0].message)
    assert text.startswith("rabbit's ramp: forward speed 1.7 m/s (verified 0 to 1.5 m/s)") and "\n" not in text
    assert "; h1's ramp: forward speed 1.7 m/s (verified 0 to 1.5 m/s)" in text and "cassie's ramp" not in text
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        compare.build_tasks(["rabbit"], ["qp"], [], CompareSettings(), ramp=False)


def test_the_envelope_names_every_unverified_command_once():
    env = VerifiedEnvelope(vx_mps=(-0.5, 2.5), vy_max_mps=0.3, turn_rate_max_radps=math.radians(18.0))
    assert env.unverified("r", vx_mps=(0.0, 1.0, 2.5), vy_mps=0.3, turn_rate_radps=math.radians(18.0)) is None
    text = env.unverified("r", vx_mps=(0.0, 2.7, 3.0), vy_mps=-0.4, turn_rate_radps=math.radians(20.0))
    assert text is not None
    assert text.startswith("forward speed 3 m/s (verified -0.5 to 2.5 m/s), lateral speed -0.4 m/s")
    assert "turn rate 20 deg/s" in text
    assert env.within(get_profile("cassie").bounds)


def test_a_verified_envelope_outside_the_bounds_is_a_profile_error(tmp_path):
    src = get_profile("rabbit").source
    text = src.read_text().replace("vx_mps = [0.0, 1.5]", "vx_mps = [0.0, 2.0]")
    assert "vx_mps = [0.0, 2.0]" in text
    path = tmp_path / "rabbit.toml"
    path.write_text(text)
    for f in src.parent.iterdir():  # the model files next to it
        if f.suffix == ".xml" and not (tmp_path / f.name).exists():
            (tmp_path / f.name).symlink_to(f)
    with pytest.raises(ProfileError, match=r"verified: the verified envelope must lie inside \[bounds\]"):
        read_profile(path)
