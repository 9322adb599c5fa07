"""Handler of ``amlip-qp walk`` (parser in :mod:`amlip_qp.cli`).

``walk`` exit status: 0 when the run finished standing, 1 when the robot
fell (the summary, log, plot and video are still written), 2 for bad input.
"""

from __future__ import annotations

import argparse
import math
import sys
from dataclasses import replace

import numpy as np

from amlip_qp.exceptions import InputError
from amlip_qp.output_paths import check_output_path, writing
from amlip_qp.profiles import DEFAULT_ROBOT, NO_SHAPING, get_profile
from amlip_qp.sim.loop.run_log import LOG_MODES
from amlip_qp.sim.loop.run_types import PlantSetting, Push, RunResult, SensorNoise
from amlip_qp.sim.reports import summary
from amlip_qp.sim.reports.video import VideoRecorder, check_video_fps, check_video_path
from amlip_qp.sim.scenarios import factory
from amlip_qp.sim.scenarios.named import get_scenario
from amlip_qp.sim.scenarios.scenarios import (
    Scenario,
    SpeedProfile,
    check_scenario,
    held_warnings,
    release_warnings,
)
from amlip_qp.sim.world.plant_loader import load_plant
from amlip_qp.sim.world.plant_modifiers import parse_payload
from amlip_qp.sim.world.terrain import parse_terrain

#: Runs at least this long (simulated s) show a progress bar on stderr.
PROGRESS_MIN_DURATION_S = 3.0
#: Default simulated time of ``walk`` without a scenario, s.
DEFAULT_WALK_DURATION_S = 10.0


def scenario_from_args(args: argparse.Namespace) -> Scenario:
    """The :class:`Scenario` ``walk`` runs: ``--scenario`` (or a steady walk) with the explicit options applied.

    Speeds are m/s, ``--turn-rate`` is deg/s (converted to rad/s here, once),
    pushes come pre-parsed as ``(t_s, (fx, fy, fz), duration_s)``.

    Raises:
        InputError: An unknown scenario, a robot that contradicts it, or a
            command, duration or push outside the robot's bounds
            (:func:`~amlip_qp.sim.scenarios.scenarios.check_scenario`).
    """
    if args.scenario is not None:
        base = get_scenario(args.scenario)
        if args.robot is not None and args.robot != base.robot:
            raise InputError(f"scenario {base.name!r} is for {base.robot}, but --robot {args.robot} was given")
    else:
        base = Scenario("custom", args.robot or DEFAULT_ROBOT, DEFAULT_WALK_DURATION_S)
    changes: dict = {}
    if args.speed_profile is not None:
        changes["vx"] = SpeedProfile.parse(args.speed_profile)
    elif args.vx is not None:
        changes["vx"] = SpeedProfile.constant(args.vx)
    if args.vy is not None:
        changes["vy_mps"] = args.vy
    if args.turn_rate is not None:
        changes["turn_rate_radps"] = math.radians(args.turn_rate)
        changes["turn_start_s"] = 0.0
        changes["turn_angle_rad"] = math.inf
    if args.duration is not None:
        changes["duration_s"] = args.duration
    if args.push:
        changes["pushes"] = tuple(base.pushes) + tuple(Push(t, f, d) for t, f, d in args.push)
    if args.no_command_shaping:
        changes["shaping"] = NO_SHAPING
    elif args.accel_limit is not None:
        shaping = base.shaping or get_profile(base.robot).shaping
        changes["shaping"] = replace(shaping, vx_accel_mps2=args.accel_limit, vy_accel_mps2=args.accel_limit)
    setting = setting_from_args(args, base.setting)
    if setting != base.setting:
        changes["setting"] = setting
    if changes and base.name != "custom":
        changes["name"] = f"{base.name}+options"
    scenario = base.with_(**changes) if changes else base
    check_scenario(scenario)
    return scenario


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
    """``base`` (a scenario's setting, its IMU mounting kept) with ``--plant``, ``--sensors``, ``--estimator``,
    ``--terrain``, the modifiers.

    Raises:
        InputError: ``--noise`` with robot sensors, a malformed ``--payload`` or
            ``--terrain``, or a nonsensical modifier value (one line saying what to fix).
    """
    mods: dict = {}
    if args.plant_mass_scale is not None:
        mods["mass_scale"] = args.plant_mass_scale
    if args.payload is not None:
        mods["payload_kg"], mods["payload_pos_m"] = parse_payload(args.payload)
    if args.plant_spring_scale is not None:
        mods["spring_scale"] = args.plant_spring_scale
    if args.friction is not None:
        mods["friction"] = args.friction
    if args.actuator_delay is not None:
        mods["actuator_delay_ticks"] = args.actuator_delay
    terrain = base.terrain
    if args.terrain is not None:
        terrain = parse_terrain(args.terrain).text
    setting = PlantSetting(
        plant=base.plant if args.plant is None else args.plant,
        sensors=base.sensors if args.sensors is None else args.sensors,
        estimator=base.estimator if args.estimator is None else args.estimator,
        modifiers=replace(base.modifiers, **mods) if mods else base.modifiers,
        terrain=terrain,
        terrain_aware=base.terrain_aware if args.terrain_aware is None else args.terrain_aware,
        clearance_m=base.clearance_m if args.clearance is None else args.clearance,
        imu=base.imu,
    )
    if args.noise and setting.sensors != "ideal":
        raise InputError("--noise adds Gaussian noise to the ideal sensors; --sensors robot has its own: give one")
    return setting


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
        scenario = scenario_from_args(args)
        get_profile(scenario.robot).check_supported(args.tracker)
        _check_output_paths(args)
        check_plant(scenario)
    release_warnings(unverified)
    noise = SensorNoise() if args.noise else None
    sim = factory.build_simulation(scenario, args.tracker, seed=args.seed, noise=noise, planner=args.planner)
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
