"""``amlip-qp sweep`` end to end: the same table on 1 worker, 2 workers and Ray; resume; bad input.

One small sweep (Rabbit, 2 trackers x 2 speeds, 0.8 s walks) runs once per
backend in a module-scoped fixture; Ray starts once, on loopback.
"""

from __future__ import annotations

import csv
import json
import shutil

import pytest

from amlip_qp.cli import main
from amlip_qp.sweep import backends
from amlip_qp.sweep import run_cell as rc

SWEEP = [
    "sweep", "--grid", "tracker=pbc,qp", "--grid", "vx=0.3,0.6", "--set", "robot=rabbit",
    "--set", "no_command_shaping=true", "--duration", "0.8", "--no-progress",
]  # fmt: skip


@pytest.fixture(scope="module")
def sweeps(tmp_path_factory):
    import ray

    base = tmp_path_factory.mktemp("sweeps")
    out = {}
    for name, extra in (("w1", ["--workers", "1"]), ("w2", ["--workers", "2"])):
        assert main([*SWEEP, "--out", str(base / name), *extra]) == 0
        out[name] = base / name
    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False, _node_ip_address="127.0.0.1")
    try:
        assert main([*SWEEP, "--out", str(base / "ray"), "--ray"]) == 0
    finally:
        ray.shutdown()
    out["ray"] = base / "ray"
    return out


def _rows(folder):
    with open(folder / "results.csv", newline="") as fh:
        return list(csv.DictReader(fh))


@pytest.mark.slow
def test_the_table_is_the_same_on_every_backend_and_worker_count(sweeps):
    one = (sweeps["w1"] / "results.csv").read_bytes()
    assert (sweeps["w2"] / "results.csv").read_bytes() == one
    assert (sweeps["ray"] / "results.csv").read_bytes() == one
    rows = _rows(sweeps["w1"])
    assert list(rows[0]) == [
        "cell", "id", "tracker", "vx", "seed", "survived", "fall_time_s", "steps", "mean_vx_mps",
        "velocity_error_rms", "foot_placement_error_rms_m", "error",
    ]  # fmt: skip
    assert all(r["error"] == "" for r in rows)
    assert [(r["cell"], r["tracker"], r["vx"]) for r in rows] == [
        ("0", "pbc", "0.3"), ("1", "pbc", "0.6"), ("2", "qp", "0.3"), ("3", "qp", "0.6")
    ]  # fmt: skip
    assert len({r["id"] for r in rows}) == 4 and len({r["seed"] for r in rows}) == 4
    for r in rows:  # a fall is a fall time and a short walk; a survivor walked the whole 0.8 s
        assert (r["survived"] == "true") == (r["fall_time_s"] == "") and int(r["steps"]) >= 1
        assert r["survived"] == "true" or 0.0 < float(r["fall_time_s"]) < 0.8
    assert all(r["survived"] == "true" for r in rows if r["vx"] == "0.3")
    slow, fast = (float(r["mean_vx_mps"]) for r in rows if r["tracker"] == "qp")
    assert fast > slow  # the QP tracker, asked for 0.6 m/s at once, moves forward faster than at 0.3 m/s


@pytest.mark.slow
def test_records_parquet_summary_and_figure_agree_with_the_table(sweeps):
    import pyarrow.parquet as pq

    folder = sweeps["w2"]
    rows = _rows(folder)
    table = pq.read_table(folder / "results.parquet").to_pylist()
    assert [t["id"] for t in table] == [r["id"] for r in rows]
    assert [repr(t["mean_vx_mps"]) for t in table] == [r["mean_vx_mps"] for r in rows]
    for r in rows:
        record = json.loads((folder / "cells" / f"{r['id']}.json").read_text())
        assert record["params"] == {"robot": "rabbit", "no_command_shaping": True, "duration": 0.8,
                                    "tracker": r["tracker"], "vx": float(r["vx"])}  # fmt: skip
        assert repr(record["metrics"]["mean_vx_mps"]) == r["mean_vx_mps"]
    summary = json.loads((folder / "summary.json").read_text())
    assert (summary["cells"], summary["ran"], summary["resumed"], summary["workers"]) == (4, 4, 0, 2)
    assert summary["figures"] == [str(folder / "map_line.png")] and (folder / "map_line.png").stat().st_size > 1000
    assert json.loads((sweeps["ray"] / "summary.json").read_text())["backend"].startswith("ray")


@pytest.mark.slow
def test_an_interrupted_sweep_resumes_with_only_the_missing_cell(sweeps, tmp_path):
    folder = tmp_path / "resume"
    shutil.copytree(sweeps["w1"], folder)
    victim = _rows(folder)[2]["id"]
    (folder / "cells" / f"{victim}.json").unlink()
    before = {p.name: p.read_bytes() for p in (folder / "cells").iterdir()}
    assert main([*SWEEP, "--out", str(folder), "--workers", "2"]) == 0
    summary = json.loads((folder / "summary.json").read_text())
    assert (summary["ran"], summary["resumed"]) == (1, 3)
    assert (folder / "results.csv").read_bytes() == (sweeps["w1"] / "results.csv").read_bytes()
    assert all((folder / "cells" / name).read_bytes() == data for name, data in before.items())  # untouched


BAD = [
    (["--grid", "speed=1,2"], "unknown parameter 'speed'; known: robot, tracker, planner, scenario, vx"),
    (["--grid", "vx=0.3,fast"], "vx: expected a number, got 'fast'"),
    (["--grid", "vx=0.3,9"], "outside rabbit's bounds"),
    (["--grid", "vx=,"], "no values: the grid would be empty"),
    (["--metrics", "speed"], "unknown metric 'speed'; known: survived"),
    (["{spec}"], "malformed TOML"),
    (["--ray", "10.255.255.1:6379"], "--ray 10.255.255.1:6379"),
    (["--bisect", "push_impulse_Ns=0:60"], "NAME=LOW:HIGH:ITERATIONS"),
    (["--bisect", "push_impulse_Ns=0:40:3", "--set", "push_phase=0.5", "--set", "push_time_s=0.3"], "one step late"),
    (["--bisect", "push_impulse_Ns=0:60:1000000000"], "[bisect] iterations must be at most 20"),
    (["--workers", "1000"], "argument --workers: expected a number of worker processes in [1, 64], got 1000"),
    (["--duration", "1e9"], "argument --duration: expected a number in [0.0005, 600] s, got '1e9'"),
    (["--duration", "1e-9"], "argument --duration: expected a number in [0.0005, 600] s, got '1e-9'"),
]


@pytest.mark.parametrize("extra, needle", BAD, ids=[" ".join(e) for e, _ in BAD])
def test_bad_input_exits_2_with_one_line_and_writes_nothing(extra, needle, tmp_path, capsys, monkeypatch):
    def no_run(*args, **kwargs):
        raise AssertionError("a cell ran")

    monkeypatch.setattr(backends, "run_local", no_run)
    monkeypatch.setattr(backends, "run_ray", no_run)
    spec = tmp_path / "bad.toml"
    spec.write_text("[parameters]\nvx = [0.3,\n")
    existing = tmp_path / "existing"  # a finished sweep of another spec: nothing in it may change
    (existing / "cells").mkdir(parents=True)
    (existing / "spec.json").write_text('{"parameters": {"vx": [1.0]}}\n')
    (existing / "results.csv").write_text("cell,id\n")
    snapshot = {p: p.read_bytes() for p in existing.rglob("*") if p.is_file()}
    for out in (tmp_path / "new", existing):
        argv = ["sweep", str(spec)] if extra == ["{spec}"] else [*SWEEP, *extra]
        try:
            code = main([*argv, "--out", str(out)])
        except SystemExit as exc:  # refused while the command line is read
            code = exc.code
        err = capsys.readouterr().err
        lines = err.strip().splitlines()
        assert code == 2 and len(lines) == 1 and lines[0].startswith(("amlip-qp: error:", "amlip-qp sweep: error:")), (
            err
        )
        assert "Traceback" not in err
        assert out == existing or needle in lines[0]  # the other sweep's folder may be refused first
    assert not (tmp_path / "new").exists()
    assert {p: p.read_bytes() for p in existing.rglob("*") if p.is_file()} == snapshot


def test_a_sweep_of_1e9_cells_is_refused_in_one_line_before_any_cell_exists(tmp_path, capsys, monkeypatch):
    from amlip_qp.sweep import spec as spec_mod

    def expanded(*args, **kwargs):
        raise AssertionError("the cells were expanded")

    monkeypatch.setattr(spec_mod.Range, "points", expanded)
    monkeypatch.setattr(spec_mod, "cells_of", expanded)
    spec = tmp_path / "huge.toml"
    spec.write_text(
        "[fixed]\nrobot = 'rabbit'\n[parameters]\nvx = { start = 0.0, stop = 1.0, num = 1000 }\n"
        "push_phase = { start = 0.0, stop = 0.8, num = 1000 }\n"
        "push_direction_deg = { start = 0, stop = 359, step = 0.359 }\n"
    )
    code = main(["sweep", str(spec), "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert code == 2
    assert err == (
        "amlip-qp: error: the sweep has 1.001e+09 cells (1000 x 1000 x 1001); at most 100000 cells are run "
        "(each is checked, then walked, for seconds): split it or sample it (sampling = 'random')\n"
    )
    assert not (tmp_path / "out").exists()


def test_a_cell_shorter_than_a_control_tick_is_bad_input_not_a_failed_cell(tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(backends, "run_local", lambda *a, **k: pytest.fail("a cell ran"))
    code = main([*SWEEP[:-3], "--set", "duration=1e-9", "--no-progress", "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1
    assert "duration 1e-09 s is shorter than one control tick (0.0005 s)" in err
    assert not (tmp_path / "out").exists()


def test_a_folder_of_another_sweep_or_files_is_refused(tmp_path, capsys):
    other = tmp_path / "other"
    other.mkdir()
    (other / "notes.txt").write_text("mine\n")
    assert main([*SWEEP, "--out", str(other)]) == 2
    assert "not empty and holds no sweep" in capsys.readouterr().err
    existing = tmp_path / "existing"
    existing.mkdir()
    (existing / "spec.json").write_text('{"parameters": {"vx": [1.0]}}\n')
    assert main([*SWEEP, "--out", str(existing)]) == 2
    assert "holds the sweep of another spec" in capsys.readouterr().err
    assert sorted(p.name for p in existing.iterdir()) == ["spec.json"]


def test_a_failing_cell_is_recorded_the_others_finish_and_a_rerun_retries_it(tmp_path, capsys, monkeypatch):
    """A stand-in walk (no simulation) that raises for one cell; the cells run in this process."""
    broken = {"on": True}

    def fake_walk(run):
        if broken["on"] and run.tracker == "qp" and run.scenario.vx(0.5) == 0.6:
            raise RuntimeError("the QP solver failed\ndetails")
        return dict.fromkeys(rc.METRICS, 0.0) | {"survived": True, "fell": False, "steps": 3}

    def serial(tasks, workers, on_record):
        for task in tasks:
            on_record(rc.run_cell(task))

    monkeypatch.setattr(rc, "walk", fake_walk)
    monkeypatch.setattr(backends, "run_local", serial)
    out = tmp_path / "out"
    assert main([*SWEEP, "--out", str(out)]) == 1
    captured = capsys.readouterr()
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1 and "1 of 4 cells failed (first: cell 3: RuntimeError: the QP solver failed)" in lines[0]
    rows = _rows(out)
    assert [r["error"] for r in rows] == ["", "", "", "RuntimeError: the QP solver failed"]
    assert rows[3]["survived"] == "" and all(r["survived"] == "true" for r in rows[:3])
    summary = json.loads((out / "summary.json").read_text())
    assert summary["failed"] == 1 and summary["failed_cells"][0]["cell"] == 3
    broken["on"] = False
    assert main([*SWEEP, "--out", str(out)]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert (summary["ran"], summary["resumed"], summary["failed"]) == (1, 3, 0)
    assert [r["error"] for r in _rows(out)] == [""] * 4
