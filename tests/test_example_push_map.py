"""examples/push_map.py: it draws a finished push-map sweep and refuses bad input in one line (exit 2)."""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path

import pytest

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "push_map.py"


@pytest.fixture(scope="module")
def push_map():
    spec = importlib.util.spec_from_file_location("push_map_example", EXAMPLE)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _finished_sweep(folder: Path) -> None:
    """A hand-made finished push-map sweep: 2 trackers x 2 directions x 2 phases, one failed cell."""
    folder.mkdir()
    rows = ["cell,id,tracker,push_direction_deg,push_phase,seed,max_push_impulse_Ns,error"]
    k = 0
    for tracker, base in (("pbc", 30.0), ("qp", 60.0)):
        for direction in (0, 180):
            for phase in (0.0, 0.5):
                failed = tracker == "qp" and direction == 180 and phase == 0.5
                value = "" if failed else repr(base + direction / 10 + phase * 10)
                rows.append(f"{k},c{k},{tracker},{direction},{phase},{k},{value},{'RuntimeError: x' if failed else ''}")
                k += 1
    (folder / "results.csv").write_text("\n".join(rows) + "\n")
    summary = {"ran": 8, "wall_time_s": 60.0, "workers": 2, "backend": "process pool"}
    (folder / "summary.json").write_text(json.dumps(summary))
    (folder / "spec.json").write_text(json.dumps({"bisect": {"high": 100.0}}))


def test_it_draws_a_finished_sweep_with_a_failed_cell(push_map, tmp_path):
    _finished_sweep(tmp_path / "sweep")
    figure = tmp_path / "figs" / "map.png"
    assert push_map.main(["--from", str(tmp_path / "sweep"), "--figure", str(figure)]) == 0
    assert figure.stat().st_size > 10_000
    records = push_map.read_records(tmp_path / "sweep")
    assert [r["metrics"][push_map.VALUE] for r in records][:4] == [30.0, 35.0, 48.0, 53.0]
    assert sum(r["metrics"][push_map.VALUE] != r["metrics"][push_map.VALUE] for r in records) == 1  # the NaN


@pytest.mark.parametrize(
    "argv, needle",
    [
        (["--from", "{tmp}/missing"], "not a finished sweep folder (no results.csv, summary.json, spec.json)"),
        (["--from", "{tmp}/other"], "results.csv has no column tracker, push_direction_deg, push_phase, max_push"),
        (["--from", "{tmp}/sweep", "--figure", "/proc/no/such/map.png"], "--figure /proc/no/such/map.png"),
    ],
)
def test_bad_input_exits_2_with_one_line(push_map, tmp_path, capsys, argv, needle):
    _finished_sweep(tmp_path / "sweep")
    (tmp_path / "other").mkdir()
    for name in ("summary.json", "spec.json"):
        (tmp_path / "other" / name).write_text("{}")
    (tmp_path / "other" / "results.csv").write_text("cell,id,vx,survived\n0,a,0.5,true\n")
    assert push_map.main([a.replace("{tmp}", str(tmp_path)) for a in argv]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("push_map.py: error: ") and needle in err
