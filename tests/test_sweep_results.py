"""The sweep's output folder: reproducible table text, atomic records, refusing folders that are not ours."""

from __future__ import annotations

import json

import pytest

from amlip_qp.exceptions import InputError
from amlip_qp.sweep.results import SweepFolder, cell_text, metric_ranges


def test_table_cells_are_reproducible_text():
    assert [cell_text(v) for v in (0.1, 1 / 3, 2.0, 1e-300, None, float("nan"), True, False, 7, "qp")] == [
        "0.1", "0.3333333333333333", "2.0", "1e-300", "", "", "true", "false", "7", "qp",
    ]  # fmt: skip
    assert float(cell_text(1 / 3)) == 1 / 3  # round trip


def _record(index, vx, survived):
    metrics = {"survived": survived, "mean_vx_mps": vx * 0.9 if survived else float("nan")}
    params = {"vx": vx, "robot": "cassie"}
    return {"index": index, "id": f"c{index}", "seed": 5 + index, "params": params, "bisect": None, "metrics": metrics}


def test_records_round_trip_and_the_table_is_in_cell_order(tmp_path):
    folder = SweepFolder(tmp_path / "out", {"parameters": {"vx": [0.5, 1.0]}})
    folder.check()
    folder.prepare()
    saved = [folder.save(_record(1, 1.0, False)), folder.save(_record(0, 0.5, True))]
    assert saved[0]["metrics"]["mean_vx_mps"] is None  # NaN is JSON null
    assert folder.finished("c0") == saved[1] and folder.finished("missing") is None
    assert not [p for p in (tmp_path / "out" / "cells").iterdir() if p.name.startswith(".")]  # no temporary left
    folder.write_table(saved, ["vx"], ["survived", "mean_vx_mps"])
    text = (tmp_path / "out" / "results.csv").read_text()
    assert text == "cell,id,vx,seed,survived,mean_vx_mps,error\n0,c0,0.5,5,true,0.45,\n1,c1,1.0,6,false,,\n"
    assert metric_ranges(saved, ["survived", "mean_vx_mps"]) == {
        "survived": {"min": 0.0, "max": 1.0, "mean": 0.5},
        "mean_vx_mps": {"min": 0.45, "max": 0.45, "mean": 0.45},
    }
    (tmp_path / "out" / "cells" / "c1.json").write_text('{"id": "c1", "metr')  # a torn file: run the cell again
    assert folder.finished("c1") is None
    assert json.loads((tmp_path / "out" / "spec.json").read_text()) == {"parameters": {"vx": [0.5, 1.0]}}
    SweepFolder(tmp_path / "out", {"parameters": {"vx": [0.5, 1.0]}}).check()  # the same spec: resume


def test_a_failed_cell_is_in_the_table_and_runs_again(tmp_path):
    folder = SweepFolder(tmp_path / "out", {"parameters": {"vx": [0.5, 1.0]}})
    folder.prepare()
    failed = {**_record(1, 1.0, False), "metrics": {}, "error": "QPSolverError: the QP is infeasible"}
    saved = [folder.save(_record(0, 0.5, True)), folder.save(failed)]
    assert folder.finished("c0") == saved[0] and folder.finished("c1") is None  # retried on resume
    folder.write_table(saved, ["vx"], ["survived", "mean_vx_mps"])
    lines = (tmp_path / "out" / "results.csv").read_text().splitlines()
    assert lines[2] == "1,c1,1.0,6,,,QPSolverError: the QP is infeasible"
    assert metric_ranges(saved, ["survived"]) == {"survived": {"min": 1.0, "max": 1.0, "mean": 1.0}}


def test_a_file_is_not_an_output_folder(tmp_path):
    (tmp_path / "f").write_text("x")
    with pytest.raises(InputError, match="is a file"):
        SweepFolder(tmp_path / "f", {}).check()
