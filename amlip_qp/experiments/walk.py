"""Handler of ``amlip-qp walk`` (parser in :mod:`amlip_qp.cli`).

The handler makes its parsed options :class:`~amlip_qp.sim.scenarios.options.WalkOptions`
(:func:`options_from_args`) and the scenario from them with the library's one
constructor, :func:`~amlip_qp.sim.scenarios.from_options.scenario_from_options`,
which a sweep cell calls too.

``walk`` exit status: 0 when the run finished standing, 1 when the robot
fell (the summary, log, plot and video are still written), 2 for bad input.
"""

from __future__ import annotations

import argparse
import math
import sys

import numpy as np

from amlip_qp.exceptions import InputError
from amlip_qp.output_paths import check_output_path, writing
from amlip_qp.profiles import get_profile
from amlip_qp.sim.loop.run_log import LOG_MODES
from amlip_qp.sim.loop.run_types import PlantSetting, RunResult, SensorNoise
from amlip_qp.sim.reports import summary
from amlip_qp.sim.reports.video import VideoRecorder, check_video_fps, check_video_path
from amlip_qp.sim.scenarios import factory
from amlip_qp.sim.scenarios.from_options import scenario_from_options, setting_from_options
from amlip_qp.sim.scenarios.options import SETTING_OPTIONS, WalkOptions
from amlip_qp.sim.scenarios.scenarios import Scenario, held_warnings, release_warnings
from amlip_qp.sim.world.plant_loader import load_plant

#: Runs at least this long (simulated s) show a progress bar on stderr.
PROGRESS_MIN_DURATION_S = 3.0


def options_from_args(args: argparse.Namespace) -> WalkOptions:
    """The walk options of a parsed ``walk`` (or ``view``) command line: the handler's one conversion.

    Raises:
        InputError: ``--vx`` with ``--speed-profile`` or ``--accel-limit`` with
            ``--no-command-shaping`` (argparse refuses them first).
    """
    return WalkOptions.from_namespace(args)


def scenario_from_args(args: argparse.Namespace) -> Scenario:
    """The :class:`Scenario` ``walk`` runs: :func:`~amlip_qp.sim.scenarios.from_options.scenario_from_options`
    of :func:`options_from_args` (the one constructor a sweep cell uses too).

    Raises:
        InputError: As :func:`~amlip_qp.sim.scenarios.from_options.scenario_from_options`.
    """
    return scenario_from_options(options_from_args(args))


def save_log(result: RunResult, path: str) -> None:
    """Write the per-tick log and the per-step records as a compressed ``.npz`` (SI units)."""
    steps = result.steps
    arrays = {f"log_{k}": v for k, v in result.log.items()}
    arrays.update(
        tick_time_us=np.asarray(result.tick_time_us),
        step_t_start_s=np.array([s.t_start_s for s in steps]),
        step_t_end_s=np.array([s.t_end_s for s in steps]),
        step_stance_left=np.array([s.stance == "left" for s in steps], dtype=bool),
        step_swing_target_m=np.array([s.swing_target_m for s in steps]).reshape(-1, 3),
        step_swing_actual_m=np.array([s.swing_actual_m for s in steps]).reshape(-1, 3),
        step_L_end_Nms=np.array([s.L_end_Nms for s in steps]).reshape(-1, 2),
        step_L_target_Nms=np.array([s.L_target_Nms for s in steps]).reshape(-1, 2),
        step_heading_rad=np.array([s.heading_rad for s in steps]),
        output_names=np.array(result.info.get("output_names", ()), dtype=str),
        actuator_names=np.array(result.info.get("actuator_names", ()), dtype=str),
    )
    with open(path, "wb") as fh:
        # numpy's stub matches ``**arrays`` against the keyword ``allow_pickle: bool`` too;
        # every value here is an array (no key is called allow_pickle).
        np.savez_compressed(fh, **arrays)  # type: ignore[arg-type]


def _write_text(option: str, path: str, text: str) -> None:
    if path == "-":
        sys.stdout.write(text + "\n")
    else:
        with writing(option, path), open(path, "w") as fh:
            fh.write(text + "\n")


def log_mode(log_option: str | None) -> str:
    """The :meth:`~amlip_qp.sim.loop.harness.Simulation.run` log mode of ``walk --log``: ``summary``, else ``full``."""
    return "summary" if log_option == "summary" else "full"


def log_file(log_option: str | None) -> str | None:
    """The file ``walk --log`` writes: its value unless it is a log mode (``summary``, ``full``) or absent."""
    return None if log_option in (None, *LOG_MODES) else log_option


def _check_output_paths(args: argparse.Namespace) -> None:
    """Fail early (exit 2) on output paths that cannot be written, before a long run."""
    if args.plot is not None and log_mode(args.log) == "summary":
        raise InputError("--plot draws the full log: drop --log summary (or give --log full)")

    check_video_fps(args.video_fps, args.video)
    if args.video is not None:
        check_video_path(args.video)
    if args.plot is not None and args.plot != "-":
        from amlip_qp.sim.reports.plots import check_figure_path

        check_figure_path(args.plot)
    for opt in ("json", "log", "plot", "video"):
        value = log_file(args.log) if opt == "log" else getattr(args, opt)
        if opt != "json" and value == "-":
            raise InputError(f"--{opt} cannot write to stdout ('-'); give a file name")
        check_output_path(f"--{opt}", value)


def setting_from_args(args: argparse.Namespace, base: PlantSetting) -> PlantSetting:
    """``base`` with the plant options of ``args`` (``walk``'s or ``compare``'s) applied
    (:func:`~amlip_qp.sim.scenarios.from_options.setting_from_options`).

    Raises:
        InputError: ``--noise`` with robot sensors, a malformed ``--payload`` or
            ``--terrain``, or a nonsensical modifier value (one line saying what to fix).
    """
    return setting_from_options(WalkOptions.from_namespace(args, SETTING_OPTIONS), base)


def check_plant(scenario: Scenario) -> None:
    """Load the scenario's plant with its modifiers and terrain once, to fail (exit 2) before the closed loop is built.

    Raises:
        InputError: An unknown plant name, or a plant that lacks what the controller needs.
        ModelFileError: The plant file does not exist.
        MJCFError: MuJoCo cannot load it, or it cannot take the modifiers.
    """
    robot = factory.load(scenario.robot)
    setting = scenario.setting
    load_plant(setting.plant or robot.name, robot, edits=factory.setting_edits(setting, robot))


def run_walk(args: argparse.Namespace) -> int:
    """``amlip-qp walk``: one run, a JSON summary and optional log, plot and video."""
    with held_warnings() as unverified:  # said once the input is known good
        options = options_from_args(args)
        scenario = scenario_from_options(options)
        get_profile(scenario.robot).check_supported(options.tracker)
        _check_output_paths(args)
        check_plant(scenario)
    release_warnings(unverified)
    noise = SensorNoise() if options.noise else None
    sim = factory.build_simulation(scenario, options.tracker, seed=options.seed, noise=noise, planner=options.planner)
    recorder = None
    if args.video is not None:
        recorder = VideoRecorder(sim.model, args.video, fps=args.video_fps)
    progress = not args.no_progress and scenario.duration_s >= PROGRESS_MIN_DURATION_S
    try:
        result = sim.run(scenario.duration_s, progress=progress, on_tick=recorder, log=log_mode(args.log))
    finally:
        if recorder is not None:
            recorder.close()
    result.info["scenario"] = scenario.name
    result.info["modifiers"] = scenario.setting.modifiers.describe()
    summ = summary.summarize(result)
    if args.json is not None:
        _write_text("--json", args.json, summary.dumps(summ))
    path = log_file(args.log)
    if path is not None:
        with writing("--log", path):
            save_log(result, path)
    if args.plot is not None:
        from amlip_qp.sim.reports.plots import walk_figure

        with writing("--plot", args.plot):
            walk_figure(result, args.plot, title=f"{scenario.name}: {result.robot} / {result.tracker}")
    if args.json != "-":
        sys.stdout.write(_one_line(summ) + "\n")
    return 1 if result.fell else 0


def _one_line(s: dict) -> str:
    def f(v, fmt):
        return "n/a" if v is None or (isinstance(v, float) and not math.isfinite(v)) else format(v, fmt)

    state = f"FELL at {s['fall_time_s']:.2f} s" if s["fell"] else "walked"
    if s.get("terrain", "flat") != "flat":
        state += f" on {s['terrain']}"
    mv = s["mean_velocity"]
    setting = ""
    mods = s.get("plant_modifiers") or {}
    if (s.get("plant"), s.get("sensors"), s.get("estimator")) != (s["robot"], "ideal", "truth") or mods:
        changed = "".join(f", {k} {v}" for k, v in mods.items())
        setting = f" (plant {s.get('plant')}{changed}, {s.get('sensors')} sensors, {s.get('estimator')} estimator)"
    return (
        f"{s['robot']}/{s['tracker']}{setting} {state}: {s['sim_time_s']:.2f} s simulated, {s['steps']} steps, "
        f"mean v = [{f(mv[0], '.3f')}, {f(mv[1], '.3f')}] m/s, "
        f"velocity error RMS {f(s['velocity_error_rms'], '.3f')} m/s, "
        f"foot placement error RMS {f(s['foot_placement_error_rms_m'], '.3f')} m, "
        f"realtime factor {f(s['realtime_factor'], '.2f')}"
    )
