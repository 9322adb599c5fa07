"""Bad input to ``amlip-qp walk``: exit status 2, one line on stderr, no traceback, and nothing
simulated.

Every case runs through :func:`amlip_qp.cli.main` in this process with the simulation builders
replaced by a function that fails the test if called (the ``no_simulation`` fixture of
``conftest.py``), so a check that comes too late (after the simulation) shows as a failure, not as
a slow test.
"""

from __future__ import annotations

import pytest

from cli_bad_input_support import RABBIT_XML, assert_refused

#: (argv, a piece of the error line). ``{tmp}`` is a fresh folder, ``{file}`` a file in it, ``{bigpng}``
#: a PNG whose header says 12000 x 12000 pixels and that has no pixel data (so it cannot be decoded:
#: the refusal comes from the header alone), ``{no_pbc}`` H1's profile with the PBC unsupported.
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
    # compare and the benchmarks
    (["walk", "--robot", "{tmp}/nothing.toml"], "robot profile not found"),
    (["walk", "--robot", "{no_pbc}", "--tracker", "pbc"], "the pbc tracker does not run on h1: a test reason"),
    (["walk", "--robot", "{file}.toml"], "robot profile not found"),
]


@pytest.mark.parametrize("argv, needle", BAD_INPUTS, ids=[" ".join(a) for a, _ in BAD_INPUTS])
def test_bad_input_exits_2_with_one_line_and_simulates_nothing(argv, needle, tmp_path, capsys, no_simulation):
    assert_refused(argv, needle, tmp_path, capsys)
