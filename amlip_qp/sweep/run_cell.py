"""A sweep cell -> one deterministic walk -> its metrics.

A cell's parameters are the walk options
(:class:`amlip_qp.sim.scenarios.options.WalkOptions`, named as ``walk``'s
options are stored: ``vx``, ``tracker``, ``plant_mass_scale``, ``terrain``,
...; ``--turn-rate`` is ``turn_rate``) and the push parameters. The cell's
walk options are checked by :meth:`~amlip_qp.sim.scenarios.options.WalkOptions.from_mapping`
(the value checks the command line's types are made of; a bad value is one
line naming the parameter) and made a scenario by
:func:`amlip_qp.sim.scenarios.from_options.scenario_from_options`, the
constructor ``amlip-qp walk`` uses on its own parsed options: no command line
is written or parsed, and every ``walk`` option but the outputs is a
parameter (the tests hold the two lists equal). A flag (``noise``,
``terrain_aware``) takes ``true`` or ``false``. The push parameters
(:data:`PUSH_DEFAULTS`) add one push on the base: ``push_impulse_Ns`` (0: no
push), ``push_direction_deg`` (in the horizontal plane from +x, forward,
towards +y, left), ``push_phase`` (the step phase it starts at, after
``push_time_s``; none: at ``push_time_s``), ``push_duration_s`` and
``push_time_s``. Force = impulse / duration.
"""

from __future__ import annotations

import math
import time
import warnings
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from amlip_qp.exceptions import InputError, UnverifiedCommandWarning
from amlip_qp.sim.scenarios.options import WalkOptions  # light: plain data and value checks

#: Push parameters and their defaults (``None``: no phase trigger, the push starts at ``push_time_s``).
PUSH_DEFAULTS: dict[str, float | None] = {
    "push_impulse_Ns": 0.0,
    "push_direction_deg": 0.0,
    "push_phase": None,
    "push_duration_s": 0.2,
    "push_time_s": 2.0,
}
#: Metric name -> how it is read from the JSON summary (:func:`amlip_qp.sim.reports.summary.summarize`).
_METRIC_READERS: dict[str, Any] = {
    "survived": lambda s: not s["fell"],
    "fell": lambda s: s["fell"],
    "fall_time_s": lambda s: s["fall_time_s"],
    "sim_time_s": lambda s: s["sim_time_s"],
    "steps": lambda s: s["steps"],
    "mean_vx_mps": lambda s: s["mean_velocity"][0],
    "mean_vy_mps": lambda s: s["mean_velocity"][1],
    "velocity_error_rms": lambda s: s["velocity_error_rms"],
    "foot_placement_error_rms_m": lambda s: s["foot_placement_error_rms_m"],
    "L_end_of_step_error_rms": lambda s: s["L_end_of_step_error_rms"],
    "heading_change_deg": lambda s: s["heading_change_deg"],
    "fallback_ticks": lambda s: s["fallback_ticks"],
    "tracker_failed_ticks": lambda s: s["tracker_failed_ticks"],
    "safe_mode_ticks": lambda s: s["safe_mode_ticks"],
    "estimator_divergences": lambda s: s["estimator_divergences"],
    "base_velocity_error_rms_mps": lambda s: s["base_velocity_error_rms_mps"],
    "yaw_estimate_error_deg": lambda s: s["yaw_estimate_error_deg"],
    # wall-clock measures: they depend on the machine and its load, so they differ from run to run
    "realtime_factor": lambda s: s["realtime_factor"],
    "tick_time_median_us": lambda s: s["tick_time_us"]["median"],
}
#: Every metric a walk cell can report (see ``docs``: the summary schema for their definitions).
METRICS: tuple[str, ...] = tuple(_METRIC_READERS)
#: The metrics kept when a spec names none (all reproducible: no wall-clock measure).
DEFAULT_METRICS: tuple[str, ...] = (
    "survived",
    "fall_time_s",
    "steps",
    "mean_vx_mps",
    "velocity_error_rms",
    "foot_placement_error_rms_m",
)


def walk_defaults() -> dict[str, Any]:
    """The sweepable walk options and their defaults (:meth:`WalkOptions.defaults
    <amlip_qp.sim.scenarios.options.WalkOptions.defaults>`)."""
    return WalkOptions.defaults()


def parameter_names() -> tuple[str, ...]:
    """Every sweepable parameter: the walk options, then the push parameters."""
    return (*WalkOptions.names(), *PUSH_DEFAULTS)


def _describe(params: Mapping[str, Any]) -> str:
    return ", ".join(f"{name}={value}" for name, value in params.items()) or "defaults"


@dataclass(frozen=True)
class WalkRun:
    """What one walk of a cell needs: the scenario, the tracker, the seed, Gaussian noise on or off, the planner."""

    scenario: Any  # amlip_qp.sim.scenarios.scenarios.Scenario (imported lazily: this module stays light)
    tracker: str
    seed: int
    noise: bool
    planner: str = "one-step"


def make_push(params: Mapping[str, Any]):
    """The push of ``params`` (:data:`PUSH_DEFAULTS` for the missing ones), or ``None`` for a zero impulse."""
    from amlip_qp.sim.loop.run_types import Push

    p = {**PUSH_DEFAULTS, **{k: v for k, v in params.items() if k in PUSH_DEFAULTS}}
    for name, value in p.items():
        if value is not None and (isinstance(value, bool) or not isinstance(value, (int, float))):
            raise InputError(f"{name} must be a number, got {value!r}")
    impulse, duration = float(p["push_impulse_Ns"]), float(p["push_duration_s"])
    if not (math.isfinite(impulse) and impulse >= 0 and duration > 0):
        raise InputError(f"a push needs push_impulse_Ns >= 0 and push_duration_s > 0, got {impulse!r}, {duration!r}")
    if impulse == 0.0:
        return None
    angle = math.radians(float(p["push_direction_deg"]))
    force = impulse / duration
    # exact zeros where the direction is along an axis (cos 90 deg is 6e-17, not 0: a planar robot refuses any FY)
    fx, fy = (0.0 if abs(c) < 1e-12 else force * c for c in (math.cos(angle), math.sin(angle)))
    phase = p["push_phase"]
    return Push(float(p["push_time_s"]), (fx, fy, 0.0), duration, None if phase is None else float(phase))


def walk_run(params: Mapping[str, Any], seed: int) -> WalkRun:
    """The walk of a cell with these parameters and seed (``seed`` is used unless the cell sets ``seed``).

    Raises:
        InputError: An unknown or malformed option or value, a command outside the
            robot's bounds, or a phase push that may not start before the walk ends.
    """
    from amlip_qp.sim.scenarios.from_options import scenario_from_options
    from amlip_qp.sim.scenarios.scenarios import check_scenario

    unknown = [n for n in params if n not in parameter_names()]
    if unknown:
        raise InputError(f"unknown parameter {unknown[0]!r}; known: {', '.join(parameter_names())}")
    walk_params = {k: v for k, v in params.items() if k not in PUSH_DEFAULTS}
    if "seed" not in params:
        walk_params["seed"] = seed
    options = WalkOptions.from_mapping(walk_params)  # its errors name the parameter
    try:
        scenario = scenario_from_options(options)
        push = make_push(params)
        if push is not None:
            scenario = scenario.with_(pushes=(*scenario.pushes, push))
            check_scenario(scenario)
            if push.phase is not None:
                latest_end = push.t_s + 2.0 * scenario.gait_settings.step_time_s + push.duration_s
                if scenario.duration_s < latest_end:
                    raise InputError(
                        f"a push at step phase {push.phase:g} after {push.t_s:g} s may start up to one step late: "
                        f"give a duration of at least {latest_end:g} s, got {scenario.duration_s:g} s"
                    )
    except InputError as exc:
        raise InputError(f"walk {_describe(params)}: {exc}") from None
    return WalkRun(scenario, options.tracker, options.seed, options.noise, options.planner)


def check_plants(runs: list[WalkRun]) -> None:
    """Load each distinct plant setting once (with its modifiers), so a bad plant fails before any walk."""
    from amlip_qp.experiments.walk import check_plant

    seen = set()
    for run in runs:
        key = (run.scenario.robot, run.scenario.setting)
        if key not in seen:
            seen.add(key)
            check_plant(run.scenario)


def walk(run: WalkRun) -> dict[str, Any]:
    """Simulate one walk; every metric of :data:`METRICS` (JSON values: NaN as ``None``)."""
    from amlip_qp.sim.loop.run_types import SensorNoise
    from amlip_qp.sim.reports import summary
    from amlip_qp.sim.scenarios import factory

    sc = run.scenario
    noise = SensorNoise() if run.noise else None
    sim = factory.build_simulation(sc, run.tracker, seed=run.seed, noise=noise, planner=run.planner)
    result = sim.run(sc.duration_s, log="summary")  # the metrics read only the summary
    result.info["scenario"] = sc.name
    result.info["modifiers"] = sc.setting.modifiers.describe()
    summ = summary.to_jsonable(summary.summarize(result))
    return {name: read(summ) for name, read in _METRIC_READERS.items()}


def run_cell(task: dict[str, Any]) -> dict[str, Any]:
    """Run one cell (in a worker process or a Ray task) and return its record.

    ``task``: ``{"index", "id", "seed", "params", "bisect"}`` with ``bisect``
    ``None`` or ``{"parameter", "low", "high", "iterations"}``. The record is
    the task with ``metrics``, ``error`` and ``wall_s`` added; with a bisection
    the metrics are ``max_<parameter>``, ``max_<parameter>_capped`` and
    ``bisect_walks``. A cell whose walk raises does not stop the sweep: its
    record has no metrics and ``error`` says what was raised (one line,
    :func:`error_text`); ``error`` is ``None`` otherwise.
    """
    t0 = time.perf_counter()
    try:
        with warnings.catch_warnings():  # the sweep said it once, when it checked the cells
            warnings.simplefilter("ignore", UnverifiedCommandWarning)
            metrics, error = cell_metrics(task), None
    except Exception as exc:  # any failure of one cell is recorded, not fatal to the sweep
        metrics, error = {}, error_text(exc)
    return {**task, "metrics": metrics, "error": error, "wall_s": time.perf_counter() - t0}


def cell_metrics(task: dict[str, Any]) -> dict[str, Any]:
    """The metrics of one cell (see :func:`run_cell`); raises whatever its walks raise."""
    from amlip_qp.experiments.robustness import largest_surviving

    params, seed, bis = task["params"], task["seed"], task["bisect"]
    if bis is None:
        return walk(walk_run(params, seed))
    name = bis["parameter"]

    def survives(value: float) -> bool:
        return bool(walk(walk_run({**params, name: value}, seed))["survived"])

    value, capped, trials = largest_surviving(survives, bis["low"], bis["high"], bis["iterations"])
    return {f"max_{name}": value, f"max_{name}_capped": capped, "bisect_walks": len(trials)}


def crashed_record(task: dict[str, Any], *, deaths: int) -> dict[str, Any]:
    """The record of a cell whose worker process died ``deaths`` times while running it
    (a crash in native code, the out-of-memory killer): no metrics, the error says so."""
    error = f"WorkerDied: the worker process died {deaths} times with this cell in flight (a crash or out of memory)"
    return {**task, "metrics": {}, "error": error, "wall_s": 0.0}


def error_text(exc: BaseException) -> str:
    """``"TypeName: first line of the message"`` (at most 300 characters): a failed cell's ``error``."""
    lines = str(exc).strip().splitlines()
    text = f"{type(exc).__name__}: {lines[0]}" if lines else type(exc).__name__
    return text if len(text) <= 300 else text[:297] + "..."
