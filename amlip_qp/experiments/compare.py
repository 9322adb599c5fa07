"""PBC vs QP: the same scenarios, the same seed, one table row per (robot, tracker, planner).

Per robot, tracker and foot-placement planner (the one-step law, the step-timing MPC), three
experiments (independent runs, spread over ``jobs`` worker processes; each run is deterministic for
its seed):

1. the **nominal** scenario (default: the robot profile's, ``cassie-1mps`` /
   ``rabbit-0.5mps``, at most 10 s):
   the :mod:`~amlip_qp.sim.reports.summary` metrics (velocity, foot-placement and
   end-of-step ``L`` errors, output tracking, torques, tick time);
2. a **speed ramp**: :func:`~amlip_qp.experiments.robustness.highest_steady_speed`;
3. **pushes** on the base while walking at the nominal scenario's speed
   profile: the largest sagittal (+x) and lateral (+y, 3-D robots only)
   impulse survived, by bisection (:func:`~amlip_qp.experiments.robustness.max_survived_impulse`).

The experiments' settings and scenarios are :mod:`~amlip_qp.experiments.robustness`'s;
this module runs them; :mod:`~amlip_qp.experiments.compare_table` gathers the rows and prints the table.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
import warnings
from collections.abc import Callable, Sequence
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from typing import Any

from amlip_qp.control import registry
from amlip_qp.exceptions import InputError, UnverifiedCommandWarning
from amlip_qp.experiments.compare_table import DEFAULT_PLANNERS, check_planners, format_table, make_row
from amlip_qp.experiments.robustness import (
    PUSH_DURATION_S,
    QUICK,
    CompareSettings,
    compare_ranges,
    highest_steady_speed,
    max_survived_impulse,
    nominal_scenario,
    push_scenario,
    ramp_scenario,
)
from amlip_qp.experiments.walk import setting_from_args
from amlip_qp.output_paths import check_output_path, writing
from amlip_qp.profiles import compared_robots, get_profile
from amlip_qp.sim.loop.run_types import PlantSetting, RunResult, SensorNoise
from amlip_qp.sim.reports import summary
from amlip_qp.sim.reports.plots import check_figure_path, comparison_figure
from amlip_qp.sim.reports.summary import summarize
from amlip_qp.sim.scenarios import factory
from amlip_qp.sim.scenarios.named import get_scenario
from amlip_qp.sim.scenarios.scenarios import Scenario, check_scenario, held_warnings, release_warnings
from amlip_qp.sim.world.plant_loader import load_plant


# ---------------------------------------------------------------- tasks
@dataclass(frozen=True)
class _Task:
    kind: str  # "nominal", "ramp", "push-x", "push-y"
    robot: str
    tracker: str
    scenario: Scenario
    settings: CompareSettings
    seed: int
    noise: bool
    setting: PlantSetting
    planner: str = "one-step"

    @property
    def name(self) -> str:
        return f"{self.robot}/{self.tracker}/{self.planner} {self.kind}"


def _run(task: _Task, scenario: Scenario) -> RunResult:
    return factory.run_scenario(
        scenario.with_(setting=task.setting),
        task.tracker,
        seed=task.seed,
        noise=SensorNoise() if task.noise else None,
        planner=task.planner,
    )


def _execute(task: _Task) -> dict[str, Any]:
    """Run one experiment (in a worker process); returns the row fields it measures."""
    t0, c0 = time.perf_counter(), time.process_time()
    s = task.settings
    if task.kind == "nominal":
        res = _run(task, task.scenario)
        summ = summarize(res)
        out: dict[str, Any] = {"nominal": summ}
    elif task.kind == "ramp":
        res = _run(task, task.scenario)
        speed = highest_steady_speed(res, s.window_s, s.tolerance)
        out = {
            "highest_steady_speed_mps": speed,
            "speed_at_upper_bound": math.isclose(speed, task.scenario.vx.final_mps, rel_tol=1e-9),
            "ramp_fell": bool(res.fell),
            "ramp_scenario": task.scenario.name,
        }
    else:
        axis = 0 if task.kind == "push-x" else 1
        trials: list[tuple[float, bool]] = []

        def survives(impulse: float) -> bool:
            pushed = push_scenario(task.scenario, impulse, axis, s)
            res = _run(task, pushed)
            trials.append((impulse, not res.fell))
            return not res.fell

        value, capped = max_survived_impulse(
            survives, compare_ranges(task.robot).push_max_impulse_Ns, s.push_iterations
        )
        prefix = "sagittal" if axis == 0 else "lateral"
        out = {
            f"max_{prefix}_impulse_Ns": value,
            f"{prefix}_impulse_at_upper_bound": capped,
            f"{prefix}_push_trials": trials,
        }
    out["_wall_s"] = time.perf_counter() - t0
    out["_cpu_s"] = time.process_time() - c0
    return out


def unsupported_pairs(robots: list[str], trackers: list[str]) -> list[tuple[str, str, str]]:
    """``(robot, tracker, reason)`` of every pair a comparison skips: the robot's profile says the
    tracker cannot run on it (``[unsupported]``)."""
    out = []
    for robot in robots:
        reasons = get_profile(robot).unsupported
        out += [(robot, trk, reasons[trk]) for trk in trackers if trk in reasons]
    return out


def build_tasks(
    robots: list[str],
    trackers: list[str],
    scenario_names: list[str],
    settings: CompareSettings,
    seed: int = 0,
    noise: bool = False,
    ramp: bool = True,
    push: bool = True,
    setting: PlantSetting | None = None,
    planners: Sequence[str] = DEFAULT_PLANNERS,
) -> list[_Task]:
    """Every experiment of a comparison, per robot, tracker and planner (``"one-step"``, ``"mpc"``).

    A ramp past a robot's verified envelope (its profile's ``[verified]``; no shipped profile's) gives
    one :class:`~amlip_qp.exceptions.UnverifiedCommandWarning` for the whole comparison.

    Raises:
        InputError: A plant that does not fit one of the robots (loaded here, once per robot),
            a setting the robot's gait cannot take (a swing clearance above its CoM height),
            or an unknown planner.
    """
    setting = setting or PlantSetting()
    planners = check_planners(planners)
    tasks = []
    unverified: list[str] = []
    for robot in robots:
        nominal = nominal_scenario(robot, scenario_names, settings)
        check_scenario(nominal.with_(setting=setting))  # the setting's clearance against the robot's gait
        if ramp:
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always", UnverifiedCommandWarning)
                check_scenario(ramp_scenario(robot, settings))
            unverified += [f"{robot}'s ramp: {w.message}" for w in caught if w.category is UnverifiedCommandWarning]
        loaded = factory.load(robot)
        planar = loaded.is_planar
        edits = factory.setting_edits(setting, loaded)
        if setting.plant is not None or edits:
            # fail fast (exit 2) on a plant that does not fit or cannot take the modifiers or the terrain
            load_plant(setting.plant or robot, loaded, edits=edits)
        for trk in trackers:
            if trk in get_profile(robot).unsupported:
                continue  # said by the handler (unsupported_pairs)
            for pl in planners:
                common = (settings, seed, noise, setting, pl)
                tasks.append(_Task("nominal", robot, trk, nominal, *common))
                if ramp:
                    tasks.append(_Task("ramp", robot, trk, ramp_scenario(robot, settings), *common))
                if push:
                    tasks.append(_Task("push-x", robot, trk, nominal, *common))
                    if not planar:
                        tasks.append(_Task("push-y", robot, trk, nominal, *common))
    unknown = [n for n in scenario_names if get_scenario(n).robot not in robots]
    if unknown:
        raise InputError(f"--scenario {', '.join(unknown)} is for a robot not in --robots {','.join(robots)}")
    if unverified:
        warnings.warn("; ".join(unverified), UnverifiedCommandWarning, stacklevel=2)
    return tasks


def _expected_cost(task: _Task) -> float:
    """Rough relative cost (simulated seconds x robot weight) used to start long experiments first."""
    s = task.settings
    weight = compare_ranges(task.robot).relative_cost
    if task.kind.startswith("push"):
        return weight * (s.push_iterations + 1) * (s.push_time_s + PUSH_DURATION_S + s.push_survive_s)
    return weight * task.scenario.duration_s


def run_comparison(tasks: list[_Task], jobs: int = 2, log: Callable[[str], None] | None = None) -> list[dict[str, Any]]:
    """Execute ``tasks`` on ``jobs`` processes (1: in this process); one row per (robot, tracker, planner), in
    task order."""
    results: list[dict[str, Any] | None] = [None] * len(tasks)
    if jobs <= 1 or len(tasks) <= 1:
        for i, task in enumerate(tasks):
            row = _execute(task)
            results[i] = row
            if log:
                log(f"  done {task.name} ({row['_wall_s']:.0f} s, CPU {row['_cpu_s']:.0f} s)")
    else:
        import multiprocessing as mp

        order = sorted(range(len(tasks)), key=lambda i: -_expected_cost(tasks[i]))
        with ProcessPoolExecutor(max_workers=jobs, mp_context=mp.get_context("spawn")) as pool:
            futures = {pool.submit(_execute, tasks[i]): i for i in order}
            from concurrent.futures import as_completed

            for fut in as_completed(futures):
                i = futures[fut]
                row = fut.result()
                results[i] = row
                if log:
                    log(f"  done {tasks[i].name} ({row['_wall_s']:.0f} s, CPU {row['_cpu_s']:.0f} s)")
    rows = []
    keys = list(dict.fromkeys((t.robot, t.tracker, t.planner) for t in tasks))
    for key in keys:
        parts = [r for t, r in zip(tasks, results) if (t.robot, t.tracker, t.planner) == key]
        rows.append(make_row(*key, parts))  # type: ignore[arg-type]
    return rows


# ------------------------------------------------------------------ main
def settings_from_args(args: argparse.Namespace) -> CompareSettings:
    """:data:`QUICK` or the default settings, with ``--push-iterations`` applied."""
    s = QUICK if args.quick else CompareSettings()
    if args.push_iterations is not None:
        from dataclasses import replace

        s = replace(s, push_iterations=args.push_iterations)
    return s


def prepare_generated_code(tasks: list[_Task]) -> None:
    """Build one closed loop per (robot, tracker, planner) of ``tasks`` here, before any worker starts.

    Building compiles the generated C (planner kernels, output map, QP
    assembly) into the cache once, in this process: the workers then load it,
    so a cold cache prints one first-run line rather than one per worker, and
    no two workers compile the same library at once.
    """
    done: set[tuple[str, str, str]] = set()
    for task in tasks:
        if (task.robot, task.tracker, task.planner) not in done:
            done.add((task.robot, task.tracker, task.planner))
            # the generated C does not depend on the plant
            factory.build_simulation(task.scenario, task.tracker, planner=task.planner)


def main(args: argparse.Namespace) -> int:
    """The ``compare`` command (see :mod:`amlip_qp.experiments.walk`). Exit 0 (falls are results, not errors)."""
    settings = settings_from_args(args)
    setting = setting_from_args(args, PlantSetting())
    for trk in args.trackers:
        registry.tracker_class(trk)  # fail fast (exit 2) if a tracker is missing
    robots = list(args.robots if args.robots is not None else compared_robots())
    with held_warnings() as unverified:  # said once the input is known good
        tasks = build_tasks(
            robots,
            args.trackers,
            args.scenario,
            settings,
            seed=args.seed,
            noise=args.noise,
            ramp=not args.no_ramp,
            push=not args.no_push,
            setting=setting,
            planners=args.planners,
        )
        # Outputs are checked before anything runs; the figure's folder (default out/) is created.
        check_output_path("--json", args.json)
        if not args.no_plot and args.plot:
            if args.plot == "-":
                raise InputError("--plot cannot write to stdout ('-'); give a file name")
            check_figure_path(args.plot)
            check_output_path("--plot", args.plot, create_folder=True)
    release_warnings(unverified)

    def log(msg: str) -> None:
        sys.stderr.write(msg + "\n")
        sys.stderr.flush()

    for robot, trk, reason in unsupported_pairs(robots, list(args.trackers)):
        log(f"compare: {robot}/{trk} skipped: the {trk} tracker does not run on {robot}: {reason}")
    log(f"compare: {len(tasks)} experiments on {args.jobs} process(es)...")
    t0 = time.perf_counter()
    if args.jobs > 1:
        prepare_generated_code(tasks)
    rows = run_comparison(tasks, jobs=args.jobs, log=log)
    log(f"compare: finished in {time.perf_counter() - t0:.0f} s")
    table = format_table(rows)
    if args.json == "-":
        sys.stdout.write(summary.dumps({"rows": rows, "settings": _settings_dict(settings, args)}) + "\n")
    else:
        sys.stdout.write(table + "\n")
        if args.json is not None:
            with writing("--json", args.json), open(args.json, "w") as fh:
                fh.write(summary.dumps({"rows": rows, "settings": _settings_dict(settings, args)}) + "\n")
    if not args.no_plot and args.plot:
        with writing("--plot", args.plot):
            path = comparison_figure(rows, args.plot)
        log(f"compare: figure written to {path}")
    return 0


def _settings_dict(settings: CompareSettings, args: argparse.Namespace) -> dict[str, Any]:
    from dataclasses import asdict

    d = asdict(settings)
    d.update(seed=args.seed, noise=args.noise, push_duration_s=PUSH_DURATION_S, planners=list(args.planners))
    d.update(setting_from_args(args, PlantSetting()).describe())
    # the per-robot ranges of the profiles, as (robot, value) pairs
    robots = args.robots if args.robots is not None else compared_robots()
    d.update(
        ramp_end_mps=tuple((r, compare_ranges(r).ramp_end_mps) for r in robots),
        push_max_impulse_Ns=tuple((r, compare_ranges(r).push_max_impulse_Ns) for r in robots),
    )
    return d
