"""``amlip-qp bench sweep``: its cells and the interleaved ratio it reports (no timing is asserted)."""

from __future__ import annotations

import json

from amlip_qp.cli import main
from amlip_qp.sweep import bench


def test_bench_cells_are_distinct_walks():
    cells = bench.bench_cells(4, 1.5, "pbc")
    assert [c["vx"] for c in cells] == [0.0, 0.333333, 0.666667, 1.0]
    assert all((c["tracker"], c["duration"], c["robot"]) == ("pbc", 1.5, "cassie") for c in cells)
    assert len({c.id for c in cells}) == 4


def test_bench_interleaves_and_reports_the_median_ratio(monkeypatch, tmp_path, capsys):
    calls = []
    rates = iter([1.0, 1.9, 1.0, 1.5, 2.0, 4.0])  # ratios 1.9, 1.5, 2.0: median 1.9

    def fake(cells, workers):
        calls.append(workers)
        return next(rates)

    monkeypatch.setattr(bench, "throughput", fake)
    out = tmp_path / "b.json"
    assert main(["bench", "sweep", "--cells", "2", "--duration", "0.5", "--repeats", "3", "--json", str(out)]) == 0
    result = json.loads(out.read_text())
    assert calls == [1, 2, 1, 2, 1, 2]
    assert [r["ratio"] for r in result["repeats"]] == [1.9, 1.5, 2.0] and result["median_ratio"] == 1.9
    assert result["cores"] >= 1 and len(result["load_average_before"]) == 3


def test_a_failed_bench_cell_stops_the_bench_with_its_error(monkeypatch, capsys):
    from amlip_qp.sweep import backends

    def failing(tasks, workers, on_record):
        on_record({**tasks[0], "metrics": {}, "error": "RuntimeError: the QP solver failed"})

    monkeypatch.setattr(backends, "run_local", failing)
    assert main(["bench", "sweep", "--cells", "2", "--duration", "0.5", "--repeats", "1"]) == 1
    err = capsys.readouterr().err
    assert "bench sweep: cell 0 failed: RuntimeError: the QP solver failed" in err and err.count("\n") == 1
