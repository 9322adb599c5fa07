"""examples/four_point_feet.py: the four-point profiles it writes, and bad input refused in one line (exit 2)."""

from __future__ import annotations

import pytest

from amlip_qp.paths import MODELS_DIR
from amlip_qp.profiles import read_profile
from sole_cases import SOLES, sole_profile

#: Per robot, its four-point soles (each four force points).
FOUR_POINTS = {"g1": ("four spheres",), "h1": ("rectangle", "triangle")}


@pytest.mark.parametrize("robot, sole", [(r, s) for r in FOUR_POINTS for s in FOUR_POINTS[r]])
def test_each_sole_profile_loads_with_four_force_points_below_the_ankle(robot, sole, tmp_path):
    path = sole_profile(robot, tmp_path, sole)
    text = path.read_text()
    line, soles = SOLES[robot]
    assert line not in text and soles[sole] in text
    line_points = read_profile(MODELS_DIR / f"{robot}.toml").feet.force_points_m
    points = read_profile(path).feet.force_points_m
    assert len(points) == 4 and len(line_points) == 2
    # the four points span the bundled line's length and sit at its height below the ankle
    xs = sorted(p[0] for p in points)
    line_xs = sorted(p[0] for p in line_points)
    assert xs[0] == pytest.approx(line_xs[0]) and xs[-1] == pytest.approx(line_xs[-1])
    assert {p[2] for p in points} == {line_points[0][2]}
    assert max(abs(p[1]) for p in points) > 0.0  # the sole has a width, the line has none


def test_the_default_sole_is_the_first(tmp_path):
    assert sole_profile("h1", tmp_path).name == "h1_rectangle.toml"
    assert sole_profile("g1", tmp_path).name == "g1_four_spheres.toml"


@pytest.mark.parametrize(
    "argv, needle",
    [
        (["--robots", "cassie"], "--robots takes robots of g1, h1, got 'cassie'"),
        (["--robots", ","], "--robots takes robots of g1, h1"),
        (["--jobs", "0"], "--jobs must be 1 to 64, got 0"),
    ],
)
def test_bad_input_exits_2_with_one_line_before_any_walk(argv, needle, capsys, monkeypatch):
    import sole_cases

    example = sole_cases._example
    monkeypatch.setattr(example, "walk", lambda argv: pytest.fail("walked before refusing"))
    with pytest.raises(SystemExit) as exc:
        example.main(argv)
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert needle in err and err.strip().splitlines()[-1].startswith("four_point_feet.py: error: ")
