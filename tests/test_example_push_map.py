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
    summary = {
        "cells": 8, "ran": 8, "failed": 1, "wall_time_s": 60.0, "workers": 2, "backend": "process pool",
        "cell_wall_s_total": 110.0,
    }  # fmt: skip
    (folder / "summary.json").write_text(json.dumps(summary))
    (folder / "spec.json").write_text(json.dumps({"bisect": {"high": 100.0}}))


def test_it_draws_a_finished_sweep_with_a_failed_cell(push_map, tmp_path, capsys):
    _finished_sweep(tmp_path / "sweep")
    figure = tmp_path / "figs" / "map.png"
    table = tmp_path / "figs" / "results.csv"
    assert push_map.main(["--from", str(tmp_path / "sweep"), "--figure", str(figure), "--csv", str(table)]) == 0
    assert figure.stat().st_size > 10_000
    assert table.read_text() == (tmp_path / "sweep" / "results.csv").read_text()
    # PBC 30, 35, 48, 53; QP 60, 65, 78 and a failed cell: the summary table on standard output
    assert capsys.readouterr().out.splitlines() == [
        "| | PBC | QP |",
        "|---|---|---|",
        "| largest impulse survived, median over the cells, N s | 41.5 | 65.0 |",
        "| mean (least – largest), N s | 41.5 (30.0 – 53.0) | 67.7 (60.0 – 78.0) |",
        "| cells at the top of the range (≥ 100 N s) | 0 | 0 |",
        "| cells measured (failed) | 4 (0) | 3 (1) |",
        "| cells where it survives more than the other tracker | 0 | 3 |",
        "",
        "Per cell QP / PBC: median 1.86 (1.62 – 2.00); 0 cells the same. "
        "8 cells, 0 walks, 110 s of cell time; the sweep: 1 min wall on 2 worker(s).",
    ]
    records = push_map.read_records(tmp_path / "sweep")
    assert [r["metrics"][push_map.VALUE] for r in records][:4] == [30.0, 35.0, 48.0, 53.0]
    assert sum(r["metrics"][push_map.VALUE] != r["metrics"][push_map.VALUE] for r in records) == 1  # the NaN


def test_a_sweep_that_varies_the_planner_is_compared_by_planner(push_map, tmp_path, capsys):
    """One tracker, two planners: the groups are the planners, the ratio MPC / one-step, with its medians and
    weakest cells (one-step 30, 40, 50; MPC 45, 50, 60: medians 1.25, weakest cells 1.5)."""
    folder = tmp_path / "sweep"
    folder.mkdir()
    rows = ["cell,id,tracker,planner,push_direction_deg,push_phase,seed,max_push_impulse_Ns,error"]
    values = {"one-step": (30.0, 40.0, 50.0), "mpc": (45.0, 50.0, 60.0)}
    for planner, impulses in values.items():
        for direction, value in zip((0, 90, 180), impulses):
            rows.append(f"{len(rows)},c{len(rows)},qp,{planner},{direction},0.0,0,{value!r},")
    (folder / "results.csv").write_text("\n".join(rows) + "\n")
    summary = {"cells": 6, "ran": 6, "failed": 0, "wall_time_s": 60.0, "workers": 1, "cell_wall_s_total": 60.0}
    (folder / "summary.json").write_text(json.dumps(summary))
    (folder / "spec.json").write_text(json.dumps({"bisect": {"high": 100.0}}))
    assert push_map.main(["--from", str(folder), "--figure", str(tmp_path / "map.png")]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[0] == "| | one-step | MPC |"
    assert out[2] == "| largest impulse survived, median over the cells, N s | 40.0 | 50.0 |"
    assert out[6] == "| cells where it survives more than the other planner | 0 | 3 |"
    assert "MPC / one-step: the medians 1.25, the weakest cells 1.50." in out[-1]


def test_against_compares_the_mpc_cells_with_one_step_cells_measured_before(push_map, tmp_path, capsys):
    """A sweep of the PBC with the MPC only, against a tracker map's results.csv (no planner column): its PBC
    cells are the one-step law's, its QP cells are left out (one-step 30, 40, 50; MPC 45, 50, 60)."""
    old = tmp_path / "old.csv"
    rows = ["cell,id,tracker,push_direction_deg,push_phase,seed,max_push_impulse_Ns,error"]
    for tracker, impulses in (("pbc", (30.0, 40.0, 50.0)), ("qp", (90.0, 90.0, 90.0))):
        for direction, value in zip((0, 90, 180), impulses):
            rows.append(f"{len(rows)},c{len(rows)},{tracker},{direction},0.0,0,{value!r},")
    old.write_text("\n".join(rows) + "\n")
    folder = tmp_path / "sweep"
    folder.mkdir()
    rows = ["cell,id,tracker,planner,push_direction_deg,push_phase,seed,max_push_impulse_Ns,bisect_walks,error"]
    for direction, value in zip((0, 90, 180), (45.0, 50.0, 60.0)):
        rows.append(f"{len(rows)},c{len(rows)},pbc,mpc,{direction},0.0,0,{value!r},6,")
    (folder / "results.csv").write_text("\n".join(rows) + "\n")
    summary = {"cells": 3, "ran": 3, "failed": 0, "wall_time_s": 60.0, "workers": 1, "cell_wall_s_total": 60.0}
    (folder / "summary.json").write_text(json.dumps(summary))
    (folder / "spec.json").write_text(json.dumps({"bisect": {"high": 100.0}}))
    argv = ["--from", str(folder), "--figure", str(tmp_path / "map.png"), "--against", str(old)]
    assert push_map.main(argv) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[0] == "| | one-step | MPC |"
    assert out[2] == "| largest impulse survived, median over the cells, N s | 40.0 | 50.0 |"
    assert out[5] == "| cells measured (failed) | 3 (0) | 3 (0) |"
    assert "MPC / one-step: the medians 1.25, the weakest cells 1.50." in out[-1]
    assert "3 cells, 18 walks, 60 s of cell time; the 3 other cells from old.csv;" in out[-1]
    assert push_map.main([*argv[:4], "--against", str(tmp_path / "none.csv")]) == 2
    assert "--against" in capsys.readouterr().err


def test_out_draws_a_finished_sweep_without_running_it_again(push_map, tmp_path, monkeypatch, capsys):
    _finished_sweep(tmp_path / "sweep")
    monkeypatch.setattr(push_map, "amlip_qp_main", lambda argv: pytest.fail("ran the sweep"))
    assert not push_map.finished(tmp_path / "sweep")  # a failed cell: --out runs the sweep to retry it
    rows = (tmp_path / "sweep" / "results.csv").read_text().replace(",,RuntimeError: x", ",99.0,")
    (tmp_path / "sweep" / "results.csv").write_text(rows)
    summary = json.loads((tmp_path / "sweep" / "summary.json").read_text())
    (tmp_path / "sweep" / "summary.json").write_text(json.dumps({**summary, "failed": 0, "ran": 1, "resumed": 7}))
    assert push_map.finished(tmp_path / "sweep")
    assert push_map.main(["--out", str(tmp_path / "sweep")]) == 0
    out = capsys.readouterr().out
    assert "| cells measured (failed) | 4 (0) | 4 (0) |" in out
    assert out.endswith("its last run: 1 cells in 1 min wall on 2 worker(s), 7 cells run before.\n")


@pytest.mark.parametrize(
    "argv, needle",
    [
        (["--from", "{tmp}/missing"], "not a finished sweep folder (no results.csv, summary.json, spec.json)"),
        (["--from", "{tmp}/other"], "results.csv has no column tracker, push_direction_deg, push_phase, max_push"),
        (["--from", "{tmp}/sweep", "--figure", "/proc/no/such/map.png"], "--figure /proc/no/such/map.png"),
        (["--from", "{tmp}/sweep", "--csv", "/proc/no/such/results.csv"], "--csv /proc/no/such/results.csv"),
        (["--out", "{tmp}/new", "--workers", "0"], "--workers must be 1 to 64, got 0"),
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
