"""``amlip-qp bench ekf``: the EKF's cost inside the closed loop (numbers, not speed goals)."""

from __future__ import annotations

import numpy as np
import pytest

from amlip_qp.exceptions import InputError
from amlip_qp.experiments import bench_ekf


def test_the_report_times_the_ekf_inside_each_tick_and_its_ratio_to_the_rest():
    r = bench_ekf.run(duration_s=0.25)
    assert r["ticks"] == 500 and not r["fell"]
    ekf, rest, tick = r["ekf_fill_us"], r["tick_without_ekf_us"], r["tick_us"]
    assert 0.0 < ekf["median"] < tick["median"]
    assert 0.0 < rest["median"] < tick["median"]
    assert r["ratio_median"] == pytest.approx(ekf["median"] / rest["median"])
    assert r["meets_goal"] == (r["ratio_median"] <= bench_ekf.GOAL_FRACTION)
    text = bench_ekf.format_report(r)
    assert "EKF fill" in text and f"{100 * r['ratio_median']:.1f} %" in text


def test_a_scenario_without_the_ekf_is_refused_before_simulating():
    with pytest.raises(InputError, match="needs a scenario with the EKF estimator"):
        bench_ekf.run(scenario="cassie-1mps")
    assert np.isclose(bench_ekf.GOAL_FRACTION, 0.15)
