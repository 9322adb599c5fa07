"""``amlip-qp bench codegen`` prints a table and writes JSON with the documented schema."""

from __future__ import annotations

import json

import pytest

from amlip_qp.cli import main

PATHS = {"c-fast", "casadi-function", "numpy"}


@pytest.fixture(autouse=True)
def _shared_cache(shared_cache_dir, monkeypatch):
    monkeypatch.setenv("AMLIP_QP_CACHE_DIR", str(shared_cache_dir))


def _check_schema(result):
    assert set(result["paths"]) == PATHS
    for stats in result["paths"].values():
        assert 0 < stats["median_us"] <= stats["p99_us"]
    for kernel in ("alip_plan", "swing_reference"):
        assert set(result["per_kernel"][kernel]) == PATHS
    assert set(result["per_tick"]) == PATHS
    assert result["c_fast_backend"] == "c"


def test_bench_json_file_and_table(tmp_path, capsys):
    out = tmp_path / "bench.json"
    assert main(["bench", "codegen", "--calls", "30", "--json", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "c-fast" in printed and "casadi-function" in printed and "median_us" in printed
    result = json.loads(out.read_text())
    _check_schema(result)
    assert result["calls"] == 30


def test_bench_json_to_stdout_is_pure_json(capsys):
    assert main(["bench", "codegen", "--calls", "20", "--json", "-"]) == 0
    captured = capsys.readouterr()
    _check_schema(json.loads(captured.out))
    assert "median_us" in captured.err


def test_bench_rejects_non_positive_calls(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["bench", "codegen", "--calls", "0"])
    assert exc.value.code == 2
