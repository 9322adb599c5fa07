"""The sweep spec: TOML and --grid values, ranges, grid order, random sampling, structural errors."""

from __future__ import annotations

import pytest

from amlip_qp.exceptions import InputError
from amlip_qp.experiments.robustness import MAX_BISECTION_ITERATIONS
from amlip_qp.sweep import spec as spec_mod
from amlip_qp.sweep.spec import MAX_CELLS, Range, cell_count, cells_of, from_toml_text, parse_cli_value, parse_spec

PUSH_MAP = """
[fixed]
robot = "cassie"
[parameters]
tracker = ["pbc", "qp"]
push_direction_deg = { start = 0, stop = 315, step = 45 }
push_phase = { start = 0.0, stop = 0.8, num = 5 }
"""


def test_ranges_are_inclusive_and_rounded():
    assert Range(0.0, 0.8, num=5).points() == [0.0, 0.2, 0.4, 0.6, 0.8]  # not 0.6000000000000001
    assert Range(0, 315, step=45).points() == [0, 45, 90, 135, 180, 225, 270, 315]
    assert Range(0.1, 0.3, step=0.1).points() == [0.1, 0.2, 0.3]
    assert Range(1.5, 1.5, num=1).points() == [1.5]


def test_grid_is_the_product_with_the_first_parameter_slowest():
    cells = cells_of(parse_spec(from_toml_text(PUSH_MAP, "spec")))
    assert len(cells) == 2 * 8 * 5
    assert [c.index for c in cells] == list(range(80))
    assert dict(cells[0].swept) == {"tracker": "pbc", "push_direction_deg": 0, "push_phase": 0.0}
    assert dict(cells[1].swept) == {"tracker": "pbc", "push_direction_deg": 0, "push_phase": 0.2}
    assert dict(cells[40].swept)["tracker"] == "qp"
    assert all(c["robot"] == "cassie" for c in cells)
    assert len({c.id for c in cells}) == 80 and len({c.seed for c in cells}) == 80


def test_random_sampling_is_reproducible_inside_its_ranges_and_drops_duplicates():
    doc = {
        "sweep": {"sampling": "random", "samples": 30, "sampling_seed": 7},
        "parameters": {"vx": {"start": 0.2, "stop": 0.9}, "tracker": ["pbc", "qp"]},
    }
    a, b = cells_of(parse_spec(doc)), cells_of(parse_spec(doc))
    assert [c.id for c in a] == [c.id for c in b] and len(a) == 30
    assert all(0.2 <= c["vx"] <= 0.9 and c["tracker"] in ("pbc", "qp") for c in a)
    few = {"sweep": {"sampling": "random", "samples": 30}, "parameters": {"tracker": ["pbc", "qp"]}}
    assert sorted(c["tracker"] for c in cells_of(parse_spec(few))) == ["pbc", "qp"]
    other = {**doc, "sweep": {**doc["sweep"], "sampling_seed": 8}}
    assert [c.id for c in cells_of(parse_spec(other))] != [c.id for c in a]


@pytest.mark.parametrize(
    "text, expected",
    [("1", 1), ("-0.5", -0.5), ("1e-1", 0.1), ("true", True), ("qp", "qp"), ("slope:-15", "slope:-15")],
)
def test_cli_values_are_typed(text, expected):
    value = parse_cli_value(text)
    assert value == expected and type(value) is type(expected)


def test_malformed_toml_names_the_line():
    with pytest.raises(InputError, match=r"spec.toml: malformed TOML: .*line 3"):
        from_toml_text("[parameters]\nvx = [0.5,\ntracker = 1\n", "spec.toml")


@pytest.mark.parametrize(
    "doc, needle",
    [
        ({}, "empty grid"),
        ({"parameters": {"vx": []}}, "'vx' has an empty list"),
        ({"parameters": {"vx": {"start": 1.0, "stop": 0.5, "num": 2}}}, "start <= stop"),
        ({"parameters": {"vx": {"start": 0.0, "stop": 1.0, "num": 2, "step": 0.5}}}, "num or step, not both"),
        ({"parameters": {"vx": {"start": 0.0, "stop": 1.0, "num": 0}}}, "positive integer"),
        ({"parameters": {"vx": [[1]]}}, "a string, a finite number or a boolean"),
        ({"parameters": {"vx": [0.5]}, "fixed": {"vx": 1.0}}, "'vx' is given twice"),
        ({"parameters": {"vx": [0.5]}, "sweep": {"sampling": "latin"}}, "'grid' or 'random'"),
        ({"parameters": {"vx": [0.5]}, "sweep": {"sampling": "random"}}, "samples"),
        ({"parameters": {"vx": [0.5]}, "sweep": {"seed": 1}}, "unknown key 'seed' in [sweep]"),
        ({"parameters": {"vx": [0.5]}, "grid": {}}, "unknown section [grid]"),
        ({"parameters": {"vx": [0.5]}, "bisect": {"parameter": "push_impulse_Ns"}}, "[bisect] needs exactly"),
        (
            {"parameters": {"vx": [0.5]}, "bisect": {"parameter": "p", "low": 2, "high": 1, "iterations": 3}},
            "low < high",
        ),
    ],
)
def test_structural_errors_say_what_to_fix(doc, needle):
    with pytest.raises(InputError) as err:
        cells_of(parse_spec(doc))
    assert needle in str(err.value)


def test_ranges_count_their_points_without_listing_them():
    for r in (Range(0.0, 1.0, num=7), Range(0, 10, step=3), Range(0.0, 0.8, step=0.2), Range(0.0, 1.0, num=1)):
        assert r.count() == len(r.points())
    assert Range(0.0, 1.0, step=1e-12).count() == pytest.approx(1e12 + 1.0)
    assert Range(-1e308, 1e308, step=1e-308).count() == float("inf")


def test_the_cell_count_is_the_product_of_the_sizes_or_the_samples():
    grid = parse_spec({"parameters": {"tracker": ["pbc", "qp"], "vx": {"start": 0.0, "stop": 1.0, "num": 5}}})
    assert cell_count(grid) == len(cells_of(grid)) == 10
    sampled = parse_spec(
        {"parameters": {"vx": {"start": 0.0, "stop": 1.0}}, "sweep": {"sampling": "random", "samples": 9}}
    )
    assert cell_count(sampled) == 9


@pytest.mark.parametrize(
    "parameters, sampling, message",
    [
        (
            {"vx": {"start": 0.0, "stop": 1.0, "num": 10**9}},
            {},
            "the sweep has 1e+09 cells (1e+09); at most 100000 cells are run",
        ),
        (
            {"vx": {"start": 0.0, "stop": 1.0, "num": 1000}, "push_phase": {"start": 0.0, "stop": 0.8, "step": 0.0008}},
            {},
            "the sweep has 1.001e+06 cells (1000 x 1001); at most 100000 cells are run",
        ),
        ({"vx": {"start": 0.0, "stop": 1e308, "step": 1e-308}}, {}, "the sweep has inf cells (inf)"),
        (
            {"vx": {"start": 0.0, "stop": 1.0}},
            {"sampling": "random", "samples": 10**9},
            "the sweep has 1e+09 random samples; at most 100000 cells are run",
        ),
    ],
)
def test_a_sweep_above_the_cell_bound_is_refused_before_anything_is_expanded(
    parameters, sampling, message, monkeypatch
):
    def expanded(*args, **kwargs):
        raise AssertionError("a range was expanded")

    monkeypatch.setattr(spec_mod.Range, "points", expanded)
    doc = {"parameters": parameters, **({"sweep": sampling} if sampling else {})}
    with pytest.raises(InputError) as err:
        parse_spec(doc)
    assert message in str(err.value) and "\n" not in str(err.value)


def test_the_cell_bound_itself_is_accepted():
    doc = {
        "parameters": {"vx": {"start": 0.0, "stop": 1.0, "num": 1000}, "vy": {"start": 0.0, "stop": 0.1, "num": 100}}
    }
    assert cell_count(parse_spec(doc)) == MAX_CELLS
    doc["parameters"]["vy"]["num"] = 101
    with pytest.raises(InputError, match="101000 cells"):
        parse_spec(doc)


def test_bisection_iterations_are_bounded():
    base = {"parameters": {"vx": [0.5]}}
    ok = {
        **base,
        "bisect": {"parameter": "push_impulse_Ns", "low": 0, "high": 60, "iterations": MAX_BISECTION_ITERATIONS},
    }
    assert parse_spec(ok).bisect.iterations == 20
    ok["bisect"]["iterations"] = 10**9
    with pytest.raises(InputError, match=r"\[bisect\] iterations must be at most 20 .* got 1000000000"):
        parse_spec(ok)
