"""Bad input to ``amlip-qp``: exit status 2, one line on stderr, no traceback, and nothing simulated.

Every case runs through :func:`amlip_qp.cli.main` in this process with the
simulation builders replaced by a function that fails the test if called, so
a check that comes too late (after the simulation) shows as a failure, not as
a slow test. Two cases run in a real subprocess to see stderr exactly.
"""

from __future__ import annotations

import argparse
import struct
import subprocess
import sys
import zlib

import numpy as np
import pytest

from amlip_qp import cli
from amlip_qp.control import registry
from amlip_qp.control.tracker import Tracker
from amlip_qp.exceptions import InputError
from amlip_qp.messages import TrackerResult
from amlip_qp.paths import MODELS_DIR
from amlip_qp.sim.scenarios import factory

#: A plant that lacks everything Cassie's controller needs.
RABBIT_XML = str(MODELS_DIR / "rabbit.xml")


def _simulated(*args, **kwargs):
    raise AssertionError("a simulation or benchmark ran although the input was bad")


@pytest.fixture
def no_simulation(monkeypatch):
    """Make every way of simulating (walk, compare, the benchmarks) or generating code fail the test."""
    from amlip_qp.codegen import bench as codegen_bench
    from amlip_qp.codegen import generate
    from amlip_qp.experiments import bench_ekf, bench_harness, compare
    from amlip_qp.sweep import bench as sweep_bench

    monkeypatch.setattr(factory, "build_simulation", _simulated)
    monkeypatch.setattr(factory, "run_scenario", _simulated)
    monkeypatch.setattr(compare, "run_comparison", _simulated)
    monkeypatch.setattr(codegen_bench, "run_benchmark", _simulated)
    from amlip_qp.control.mpc import bench as mpc_bench

    monkeypatch.setattr(mpc_bench, "run_benchmark", _simulated)
    from amlip_qp.experiments import bench_qp

    monkeypatch.setattr(bench_qp, "run", _simulated)
    monkeypatch.setattr(bench_qp, "format_report", _simulated)
    monkeypatch.setattr(bench_ekf, "build_simulation", _simulated)
    monkeypatch.setattr(bench_harness, "build_simulation", _simulated)
    monkeypatch.setattr(sweep_bench, "bench_cells", _simulated)
    monkeypatch.setattr(generate, "generate_files", _simulated)
    monkeypatch.setattr(generate, "write_files", _simulated)


def header_only_png(path, width, height):
    """A PNG signature and an IHDR chunk of ``width`` x ``height`` 8-bit gray pixels, without image data."""
    ihdr = struct.pack(">IIBBBBB", width, height, 8, 0, 0, 0, 0)
    chunk = struct.pack(">I", len(ihdr)) + b"IHDR" + ihdr + struct.pack(">I", zlib.crc32(b"IHDR" + ihdr))
    path.write_bytes(b"\x89PNG\r\n\x1a\n" + chunk)
    return path


def _main(argv, capsys):
    try:
        code = cli.main(argv)
    except SystemExit as exc:  # argparse errors
        code = exc.code
    out, err = capsys.readouterr()
    return code, out, err


#: (argv, a piece of the error line). ``{tmp}`` is a fresh folder, ``{file}`` a file in it, ``{bigpng}``
#: a PNG whose header says 12000 x 12000 pixels and that has no pixel data (so it cannot be decoded:
#: the refusal comes from the header alone).
BAD_INPUTS = [
    # outputs that cannot be written, checked before simulating
    (["walk", "--json", "/proc/x"], "--json /proc/x: cannot write"),
    (["walk", "--plot", "/proc/x.png"], "--plot /proc/x.png: cannot write"),
    (["walk", "--video", "/proc/x.mp4"], "--video /proc/x.mp4: cannot write"),
    (["walk", "--log", "/proc/x.npz"], "--log /proc/x.npz: cannot write"),
    (["walk", "--json", "/sys/amlip_qp_x.json"], "cannot write"),  # a folder nobody may write into
    (["walk", "--json", "{tmp}/missing/x.json"], "does not exist"),
    (["walk", "--log", "{tmp}"], "is a folder"),
    (["walk", "--plot", "{file}/x.png"], "is a file, not a folder"),
    (["walk", "--log", "-"], "cannot write to stdout"),
    (["walk", "--log", "summary", "--plot", "{tmp}/fig.png"], "--plot draws the full log: drop --log summary"),
    (["walk", "--video", "out.avi"], ".mp4 or .gif"),
    (["walk", "--plot", "{tmp}/fig.xyz"], "figure file must end in .png, .pdf, .svg"),
    # physical bounds (amlip_qp.profiles)
    (["walk", "--duration", "1e12"], "CommandBounds.duration_max_s"),
    (["walk", "--accel-limit", "0"], "--accel-limit: expected a number in (0, 100] m/s^2, got '0'"),
    (["walk", "--accel-limit", "1e3"], "--accel-limit: expected a number in (0, 100] m/s^2, got '1e3'"),
    (["walk", "--duration", "1e-9"], "duration 1e-09 s is shorter than one control tick (0.0005 s)"),
    (["walk", "--accel-limit", "nan"], "--accel-limit: expected a finite number"),
    (["walk", "--accel-limit", "1", "--no-command-shaping"], "not allowed with argument --accel-limit"),
    (["walk", "--vx", "1e9"], "forward speed 1e+09 m/s is outside cassie's bounds [-4.14, 4.14] m/s"),
    (["walk", "--vx", "-1e9"], "CommandBounds.vx_mps"),
    (["walk", "--robot", "rabbit", "--vx", "2"], "outside rabbit's bounds"),
    (["walk", "--vx", "4.2"], "forward speed 4.2 m/s is outside cassie's bounds"),
    (["walk", "--speed-profile", "0:0,5:30"], "forward speed 30 m/s"),
    (["walk", "--vy", "5"], "CommandBounds.vy_max_mps"),
    (["walk", "--turn-rate", "-1e3"], "CommandBounds.turn_rate_max_radps"),
    (["walk", "--push", "1:5000,0,0:0.01"], "CommandBounds.push_force_max_N"),
    (["walk", "--push", "1:400,0,0:0.5"], "CommandBounds.push_impulse_max_Ns"),
    (["walk", "--push", "9.9:100,0,0:0.2"], "ends after the run"),
    (["walk", "--scenario", "cassie-push", "--duration", "5"], "ends after the run"),
    (["walk", "--robot", "rabbit", "--vy", "0.2"], "rabbit is planar"),
    (["walk", "--robot", "rabbit", "--turn-rate", "10"], "rabbit is planar"),
    (["walk", "--robot", "rabbit", "--push", "1:0,50,0:0.2"], "rabbit is planar"),
    # malformed values
    (["walk", "--planner", "two-step"], "--planner: invalid choice: 'two-step'"),
    (["bench", "mpc", "--duration", "0"], "--duration"),
    (["bench", "mpc", "--json", "/proc/x"], "--json /proc/x: cannot write"),
    (["walk", "--push", "1:2,3:0.2"], "expected T:FX,FY,FZ:DUR"),
    (["walk", "--push", "1:a,0,0:0.2"], "expected T:FX,FY,FZ:DUR"),
    (["walk", "--push", "-1:1,0,0:0.2"], "T >= 0 s"),
    (["walk", "--push", "1:nan,0,0:0.2"], "expected T:FX,FY,FZ:DUR"),
    (["walk", "--vx", "nan"], "finite"),
    (["walk", "--vx", "inf"], "finite"),
    (["walk", "--vx", "-inf"], "finite"),
    (["walk", "--duration", "-1e1"], "positive"),
    (["walk", "--speed-profile", "0:0,x:1"], "speed profile"),
    (["walk", "--speed-profile", "5:0,1:1"], "increase strictly, got [5.0, 1.0]"),
    # unknown names
    (["walk", "--robot", "atlas"], "unknown robot 'atlas'; known robots: cassie"),
    (["walk", "--tracker", "lqr"], "invalid choice"),
    (["walk", "--scenario", "moonwalk"], "unknown scenario 'moonwalk'"),
    (["walk", "--scenario", "rabbit-1mps", "--robot", "cassie"], "is for rabbit"),
    # the plant, the sensors and the estimator
    (["walk", "--plant", "moon"], "unknown plant 'moon' for cassie: known plants are cassie, cassie-closed-chain"),
    (["walk", "--robot", "rabbit", "--plant", "cassie-closed-chain"], "unknown plant 'cassie-closed-chain' for rabbit"),
    (["walk", "--plant", "{tmp}/none.xml"], "plant model file not found"),
    (["walk", "--plant", "{file}"], "MuJoCo cannot load the plant"),
    (["walk", "--plant", RABBIT_XML], "does not fit the cassie controller: it lacks body 'cassie-pelvis'"),
    (["walk", "--sensors", "perfect"], "argument --sensors: invalid choice"),
    (["walk", "--estimator", "kalman"], "argument --estimator: invalid choice"),
    (["walk", "--noise", "--sensors", "robot"], "--sensors robot has its own"),
    (["compare", "--jobs", "1", "--plant", "moon"], "unknown plant 'moon' for cassie"),
    (["compare", "--robots", "cassie", "--jobs", "1", "--plant", RABBIT_XML], "it lacks body 'cassie-pelvis'"),
    (["compare", "--sensors", "perfect"], "argument --sensors: invalid choice"),
    (["compare", "--estimator", "kalman"], "argument --estimator: invalid choice"),
    (["compare", "--jobs", "1", "--noise", "--sensors", "robot"], "--sensors robot has its own"),
    # plant modifiers: nonsensical values
    (["walk", "--plant-mass-scale", "0"], "--plant-mass-scale) must be a number in [0.1, 10], got 0.0"),
    (["walk", "--plant-mass-scale", "0.01"], "--plant-mass-scale) must be a number in [0.1, 10], got 0.01"),
    (["walk", "--plant-mass-scale", "nan"], "--plant-mass-scale) must be a number in [0.1, 10]"),
    (["walk", "--payload", "-5"], "--payload) must be a mass in [0, 100] kg"),
    (["walk", "--payload", "5@1,2"], "--payload position needs 3 coordinates"),
    (["walk", "--payload", "five"], "--payload takes KG or KG@X,Y,Z"),
    (["walk", "--plant-spring-scale", "-1"], "--plant-spring-scale) must be a number in [0, 10], got -1.0"),
    (["walk", "--plant-spring-scale", "1e300"], "--plant-spring-scale) must be a number in [0, 10], got 1e+300"),
    (["walk", "--friction", "0"], "--friction) must be a coefficient in [1e-05, 10], got 0.0"),
    (["walk", "--friction", "1e-9"], "--friction) must be a coefficient in [1e-05, 10], got 1e-09"),
    (["walk", "--actuator-delay", "-1"], "--actuator-delay) must be a whole number of ticks in [0, 100]"),
    (["walk", "--actuator-delay", "1.5"], "argument --actuator-delay: expected a whole number, got '1.5'"),
    (["compare", "--jobs", "1", "--friction", "-0.5"], "--friction) must be a coefficient in [1e-05, 10]"),
    (["bench", "ekf", "--scenario", "cassie-1mps"], "needs a scenario with the EKF estimator"),
    (["bench", "ekf", "--scenario", "nowhere"], "unknown scenario 'nowhere'"),
    (["bench", "ekf", "--duration", "0"], "--duration"),
    (["compare", "--jobs", "1", "--payload", "5@9,0,0"], "must be 3 numbers within 1 m of the base body"),
    # the terrain (--terrain)
    (["walk", "--terrain", "slope:45"], "the slope must be less than 45 deg either way, got 45"),
    (["walk", "--terrain", "slope:-60"], "the slope must be less than 45 deg"),
    (["walk", "--terrain", "slope:steep"], "the slope must be a number of degrees"),
    (["walk", "--terrain", "slope"], "wrong number of fields for slope"),
    (["walk", "--terrain", "hill:3"], "unknown terrain; use flat, slope:DEG"),
    (["walk", "--terrain", "stairs:-0.1:0.3"], "RISE_M must be a number in (0, 1], got -0.1"),
    (["walk", "--terrain", "stairs:0.1:x"], "RUN_M must be a number, got 'x'"),
    (["walk", "--terrain", "stairs:0.1:0.3:2.5"], "N must be a whole number"),
    (["walk", "--terrain", "rough:-0.04"], "AMPLITUDE_M must be a number in (0, 1]"),
    (["walk", "--terrain", "rough:0.04:-1"], "SEED must be in [0, "),
    (["walk", "--terrain", "waves:0.3:0"], "WAVELENGTH_M must be a number in (0, 100]"),
    (["walk", "--terrain", "waves:2:4"], "these waves are 58 deg steep at their flanks"),
    (["walk", "--terrain", "hfield:{tmp}/none.png:10:4:1"], "height map not found"),
    (["walk", "--terrain", "hfield:{file}:10:4:1"], "cannot read the height map"),
    (["walk", "--terrain", "hfield:{tmp}/x.png:10:4"], "give hfield:PATH.png:SIZE_X_M:SIZE_Y_M:HEIGHT_M"),
    (["walk", "--terrain", "slope:10", "--plant", RABBIT_XML], "it lacks body 'cassie-pelvis'"),
    (
        ["walk", "--terrain", "hfield:{bigpng}:20:8:0.1"],
        "has 12000 x 12000 pixels; at most 16777216 pixels (4096 x 4096) are read: downsample it",
    ),
    # the video
    (["walk", "--video-fps", "1e9"], "argument --video-fps: expected a number in (0, 240] frames/s, got '1e9'"),
    (["walk", "--video-fps", "0"], "argument --video-fps: expected a number in (0, 240] frames/s, got '0'"),
    (["walk", "--video-fps", "nan"], "argument --video-fps: expected a finite number, got 'nan'"),
    (["walk", "--video", "{tmp}/v.gif", "--video-fps", "120"], "--video-fps must be in (0, 100] frames/s (a .gif's"),
    # seeds, worker counts, iterations
    (["walk", "--seed", "4294967296"], "argument --seed: expected a seed in [0, 4294967295], got 4294967296"),
    (["walk", "--seed", "-1"], "argument --seed: expected a seed in [0, 4294967295], got -1"),
    (["compare", "--jobs", "1000"], "argument --jobs: expected a number of worker processes in [1, 64], got 1000"),
    (["compare", "--jobs", "0"], "argument --jobs: expected a number of worker processes in [1, 64], got 0"),
    (
        ["compare", "--push-iterations", "1000000000"],
        "argument --push-iterations: expected a number of iterations in [0, 20], got 1000000000",
    ),
    (["compare", "--jobs", "1", "--terrain", "stairs:0:0.3"], "RISE_M must be a number in (0, 1], got 0"),
    # compare and the benchmarks
    (["compare", "--jobs", "1", "--json", "/proc/x.json"], "--json /proc/x.json: cannot write"),
    (["compare", "--jobs", "1", "--plot", "/proc/x.png"], "--plot /proc/x.png: cannot write"),
    (["compare", "--jobs", "1", "--json", "{tmp}/missing/x.json"], "does not exist"),
    (["compare", "--jobs", "1", "--plot", "{tmp}/cmp"], "figure file must end in"),
    (["compare", "--jobs", "1", "--plot", "{file}/cmp.png"], "is a file, not a folder"),
    (["compare", "--robots", "cassie,atlas"], "argument --robots: unknown robot 'atlas'"),
    (["compare", "--robots", ","], "expected a comma-separated list of robots"),
    (["compare", "--planners", "one-step,two-step"], "--planners: expected a comma-separated list from one-step, mpc"),
    (["compare", "--planners", ","], "--planners: expected a comma-separated list from one-step, mpc, got ','"),
    (["walk", "--robot", "{tmp}/nothing.toml"], "robot profile not found"),
    (["walk", "--robot", "{no_pbc}", "--tracker", "pbc"], "the pbc tracker does not run on h1: a test reason"),
    (["walk", "--robot", "{file}.toml"], "robot profile not found"),
    (["compare", "--jobs", "1", "--scenario", "moonwalk"], "unknown scenario"),
    (["bench", "codegen", "--json", "/proc/x.json"], "--json /proc/x.json: cannot write"),
    (["bench", "qp", "--json", "/proc/x.json"], "--json /proc/x.json: cannot write"),
    (["bench", "codegen", "--calls", "1000000000000"], "--calls: expected a number of calls in [1, 1000000]"),
    (["bench", "qp", "--ticks", "1000000000"], "--ticks: expected a number of ticks in [1, 20000], got 1000000000"),
    (["bench", "ekf", "--duration", "1e9"], "--duration: expected a number in [0.0005, 600] s, got '1e9'"),
    (["bench", "harness", "--duration", "inf"], "--duration: expected a finite number, got 'inf'"),
    (["bench", "harness", "--repeats", "1000"], "--repeats: expected a number of repeats in [1, 20], got 1000"),
    (["bench", "sweep", "--cells", "1000000"], "--cells: expected a number of cells in [1, 1000], got 1000000"),
    (["bench", "sweep", "--duration", "1e-9"], "--duration: expected a number in [0.0005, 600] s, got '1e-9'"),
    # codegen's output folder
    (["codegen", "--out", "/proc/x"], "--out /proc/x: cannot create the folder (No such file or directory)"),
    (["codegen", "--out", "/sys/kernel"], "--out /sys/kernel: cannot write there (Permission denied)"),
    (["codegen", "--out", "{file}"], "is a file, not a folder; give a folder path"),
]


def _profile_without_pbc(tmp_path):
    """H1's profile, its model by absolute path, with an ``[unsupported]`` reason for the PBC (written
    beside ``tmp_path``, which the test checks for files written)."""
    text = (MODELS_DIR / "h1.toml").read_text()
    text = text.replace('file = "unitree_h1/h1.xml"', f'file = "{MODELS_DIR / "unitree_h1" / "h1.xml"}"')
    path = tmp_path.parent / f"{tmp_path.name}_no_pbc.toml"
    path.write_text(text + '\n[unsupported]\npbc = "a test reason"\n')
    return path


@pytest.mark.parametrize("argv, needle", BAD_INPUTS, ids=[" ".join(a) for a, _ in BAD_INPUTS])
def test_bad_input_exits_2_with_one_line_and_simulates_nothing(argv, needle, tmp_path, capsys, no_simulation):
    a_file = tmp_path / "a_file.txt"
    a_file.write_text("not a folder\n")
    big_png = header_only_png(tmp_path / "big.png", 12000, 12000)
    before = sorted(p.name for p in tmp_path.iterdir())
    no_pbc = _profile_without_pbc(tmp_path)
    argv = [a.format(tmp=tmp_path, file=a_file, bigpng=big_png, no_pbc=no_pbc) for a in argv]
    code, out, err = _main(argv, capsys)
    assert sorted(p.name for p in tmp_path.iterdir()) == before  # nothing written
    assert code == 2, err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("amlip-qp"), err
    assert "Traceback" not in err and "np.float64" not in err and out == ""
    assert needle in lines[0]


@pytest.mark.parametrize(
    "argv, stderr",
    [
        (
            ["walk", "--json", "/proc/x"],
            "amlip-qp: error: --json /proc/x: cannot write there (No such file or directory); give a writable path\n",
        ),
        (
            ["walk", "--duration", "1e12"],
            "amlip-qp: error: duration 1e+12 s is above cassie's bound 600 s "
            "(CommandBounds.duration_max_s in amlip_qp.profiles: the per-tick log is kept in memory)\n",
        ),
    ],
)
def test_bad_input_in_a_subprocess_prints_exactly_one_line(argv, stderr):
    proc = subprocess.run([sys.executable, "-m", "amlip_qp.cli", *argv], capture_output=True, text=True, timeout=120)
    assert (proc.returncode, proc.stderr, proc.stdout) == (2, stderr, "")


@pytest.mark.parametrize(
    "argv, attribute, value",
    [
        (["walk", "--vx", "-1e-1"], "vx", -0.1),
        (["walk", "--vx=-1e-1"], "vx", -0.1),
        (["walk", "--turn-rate", "-5E0"], "turn_rate", -5.0),
        (["walk", "--vy", "-.25"], "vy", -0.25),
        (["walk", "--vx", "-2.5e+0"], "vx", -2.5),
    ],
)
def test_negative_numbers_in_exponent_form_are_values(argv, attribute, value):
    assert getattr(cli.build_parser().parse_args(argv), attribute) == value


def test_an_option_is_still_an_option_after_a_value_taking_flag(capsys):
    code, _, err = _main(["walk", "--vx", "--json", "-"], capsys)
    assert code == 2 and "expected one argument" in err


def test_commands_inside_the_bounds_pass_the_check():
    from amlip_qp.experiments.walk import scenario_from_args

    parser = cli.build_parser()
    for argv in (
        ["--vx", "2.5"],
        ["--vx", "-5e-1"],
        ["--vx", "-1", "--vy", "-0.5", "--turn-rate", "-60"],
        ["--robot", "rabbit", "--vx", "1.0"],
        ["--robot", "rabbit", "--vx", "0.5", "--push", "1:100,0,0:0.2"],
        ["--duration", "600", "--push", "599.8:500,0,0:0.2"],
    ):
        scenario = scenario_from_args(parser.parse_args(["walk", *argv]))
        assert scenario.duration_s > 0


class ZeroTracker(Tracker):
    name = "zero"

    def __init__(self, robot):
        self.nu = robot.nu

    def compute(self, kin, target):
        return TrackerResult(tau_Nm=np.zeros(self.nu))


@pytest.mark.parametrize("option, name", [("--json", "s.json"), ("--log", "run.npz"), ("--plot", "fig.png")])
def test_an_os_error_while_writing_after_the_run_exits_2(option, name, tmp_path, monkeypatch, capsys):
    """A link to ``/dev/full`` opens, then every write fails (ENOSPC): the early check passes, the write does not."""
    path = tmp_path / name
    path.symlink_to("/dev/full")
    monkeypatch.setattr(registry, "make_tracker", lambda name, robot: ZeroTracker(robot))
    code, out, err = _main(["walk", "--robot", "rabbit", "--duration", "0.01", option, str(path)], capsys)
    assert code == 2
    assert err == f"amlip-qp: error: {option} {path}: writing failed (No space left on device); give a writable path\n"


def test_any_other_os_error_exits_2_naming_the_path(monkeypatch, capsys):
    from amlip_qp.experiments import walk as sim_cli

    def disk_full(args):
        raise OSError(28, "No space left on device", "/data/run.npz")

    monkeypatch.setattr(sim_cli, "run_walk", disk_full)
    code, out, err = _main(["walk"], capsys)
    assert code == 2
    assert (
        err
        == "amlip-qp: error: /data/run.npz: No space left on device; check the path, its folder and the free space\n"
    )


#: How each command is given the option under test (enough for it to reach its checks, nothing written).
COMMANDS = {
    "walk": ["walk"],
    "compare": ["compare", "--no-plot"],
    "sweep": ["sweep", "--grid", "vx=0.5", "--out", "{tmp}/sweep"],
    "codegen": ["codegen", "--out", "{tmp}/gen"],
    "bench codegen": ["bench", "codegen"],
    "bench qp": ["bench", "qp"],
    "bench ekf": ["bench", "ekf"],
    "bench harness": ["bench", "harness"],
    "bench sweep": ["bench", "sweep"],
}
#: Options whose error names the quantity instead of the option (the robot's CommandBounds).
QUANTITY = {"--vx": "forward speed", "--vy": "lateral speed", "--turn-rate": "turn rate", "--duration": "duration"}


def numeric_options(command: list[str]) -> list[tuple[str, bool]]:
    """``(option, takes an int)`` for every option of ``command`` whose value type reads a number.

    argparse keeps a parser's options in ``_actions`` and has no public accessor for them.
    """
    parser = cli.build_parser()
    for word in command:
        sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
        parser = sub.choices[word]
    out = []
    for action in parser._actions:
        if not action.option_strings or action.type is None or action.nargs == 0:
            continue
        try:
            value = action.type("1")
        except (argparse.ArgumentTypeError, ValueError, TypeError, InputError):
            continue  # a text value (a list of names, a push spec)
        if isinstance(value, (int, float)):
            out.append((action.option_strings[-1], isinstance(value, int)))
    return out


def test_the_audit_sees_every_numeric_option():
    found = {name: [o for o, _ in numeric_options(name.split())] for name in COMMANDS}
    assert found["walk"] == [
        "--vx", "--vy", "--turn-rate", "--duration", "--accel-limit", "--seed", "--clearance",
        "--plant-mass-scale", "--plant-spring-scale", "--friction", "--actuator-delay", "--video-fps",
    ]  # fmt: skip
    assert found["compare"] == [
        "--push-iterations", "--seed", "--clearance", "--plant-mass-scale", "--plant-spring-scale", "--friction",
        "--actuator-delay", "--jobs",
    ]  # fmt: skip
    assert found["sweep"] == ["--duration", "--workers"]
    assert found["codegen"] == []
    assert (found["bench codegen"], found["bench qp"], found["bench ekf"]) == (["--calls"], ["--ticks"], ["--duration"])
    assert found["bench harness"] == ["--duration", "--repeats"]
    assert found["bench sweep"] == ["--cells", "--duration", "--repeats"]


CASES = [
    (name, option, value)
    for name, command in COMMANDS.items()
    for option, is_int in numeric_options(name.split())
    for value in ((str(10**30), str(-(10**30))) if is_int else ("1e300", "-1e300", "nan", "inf"))
]


@pytest.mark.parametrize("name, option, value", CASES, ids=[f"{n} {o} {v}" for n, o, v in CASES])
def test_every_numeric_option_refuses_absurd_values_in_one_line(name, option, value, tmp_path, capsys, no_simulation):
    argv = [a.format(tmp=tmp_path) for a in COMMANDS[name]]
    code, out, err = _main([*argv, f"{option}={value}"], capsys)
    lines = err.strip().splitlines()
    assert code == 2 and len(lines) == 1 and out == "", err
    assert (QUANTITY.get(option, option) if "argument" not in lines[0] else option) in lines[0]
    assert not any(tmp_path.iterdir())  # nothing written (codegen's and sweep's folders not even created)
