"""The step-timing MPC planner on its fast path (generated-C QP kernel, hot-started DAQP) and its bench."""

import json

import numpy as np
import pytest

from alip_point_mass import OUTPUTS, REACH_M, G, H, M, T, Walk
from amlip_qp.control.mpc import make_mpc_planner
from amlip_qp.control.mpc.bench import format_table, run_benchmark
from amlip_qp.exceptions import InputError
from amlip_qp.messages import Command
from codegen_cases import needs_cc

COMMAND = Command(step_time_s=T, com_height_m=H, clearance_m=0.1, vx_mps=0.5, step_width_m=0.25)
PUSH = (0.95, np.array([2.6, 0.0]))


@needs_cc
def test_the_compiled_planner_walks_the_numpy_planners_walk():
    """Through a push that activates the step-time and reach limits: the same steps to 1e-9."""
    walks = [
        Walk(make_mpc_planner(OUTPUTS, M, g=G, backend=b), COMMAND, reach_m=REACH_M).run(2.4, push=PUSH)
        for b in ("c", "numpy")
    ]
    c, ref = walks
    assert len(c.steps) == len(ref.steps) >= 9 and not c.fell
    for a, b in zip(c.steps, ref.steps):
        assert a[1] == pytest.approx(b[1], abs=1e-9)
        np.testing.assert_allclose(a[2], b[2], atol=1e-9)
    assert min(t1 - t0 for t0, t1, *_ in c.steps) == pytest.approx(0.6 * T, abs=1e-9)


def test_unknown_backend_raises():
    with pytest.raises(InputError, match="backend"):
        make_mpc_planner(OUTPUTS, M, backend="fortran")


@needs_cc
def test_bench_reports_the_solve_time_of_a_pushed_walk():
    result = run_benchmark(duration_s=1.5)
    assert result["ticks"] == 3000 and result["failures"] == 0 and not result["fell"]
    assert result["shortest_step_s"] < T - 0.05  # the push shortened a step
    for key in ("mpc_solve", "mpc_update", "one_step_update"):
        assert 0.0 < result[key]["median_us"] <= result[key]["p99_us"]
    assert "mpc_solve" in format_table(result)
    json.dumps(result)


@needs_cc
def test_bench_mpc_times_the_trackers_solve_in_turns_and_judges_the_goal():
    """``amlip-qp bench mpc``: the tracker's own solve (hot DAQP on Cassie) in turns of 50 ticks."""
    from amlip_qp.experiments.bench_mpc import BLOCK_TICKS, format_table, run, tracker_runner_name

    assert tracker_runner_name() == "daqp-tracker"  # Cassie's profile names DAQP
    result = run(duration_s=0.5)
    ts = result["tracker_solve"]
    assert result["ticks"] == 1000 and ts["problems"] == 1000 and ts["failures"] == 0
    assert ts["solves"] == (1000 // BLOCK_TICKS - 1) * BLOCK_TICKS  # a block after every 50 ticks but the last
    assert 0.0 < ts["median_us"] <= ts["p99_us"]
    assert result["goal_met"] == (result["mpc_solve"]["median_us"] <= ts["median_us"])
    table = format_table(result)
    assert "tracker_solve" in table and ("goal: mpc_solve median <= tracker_solve median: " in table)
    json.dumps(result)
