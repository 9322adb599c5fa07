"""``amlip-qp bench harness``: where a closed-loop tick goes (numbers, not speed goals)."""

from __future__ import annotations

import json
import re

import pytest

from amlip_qp import cli
from amlip_qp.exceptions import InputError
from amlip_qp.experiments import bench_harness


def test_the_report_splits_each_tick_for_every_tracker_and_log_mode():
    r = bench_harness.run(duration_s=0.05, repeats=2, trackers=("pbc",))
    assert set(r["runs"]) == {"pbc/full", "pbc/summary"}
    for row in r["runs"].values():
        assert row["ticks"] == 2 * 100 and not row["fell"]
        parts = (row["controller_us_per_tick"], row["mujoco_us_per_tick"], row["harness_us_per_tick"])
        assert min(parts) > 0.0 and row["sum_us_per_tick"] == pytest.approx(sum(parts))
        assert row["realtime_factor"] > 0.0
    assert r["same_summary"] == {"pbc": True}  # both modes walk the same trajectory
    assert r["qp_meets_realtime_goal"] == {}  # no QP walk timed
    for row in r["runs"].values():
        # the loop's wall time holds the three timed parts (and nothing of them twice)
        assert row["tick_per_mujoco"] > 1.0 + row["harness_per_mujoco"]
        ref = bench_harness.REFERENCE_TICK_PER_MUJOCO
        assert row["realtime_factor_at_reference"] == pytest.approx(0.65 * ref / row["tick_per_mujoco"])
        assert row["step_alone_us"] > 0.0 and row["tick_per_step"] > row["harness_per_step"] > 0.0
    assert r["harness_meets_goal"] == {}  # the reference's walks were QP walks: no verdict on a PBC walk
    for row in r["runs"].values():
        # the tick in MuJoCo steps: each step of the yardstick timed alone, medians; the PBC's goals
        assert row["step_median_us"] > 0.0 and row["controller_per_step"] > row["tracker_per_step"] > 0.0
        assert row["tracker_us_per_tick"] < row["controller_us_per_tick"]
        assert row["controller_per_loop_step"] > row["tracker_per_loop_step"] > 0.0
        goals = row["speed_goals"]
        assert set(goals) == {"controller_steps", "realtime_factor"}  # cassie-1mps: Cassie's nominal walk
        assert goals["controller_steps"] == {
            "goal": 6.0, "value": row["controller_per_loop_step"], "met": row["controller_per_loop_step"] <= 6.0
        }  # fmt: skip
        assert goals["realtime_factor"]["goal"] == 1.5
        assert goals["realtime_factor"]["met"] == (row["realtime_factor"] >= 1.5)
    text = bench_harness.format_report(r)
    for key, row in r["runs"].items():
        # the PBC's own work in its parts: the IK, the swing compensation and the dynamics each a positive
        # share of MuJoCo's step and less than the whole work, and a line of the table per row
        parts = row["tracker_parts_per_loop_step"]
        assert set(parts) == {"kinematics", "ik", "compensation", "dynamics", "rest"} and min(parts.values()) > 0.0
        assert max(parts["ik"], parts["dynamics"], parts["compensation"]) < row["tracker_per_loop_step"]
        assert re.search(rf"{key}\s+kinematics\s+{parts['kinematics']:.2f}\s+ik\s+{parts['ik']:.2f}", text)
    assert "the kinematics update, the IK, the swing compensation" in text and "the problem's build" not in text
    assert "pbc/summary" in text and "same summary in both log modes: pbc: yes" in text
    assert "a cassie-1mps qp walk of 13.20 MuJoCo steps of wall time per tick (harness 3.01) ran at 0.65x" in text
    assert "no verdict on the goals" in text


@pytest.mark.parametrize("scenario", ["cassie-1mps", "rabbit-0.5mps"])
def test_the_goals_are_judged_on_the_reference_walk_only(scenario):
    r = bench_harness.run(scenario=scenario, duration_s=0.05, repeats=1, trackers=("qp",))
    text = bench_harness.format_report(r)
    goals = r["runs"]["qp/summary"]["speed_goals"]
    assert goals["controller_steps"]["goal"] == 3.0 and goals["tracker_steps"]["goal"] == 2.0
    assert goals["tracker_steps"]["met"] == (r["runs"]["qp/summary"]["tracker_per_loop_step"] <= 2.0)
    # a real-time goal only where the robot's profile sets one for its nominal walk (Rabbit's sets none)
    assert ("realtime_factor" in goals) == (scenario == "cassie-1mps")
    assert "tick <= 3 steps: " in text and "tracker <= 2 steps: " in text
    for key, row in r["runs"].items():
        # the tracker's work in its parts, each a positive share of MuJoCo's step (its solver's call and
        # its build each less than the whole work), and a line of the table per row
        parts = row["tracker_parts_per_loop_step"]
        assert set(parts) == {"kinematics", "build", "solve", "rest"} and min(parts.values()) > 0.0
        assert max(parts["build"], parts["solve"], parts["kinematics"]) < row["tracker_per_loop_step"]
        assert re.search(rf"{key}\s+kinematics\s+{parts['kinematics']:.2f}\s+build\s+{parts['build']:.2f}", text)
        # the controller's tick in its parts: each a positive share, together the whole tick's median or near it
        # (medians of parts need not add up), the tracker's work the same as the goal's
        ticked = row["controller_parts_per_loop_step"]
        assert set(ticked) == {"estimate", "plan", "tracker", "rest"} and min(ticked.values()) > 0.0
        assert ticked["tracker"] == pytest.approx(row["tracker_per_loop_step"])
        assert sum(ticked.values()) == pytest.approx(row["controller_per_loop_step"], rel=0.25)
        assert re.search(rf"{key}\s+estimate\s+{ticked['estimate']:.2f}\s+plan\s+{ticked['plan']:.2f}", text)
    if scenario != bench_harness.REFERENCE_SCENARIO:
        assert r["qp_meets_realtime_goal"] == {} and r["harness_meets_goal"] == {}
        assert "no verdict on the goals" in text
        return
    row = r["runs"]["qp/summary"]
    assert r["qp_meets_realtime_goal"] == {"qp/summary": row["realtime_factor_at_reference"] >= 1.0}
    goal = bench_harness.REFERENCE_HARNESS_PER_MUJOCO / 4
    assert r["harness_meets_goal"] == {k: row["harness_per_mujoco"] <= goal for k, row in r["runs"].items()}
    assert f"harness <= {goal:.2f} MuJoCo steps per tick" in text and "qp/summary walk at >= 1x real time" in text


def test_the_verdicts_state_the_goals_as_numbers_and_name_no_commit():
    """A reader checks a verdict against the numbers it prints: 0.75 MuJoCo steps per tick for the
    harness, 1.0x real time (8.58 MuJoCo steps of wall time per tick) for the walk."""
    assert bench_harness.GOAL_HARNESS_PER_MUJOCO == pytest.approx(3.01 / 4)
    assert bench_harness.GOAL_TICK_PER_MUJOCO == pytest.approx(0.65 * 13.2)
    r = bench_harness.run(duration_s=0.05, repeats=1, trackers=("qp",))
    text = bench_harness.format_report(r)
    assert "harness <= 0.75 MuJoCo steps per tick: " in text
    assert "qp/summary walk at >= 1x real time on that machine state (<= 8.58 MuJoCo steps per tick): " in text
    assert r["goal_tick_per_mujoco"] == pytest.approx(8.58) and r["goal_harness_per_mujoco"] == pytest.approx(0.7525)
    assert "commit" not in r["reference"] and not hasattr(bench_harness, "REFERENCE_COMMIT")
    assert re.search(r"\b(?=[0-9a-f]*[a-f])(?=[0-9a-f]*[0-9])[0-9a-f]{7,40}\b", text) is None, "a commit hash"
    assert "commit" not in text.lower() and "issue" not in text.lower()


def test_the_gathered_qp_variant_is_timed_and_judged_too():
    r = bench_harness.run(duration_s=0.05, repeats=1, trackers=("qp-gathered",))
    assert set(r["runs"]) == {"qp-gathered/full", "qp-gathered/summary"} and r["same_summary"] == {"qp-gathered": True}
    row = r["runs"]["qp-gathered/summary"]
    assert r["qp_meets_realtime_goal"] == {"qp-gathered/summary": row["realtime_factor_at_reference"] >= 1.0}
    assert set(r["harness_meets_goal"]) == {"qp-gathered/full", "qp-gathered/summary"}
    assert "qp-gathered/summary walk at >= 1x real time" in bench_harness.format_report(r)
    tracker = bench_harness.tracker_for(bench_harness.get_scenario("cassie-1mps"), "qp-gathered")
    assert tracker.build_backend == "c"
    assert bench_harness.tracker_for(bench_harness.get_scenario("cassie-1mps"), "qp") == "qp"


def test_bad_trackers_and_counts_are_refused_before_simulating():
    with pytest.raises(InputError, match="unknown trackers"):
        bench_harness.run(trackers=("lqr",))
    with pytest.raises(InputError, match="repeats >= 1"):
        bench_harness.run(repeats=0)


def test_the_cli_runs_it(capsys, tmp_path):
    out = tmp_path / "bench.json"
    code = cli.main(
        ["bench", "harness", "--duration", "0.02", "--repeats", "1", "--trackers", "pbc", "--json", str(out)]
    )
    assert code == 0 and out.is_file()
    assert "pbc/full" in capsys.readouterr().out


def test_robots_stands_for_every_bundled_robots_nominal_walk():
    names = bench_harness.scenario_names("robots")
    assert names == ("cassie-1mps", "g1-1mps", "h1-1mps", "rabbit-0.5mps")
    assert bench_harness.scenario_names(" h1-1mps, robots ") == ("h1-1mps", "cassie-1mps", "g1-1mps", "rabbit-0.5mps")
    with pytest.raises(InputError, match="expected scenario names"):
        bench_harness.scenario_names(" , ")
    with pytest.raises(InputError, match="nowhere"):
        bench_harness.scenario_names("cassie-1mps,nowhere")


def test_several_scenarios_give_one_table_each_and_one_json_list(tmp_path, capsys):
    out = tmp_path / "h.json"
    code = cli.main(
        ["bench", "harness", "--scenario", "g1-1mps,h1-1mps", "--duration", "0.02", "--repeats", "1",
         "--trackers", "qp", "--json", str(out)]
    )  # fmt: skip
    assert code == 0
    text = capsys.readouterr().out
    assert "closed-loop tick, g1-1mps" in text and "closed-loop tick, h1-1mps" in text
    reports = json.loads(out.read_text())["scenarios"]
    assert [r["scenario"] for r in reports] == ["g1-1mps", "h1-1mps"]
    assert all(r["runs"]["qp/summary"]["ticks"] == 40 for r in reports)
