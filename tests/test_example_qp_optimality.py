"""``examples/qp_optimality.py``: each tick's QP solution against a fresh solve of the same problem."""

from __future__ import annotations

import importlib.util
import math
import pathlib

import numpy as np
import pytest

from amlip_qp.qp.daqp_solver import DAQPSolver
from amlip_qp.qp.problem import QPProblem

ROOT = pathlib.Path(__file__).resolve().parents[1]


def _module():
    spec = importlib.util.spec_from_file_location("qp_optimality", ROOT / "examples" / "qp_optimality.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _box_qp() -> QPProblem:
    """min 1/2 |x|^2 - x_0 over the box [-10, 10]^2 with x_0 + x_1 = 1: the optimum (1, 0), cost -1/2."""
    return QPProblem(
        np.eye(2), np.array([-1.0, 0.0]), np.array([[1.0, 1.0]]), np.array([1.0]),
        np.zeros((0, 2)), np.zeros(0), np.zeros(0), np.full(2, -10.0), np.full(2, 10.0),
    )  # fmt: skip


def test_a_feasible_point_above_the_optimum_is_off_and_the_optimum_is_not():
    module = _module()
    reference = DAQPSolver(warm_start=False)
    at = module.judge(0.5, _box_qp(), np.array([1.0, 0.0]), False, reference)
    assert not at.off and abs(at.excess_cost) < 1e-12 and at.dx < 1e-12
    # (0.9, 0.1) is feasible: its cost -0.49 is 0.01 above the optimum's -0.5, past 1e-3 of max(1, 0.5)
    above = module.judge(0.5, _box_qp(), np.array([0.9, 0.1]), False, reference)
    assert above.off and above.excess_cost == pytest.approx(0.01) and above.dx == pytest.approx(0.1)
    # (0.99, 0.01): 1e-4 above, within the tolerance
    near = module.judge(0.5, _box_qp(), np.array([1.0 - 0.01, 0.01]), False, reference)
    assert not near.off and near.excess_cost == pytest.approx(1e-4)
    relaxed = module.judge(0.5, _box_qp(), np.array([0.0, 0.0]), True, reference)
    assert not relaxed.off and math.isnan(relaxed.excess_cost)


def test_daqps_hot_started_solves_are_the_optimum_in_every_tick_of_a_walk():
    """Rabbit at 0.5 m/s for 1 s with DAQP hot-started from the last working set: every one of the 2000
    ticks solved, none without the torque rows, and each solution the optimum of its problem."""
    module = _module()
    ticks, outcome = module.walk("rabbit-0.5mps", "daqp", 0.0, 1.0)
    assert not outcome["fell"] and outcome["fallbacks"] == 0
    assert len(ticks) == 2000 and [k.t_s for k in ticks[:3]] == pytest.approx([0.0, 0.0005, 0.001])
    assert not any(k.relaxed or k.off for k in ticks)
    assert max(abs(k.excess_cost) for k in ticks) < 1e-6
    row = module.table_row("rabbit-0.5mps", "daqp", ticks, outcome)
    assert row == "| rabbit-0.5mps | daqp | walked, 0 fallbacks | 2000 | 0 | 0 | 0 |"


@pytest.mark.parametrize(
    "argv",
    [
        ["--solvers", "osqp"],
        ["--push", "-1"],
        ["--duration", "0"],
        ["--push", "10", "--duration", "3"],
        ["--duration", "1e9"],
        ["--push", "5000", "--duration", "4"],
        ["--scenario", "nope"],
    ],
)
def test_bad_options_exit_2_before_walking(argv, monkeypatch, capsys):
    module = _module()

    def no_walk(*args, **kwargs):
        raise AssertionError("a walk ran although the input was bad")

    monkeypatch.setattr(module, "walk", no_walk)
    with pytest.raises(SystemExit) as exc:
        module.main(argv)
    assert exc.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err[-1].startswith("usage:") is False and "error:" in err[-1]
