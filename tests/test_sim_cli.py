"""``amlip-qp walk`` and ``amlip-qp compare``: bad input, outputs, determinism.

Runs are tiny (a stand-in zero-torque tracker falls within half a second);
walking quality is the trackers' own tests' business.
"""

from __future__ import annotations

import json
import subprocess
import sys
import warnings

import numpy as np
import pytest

from amlip_qp import cli
from amlip_qp.control import registry
from amlip_qp.exceptions import InputError
from amlip_qp.sim.reports.summary import TIMING_FIELDS
from amlip_qp.sim.scenarios import factory
from cli_bad_input_support import run_main
from stand_ins import ZeroTracker

SUMMARY_KEYS = {
    "robot", "tracker", "scenario", "seed", "noise", "duration_s", "sim_time_s", "fell", "fall_time_s", "steps",
    "commanded_velocity", "mean_velocity", "velocity_error_rms", "heading_change_deg", "foot_placement_error_rms_m",
    "L_end_of_step_error_rms", "L_end_of_step_error_rms_xy", "output_tracking_rms", "torque_peak_Nm", "torque_rms_Nm",
    "tick_time_us", "realtime_factor", "fallback_ticks", "tracker_failed_ticks", "settle_s",
    "plant", "sensors", "estimator", "plant_modifiers", "terrain", "safe_mode_ticks", "estimator_divergences",
    "base_velocity_error_rms_mps", "yaw_estimate_error_deg",
    "controller_us_per_tick", "mujoco_us_per_tick", "harness_us_per_tick",
}  # fmt: skip


@pytest.fixture
def stand_in(monkeypatch):
    """Every tracker name builds the zero-torque stand-in."""
    monkeypatch.setattr(registry, "make_tracker", lambda name, robot: ZeroTracker(robot))
    monkeypatch.setattr(registry, "tracker_class", lambda name: ZeroTracker)


@pytest.mark.parametrize(
    "argv",
    [
        ["walk", "--push", "1:2,3:0.2"],
        ["walk", "--push", "1:a,0,0:0.2"],
        ["walk", "--push", "-1:1,0,0:0.2"],
        ["walk", "--push", "1:1,0,0:0"],
        ["walk", "--duration", "-1"],
        ["walk", "--duration", "0"],
        ["walk", "--vx", "nan"],
        ["walk", "--vy", "inf"],
        ["walk", "--turn-rate", "fast"],
        ["walk", "--robot", "atlas"],
        ["walk", "--tracker", "lqr"],
        ["walk", "--vx", "1", "--speed-profile", "0:0,5:1"],
        ["walk", "--speed-profile", "0:0,x:1", "--duration", "0.01"],
        ["walk", "--speed-profile", "5:0,1:1", "--duration", "0.01"],
        ["walk", "--scenario", "no-such-scenario"],
        ["walk", "--scenario", "rabbit-1mps", "--robot", "cassie"],
        ["walk", "--robot", "rabbit", "--vy", "0.2", "--duration", "0.01"],
        ["walk", "--video", "out.avi", "--duration", "0.01"],
        ["walk", "--json", "/no/such/folder/x.json", "--duration", "0.01"],
        ["walk", "--log", "/tmp", "--duration", "0.01"],
        ["walk", "--seed", "-1", "--duration", "0.01"],
        ["walk", "--duration", "1e-9"],
        ["compare", "--seed", "-3"],
        ["compare", "--robots", "cassie,atlas"],
        ["compare", "--push-iterations", "-1"],
        ["compare", "--scenario", "cassie-1mps", "--robots", "rabbit", "--jobs", "1"],
    ],
)
def test_bad_input_exits_2_with_one_line(argv, capsys, stand_in):
    code, out, err = run_main(argv, capsys)
    assert code == 2, err
    assert len(err.strip().splitlines()) == 1, err
    assert err.startswith("amlip-qp")


def test_bad_input_in_a_subprocess_has_no_traceback():
    proc = subprocess.run(
        [sys.executable, "-m", "amlip_qp.cli", "walk", "--push", "oops"], capture_output=True, text=True, timeout=60
    )
    assert proc.returncode == 2
    assert len(proc.stderr.strip().splitlines()) == 1 and "Traceback" not in proc.stderr


def test_walk_json_schema_and_outputs(tmp_path, capsys, stand_in):
    log, plot, summary_path = tmp_path / "run.npz", tmp_path / "run.png", tmp_path / "s.json"
    argv = ["walk", "--robot", "rabbit", "--duration", "0.05", "--vx", "0.3", "--push", "0.01:20,0,0:0.02"]
    code, out, err = run_main(argv + ["--json", "-", "--log", str(log), "--plot", str(plot)], capsys)
    assert code == 0, err
    data = json.loads(out)
    assert set(data) == SUMMARY_KEYS
    assert data["robot"] == "rabbit" and data["tracker"] == "zero" and data["fell"] is False
    assert data["duration_s"] == 0.05 and data["sim_time_s"] == pytest.approx(0.05)
    assert data["commanded_velocity"] == [0.3, 0.0]
    assert set(data["output_tracking_rms"]) == {
        "torso_pitch",
        "com_z_over_stance",
        "com_x_over_swing",
        "com_z_over_swing",
    }
    assert set(data["tick_time_us"]) == {"median", "p99"}
    with np.load(log) as npz:
        assert npz["log_t"].shape == (100,)
        assert npz["log_push"][:, 0].max() == 20.0
        assert list(npz["output_names"]) == list(data["output_tracking_rms"])
    assert plot.stat().st_size > 10_000
    code, out, err = run_main(argv + ["--json", str(summary_path)], capsys)
    assert code == 0 and "rabbit/zero walked" in out
    assert json.loads(summary_path.read_text())["steps"] == data["steps"]


def test_walk_log_modes_give_the_same_summary_and_write_no_file(tmp_path, capsys, stand_in, monkeypatch):
    monkeypatch.chdir(tmp_path)
    argv = ["walk", "--robot", "cassie", "--duration", "0.05", "--vx", "0.3", "--json", "-"]
    runs = {}
    for mode in ("summary", "full"):
        code, out, err = run_main(argv + ["--log", mode], capsys)
        assert code == 0, err
        runs[mode] = {k: v for k, v in json.loads(out).items() if k not in TIMING_FIELDS}
    assert runs["summary"] == runs["full"] and list(tmp_path.iterdir()) == []


def test_walk_is_deterministic_with_noise(capsys, stand_in):
    argv = ["walk", "--robot", "cassie", "--duration", "0.05", "--noise", "--seed", "3", "--json", "-"]
    a = json.loads(run_main(argv, capsys)[1])
    b = json.loads(run_main(argv, capsys)[1])
    c = json.loads(run_main(argv[:-4] + ["--seed", "4", "--json", "-"], capsys)[1])
    timing = set(TIMING_FIELDS)
    assert {k: v for k, v in a.items() if k not in timing} == {k: v for k, v in b.items() if k not in timing}
    assert a["output_tracking_rms"] != c["output_tracking_rms"]


def test_walk_with_the_robot_sensors_records_the_setting(capsys, stand_in):
    argv = ["walk", "--duration", "0.05", "--plant", "cassie", "--sensors", "robot", "--seed", "3"]
    code, out, err = run_main(argv, capsys)
    assert code == 0 and "cassie/zero (plant cassie, robot sensors, truth estimator) walked" in out, err
    a = json.loads(run_main(argv + ["--json", "-"], capsys)[1])
    b = json.loads(run_main(argv + ["--json", "-"], capsys)[1])
    assert (a["plant"], a["sensors"], a["estimator"]) == ("cassie", "robot", "truth")
    assert a["base_velocity_error_rms_mps"] == 0.0 and a["yaw_estimate_error_deg"] == 0.0
    assert a["output_tracking_rms"] == b["output_tracking_rms"]  # deterministic for a seed


def test_walk_reports_a_fall_with_exit_1(capsys, stand_in):
    code, out, err = run_main(["walk", "--robot", "rabbit", "--duration", "2", "--no-progress", "--json", "-"], capsys)
    assert code == 1
    data = json.loads(out)
    assert data["fell"] is True and 0 < data["fall_time_s"] < 2 and data["sim_time_s"] < 2


@pytest.mark.filterwarnings("ignore::Warning:glfw")  # GLFW (unused here) complains about the missing display
def test_walk_video_gif(tmp_path, capsys, stand_in):
    import imageio.v3 as iio

    path = tmp_path / "walk.gif"
    code, out, err = run_main(
        ["walk", "--robot", "cassie", "--duration", "0.2", "--video", str(path), "--video-fps", "20"], capsys
    )
    assert code == 0, err
    frames = iio.imread(path, index=None)
    assert frames.shape[0] == 5 and frames.shape[-1] in (3, 4)  # t = 0, 0.05, ..., 0.2 s at 20 fps
    assert frames[-1].std() > 5  # not a blank image


def test_scenario_options_override(capsys, stand_in):
    from amlip_qp.experiments.walk import scenario_from_args

    parser = cli.build_parser()
    args = parser.parse_args(
        ["walk", "--scenario", "cassie-turn-90", "--turn-rate", "-10", "--duration", "1", "--push", "0.5:0,30,0:0.1"]
    )
    sc = scenario_from_args(args)
    assert sc.robot == "cassie" and sc.duration_s == 1.0
    assert sc.turn_rate_at(0.0) == pytest.approx(np.radians(-10.0))
    assert sc.vx(10.0) == pytest.approx(0.75)  # from the named scenario
    assert len(sc.pushes) == 1 and sc.pushes[0].force_N == (0.0, 30.0, 0.0)
    args = parser.parse_args(["walk", "--speed-profile", "0:0,5:2.1"])
    sc = scenario_from_args(args)
    assert sc.robot == "cassie" and sc.vx(2.5) == pytest.approx(1.05) and sc.duration_s == 10.0


def test_command_shaping_options_reach_the_controller():
    from amlip_qp.experiments.walk import scenario_from_args
    from amlip_qp.profiles import NO_SHAPING, get_profile
    from amlip_qp.sim.scenarios.factory import build_simulation

    parser = cli.build_parser()
    assert scenario_from_args(parser.parse_args(["walk", "--robot", "rabbit"])).shaping is None  # the profile's
    sc = scenario_from_args(parser.parse_args(["walk", "--robot", "rabbit", "--accel-limit", "0.25"]))
    profile = get_profile("rabbit").shaping
    assert (sc.shaping.vx_accel_mps2, sc.shaping.vy_accel_mps2) == (0.25, 0.25)
    assert sc.shaping.turn_accel_radps2 == profile.turn_accel_radps2
    assert sc.shaping.max_step_length_m == profile.max_step_length_m
    sim = build_simulation(sc.with_(duration_s=0.01), "pbc")
    assert sim.controller.shaper.shaping is sc.shaping
    sc = scenario_from_args(parser.parse_args(["walk", "--robot", "rabbit", "--no-command-shaping"]))
    assert sc.shaping is NO_SHAPING
    assert build_simulation(sc.with_(duration_s=0.01), "pbc").controller.shaper.shaping is NO_SHAPING
    with pytest.raises(SystemExit) as info:
        parser.parse_args(["walk", "--accel-limit", "0.5", "--no-command-shaping"])
    assert info.value.code == 2
    with pytest.raises(SystemExit):
        parser.parse_args(["walk", "--accel-limit", "0"])


def test_compare_quick_with_stand_in(tmp_path, capsys, stand_in):
    out_json, fig = tmp_path / "cmp.json", tmp_path / "figures" / "cmp.png"  # the figure's folder is created
    argv = ["compare", "--quick", "--robots", "rabbit,cassie", "--jobs", "1", "--push-iterations", "2"]
    code, out, err = run_main(argv + ["--json", str(out_json), "--plot", str(fig)], capsys)
    assert code == 0, err
    lines = out.strip().splitlines()
    assert lines[0].split()[:3] == ["robot", "tracker", "fell"] and len(lines) == 2 + 4
    data = json.loads(out_json.read_text())
    rows = data["rows"]
    assert [(r["robot"], r["tracker"]) for r in rows] == [
        ("rabbit", "pbc"),
        ("rabbit", "qp"),
        ("cassie", "pbc"),
        ("cassie", "qp"),
    ]
    for r in rows:
        assert r["fell"] is True  # zero torque
        assert r["max_sagittal_impulse_Ns"] == 0.0 and r["highest_steady_speed_mps"] == 0.0
        assert (r["max_lateral_impulse_Ns"] is None) == (r["robot"] == "rabbit")
        assert len(r["sagittal_push_trials"]) == 3  # the upper bound, then 2 bisection steps
    assert data["settings"]["push_iterations"] == 2
    assert fig.stat().st_size > 10_000


def test_compare_gives_each_tracker_per_planner_in_the_table_and_the_json(tmp_path, capsys, stand_in):
    out_json = tmp_path / "cmp.json"
    argv = ["compare", "--quick", "--robots", "rabbit", "--planners", "mpc,one-step", "--no-ramp", "--jobs", "1"]
    code, out, err = run_main(argv + ["--push-iterations", "0", "--json", str(out_json), "--no-plot"], capsys)
    assert code == 0, err
    lines = out.strip().splitlines()
    assert [line.split("  ")[1].strip() for line in lines[2:]] == [
        "pbc / mpc",
        "pbc / one-step",
        "qp / mpc",
        "qp / one-step",
    ]
    data = json.loads(out_json.read_text())
    assert [(r["tracker"], r["planner"]) for r in data["rows"]] == [
        ("pbc", "mpc"),
        ("pbc", "one-step"),
        ("qp", "mpc"),
        ("qp", "one-step"),
    ]
    assert all(r["fell"] is True and r["max_sagittal_impulse_Ns"] == 0.0 for r in data["rows"])  # zero torque
    assert data["settings"]["planners"] == ["mpc", "one-step"]
    assert cli.build_parser().parse_args(["compare"]).planners == ["one-step"]


def test_compare_lets_warnings_of_a_run_reach_the_user(capsys, monkeypatch):
    from amlip_qp.codegen.runtime import CodegenFallbackWarning

    class FallbackTracker(ZeroTracker):
        def __init__(self, robot):
            super().__init__(robot)
            warnings.warn("stand-in: no C compiler", CodegenFallbackWarning, stacklevel=2)

    monkeypatch.setattr(registry, "make_tracker", lambda name, robot: FallbackTracker(robot))
    monkeypatch.setattr(registry, "tracker_class", lambda name: FallbackTracker)
    argv = [
        "compare",
        "--quick",
        "--robots",
        "rabbit",
        "--trackers",
        "qp",
        "--no-ramp",
        "--no-push",
        "--jobs",
        "1",
        "--no-plot",
    ]
    with pytest.warns(CodegenFallbackWarning, match="no C compiler"):
        code, out, err = run_main(argv, capsys)
    assert code == 0, err


def test_factory_names_a_missing_tracker(monkeypatch):
    monkeypatch.setitem(registry.TRACKER_MODULES, "pbc", "amlip_qp.control.no_such_module")
    with pytest.raises(InputError, match="'pbc' tracker is not available"):
        registry.tracker_class("pbc")
    with pytest.raises(InputError, match="unknown tracker"):
        registry.tracker_class("lqr")


@pytest.mark.parametrize("name", ["pbc", "qp"])
def test_real_trackers_are_wired(name):
    cls = registry.tracker_class(name)
    assert cls.name == name
    from amlip_qp.sim.scenarios.scenarios import Scenario

    res = factory.run_scenario(Scenario("tiny", "rabbit", 0.01), name)
    assert res.tracker == name and res.log["t"].size == 20


def test_clearance_option_reaches_the_planner_command_and_is_bounded():
    from amlip_qp.exceptions import InputError
    from amlip_qp.experiments.walk import scenario_from_args

    parser = cli.build_parser()
    sc = scenario_from_args(parser.parse_args(["walk", "--vx", "0.5"]))
    assert sc.setting.clearance_m is None and sc.command(1.0).clearance_m == 0.10  # Cassie's gait
    sc = scenario_from_args(parser.parse_args(["walk", "--scenario", "cassie-1mps", "--clearance", "0.2"]))
    assert sc.setting.clearance_m == 0.2 and sc.command(5.0).clearance_m == 0.2
    assert sc.command(5.0).vx_mps == 1.0  # the rest of the scenario is kept
    with pytest.raises(InputError, match="below the CoM height"):
        scenario_from_args(parser.parse_args(["walk", "--clearance", "0.8"]))
    with pytest.raises(SystemExit) as info:
        parser.parse_args(["walk", "--clearance", "-0.1"])
    assert info.value.code == 2


def test_compare_takes_the_terrain_aware_and_clearance_settings():
    from amlip_qp.experiments.walk import setting_from_args
    from amlip_qp.sim.loop.run_types import PlantSetting

    parser = cli.build_parser()
    args = parser.parse_args(["compare", "--terrain", "slope:10", "--terrain-aware", "--clearance", "0.15"])
    setting = setting_from_args(args, PlantSetting())
    assert (setting.terrain, setting.terrain_aware, setting.clearance_m) == ("slope:10", True, 0.15)
    assert setting_from_args(parser.parse_args(["compare"]), PlantSetting()) == PlantSetting()


def test_no_terrain_aware_turns_an_aware_scenario_blind_and_the_default_keeps_it():
    from amlip_qp.experiments.walk import scenario_from_args

    parser = cli.build_parser()
    stairs = ["walk", "--scenario", "cassie-stairs-10cm"]
    assert scenario_from_args(parser.parse_args(stairs)).setting.terrain_aware
    assert not scenario_from_args(parser.parse_args([*stairs, "--no-terrain-aware"])).setting.terrain_aware
