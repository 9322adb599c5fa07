"""The sweep's figures: which one for which sweep, and the grid they are drawn from."""

from __future__ import annotations

import itertools
import math

from amlip_qp.sweep.figures import grid_values, sweep_figures
from amlip_qp.sweep.spec import parse_spec


def _records(params: dict[str, list], value) -> list[dict]:
    names = list(params)
    return [
        {"params": dict(zip(names, combo)), "metrics": {"m": value(dict(zip(names, combo)))}}
        for combo in itertools.product(*params.values())
    ]


def test_grid_values_place_each_cell_and_leave_missing_ones_nan():
    recs = _records({"tracker": ["qp"], "a": [1, 2, 3], "b": [10, 20]}, lambda p: p["a"] * p["b"])
    xs, ys, z = grid_values(recs[:-1], "a", "b", "m", {"tracker": "qp"})
    assert (xs, ys) == ([1, 2, 3], [10, 20])
    assert z[0].tolist() == [10.0, 20.0, 30.0] and z[1, :2].tolist() == [20.0, 40.0] and math.isnan(z[1, 2])


def test_each_sweep_shape_gets_its_figure(tmp_path):
    polar = {"tracker": ["pbc", "qp"], "push_direction_deg": [0, 90, 180, 270], "push_phase": [0.0, 0.5]}
    recs = _records(polar, lambda p: p["push_direction_deg"] / 10.0)
    spec = parse_spec({"parameters": polar})
    assert sweep_figures(tmp_path, spec, recs, ["m"]) == [str(tmp_path / "map_polar.png")]
    heat = {"terrain": ["flat", "slope:5"], "vx": [0.5, 1.0]}
    spec = parse_spec({"parameters": heat})
    assert sweep_figures(tmp_path, spec, _records(heat, lambda p: p["vx"] > 0.6), ["m"]) == [
        str(tmp_path / "map_heat.png")
    ]
    line = {"tracker": ["pbc", "qp"], "vx": [0.5, 1.0]}
    spec = parse_spec({"parameters": line})
    assert sweep_figures(tmp_path, spec, _records(line, lambda p: p["vx"]), ["m"]) == [str(tmp_path / "map_line.png")]
    for name in ("map_polar.png", "map_heat.png", "map_line.png"):
        assert (tmp_path / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    three = {"a": [1], "b": [2], "c": [3]}
    assert sweep_figures(tmp_path, parse_spec({"parameters": three}), _records(three, lambda p: 1.0), ["m"]) == []
    rnd = parse_spec({"parameters": line, "sweep": {"sampling": "random", "samples": 3}})
    assert sweep_figures(tmp_path, rnd, _records(line, lambda p: 1.0), ["m"]) == []
