"""``amlip-qp bench harness``: where a closed-loop tick goes, per tracker and log mode.

Every tick of :meth:`~amlip_qp.sim.loop.harness.Simulation.run` is timed in three
parts: the controller's ``step`` (``tick_time_us``), MuJoCo's plant steps
(``mujoco_time_us``) and the rest of the loop, the harness's own time
(``harness_time_us``: reading the plant state, sensors, command, controls,
pushes, logging, fall checks). :func:`run` walks a scenario with each tracker
in both log modes (``full`` and ``summary``), repeatedly, taking turns
(tracker by tracker, mode by mode, repeat by repeat), so the speed drifts of a
shared machine (up to 1.6x within minutes on the 2-core development machine)
affect every configuration alike. It reports, per tracker and mode, the
median of each part over all ticks of all repeats, their sum, and the median
real-time factor; it also checks that both log modes give the same summary
(timing fields aside), as they walk the same trajectory.

The speed goals are numbers in units of MuJoCo's step time of the same walk,
which is the same work in every version of the code, so that runs made at
different machine speeds compare: for the 10-s ``cassie-1mps`` QP walk, the
harness's own time at most 0.75 MuJoCo steps per tick
(:data:`GOAL_HARNESS_PER_MUJOCO`), and the walk at 1.0x real time or faster
(:data:`GOAL_REALTIME_FACTOR`) on the reference machine state, on which a walk
costing :data:`REFERENCE_TICK_PER_MUJOCO` MuJoCo steps of wall time per tick
ran at :data:`REFERENCE_REALTIME_FACTOR`: a wall time of at most 8.58 MuJoCo
steps per tick (:data:`GOAL_TICK_PER_MUJOCO`). A walk of ``tick_per_mujoco``
steps per tick runs at ``realtime_factor_at_reference`` on that machine state.
``examples/speed_against.py`` walks another checkout and this one
interleaved and times both the same way; it is the primary measure of a
change. MuJoCo's step inside the loop is a stable yardstick under the shared
machine's load, but it depends a little on the code under test (a leaner loop
leaves MuJoCo's data in the caches, so its step runs faster), which makes these
verdicts conservative for a leaner loop. Each row also gives MuJoCo's
step time alone (:mod:`amlip_qp.experiments.mujoco_yardstick`, replayed on the state at
the end of the warm-up walk, after each walk) and the tick and harness in such
steps, for information: that yardstick does not depend on the code, but it
swings with the machine's load. Recording needs the plant, so the benchmark
lives in ``sim``.

The controller's own speed goals (:mod:`amlip_qp.experiments.bench_goals`) are judged
per row in MuJoCo steps: the controller's tick and the tracker's own work per
tick (the kinematics update and the tracker's ``compute``, recorded by the controller's
:class:`~amlip_qp.control.walking.stage_timer.StageTimer`) over MuJoCo's step in the
same tick of the loop, medians over the ticks (the goals' unit: MuJoCo's step
inside the walking loop, 35-40 µs for Cassie on the development machine; both
parts of a tick see the same machine state); and the real-time factor against
the robot's ``[compare] realtime_goal`` on its nominal walk. The same two are
also given over the yardstick's step alone with every step timed on its own
(:func:`~amlip_qp.experiments.mujoco_yardstick.step_median_us`, robust to a step
preempted by another process; a warm-cache step, about 2.4 times shorter
than the loop's), the median over the walks. The controller's tick is split into the estimate, the
planner's update, the tracker's own work and the rest, and for a tracker that times its own build
and solve (the QP tracker's ``info``) the tracker's work into the kinematics update, the problem's
build, the solver's call and the rest, each over MuJoCo's step in the same tick.
"""

from __future__ import annotations

import argparse
from collections.abc import Callable
from typing import TYPE_CHECKING, cast

import numpy as np

from amlip_qp.control.registry import TRACKER_MODULES, tracker_class
from amlip_qp.control.walking.stage_timer import StageTimer
from amlip_qp.exceptions import InputError
from amlip_qp.experiments.bench_goals import realtime_goal, tick_goals, tracker_base
from amlip_qp.experiments.bench_harness_report import format_report
from amlip_qp.experiments.mujoco_yardstick import snapshot_walk, step_median_us, step_time_us
from amlip_qp.profiles import DEFAULT_SCENARIO, bundled_names, get_profile
from amlip_qp.sim.loop.run_log import LOG_MODES
from amlip_qp.sim.reports.summary import TIMING_FIELDS, summarize, to_jsonable
from amlip_qp.sim.scenarios.factory import build_simulation, load
from amlip_qp.sim.scenarios.named import get_scenario

if TYPE_CHECKING:
    from amlip_qp.control.tracker import Tracker

#: The goal for a QP walk: simulated time / wall time, at least, on the reference machine state.
GOAL_REALTIME_FACTOR = 1.0

#: The reference walk: the 10-s ``cassie-1mps`` QP walk of an earlier version of the code on the
#: 2-core development machine (the medians of 6 walks of ``examples/speed_against.py --reference``,
#: interleaved with this code). Its wall time per tick and its harness's own time per tick (wall
#: time less controller and MuJoCo: its harness reports no split), each divided by MuJoCo's step
#: time per tick of the same walk (MuJoCo's step is the same work in every version, so the ratios
#: compare runs made at different machine speeds; a leaner harness leaves MuJoCo's step a little
#: faster, so these ratios slightly understate a leaner code's gain). MuJoCo steps per tick.
REFERENCE_TICK_PER_MUJOCO = 13.2
REFERENCE_HARNESS_PER_MUJOCO = 3.01

#: The real-time factor of the reference walk: the machine state the real-time goal is judged at.
REFERENCE_REALTIME_FACTOR = 0.65

#: The scenario and tracker of the reference walks: the goals are judged on those only.
REFERENCE_SCENARIO, REFERENCE_TRACKER = DEFAULT_SCENARIO, "qp"

#: The harness goal: at most a quarter of the reference's own cost per tick, 0.75 MuJoCo steps per tick.
GOAL_HARNESS_PER_MUJOCO = REFERENCE_HARNESS_PER_MUJOCO / 4.0

#: The real-time goal as a cost: at most 8.58 MuJoCo steps of wall time per tick.
GOAL_TICK_PER_MUJOCO = REFERENCE_REALTIME_FACTOR * REFERENCE_TICK_PER_MUJOCO / GOAL_REALTIME_FACTOR

#: Tracker variants the benchmark knows besides :data:`TRACKER_MODULES`' names: ``name -> (tracker, options)``.
VARIANTS: dict[str, tuple[str, dict[str, object]]] = {
    "qp-gathered": ("qp", {"in_place_assembly": False}),
    "qp-daqp": ("qp", {"qp_solver": "daqp"}),
    "qp-proxqp": ("qp", {"qp_solver": "proxqp"}),
    "qp-full": ("qp", {"airborne_reduction": False}),
}

#: The tracker's work and the parts of it the stage timer records, per tick (``StageTimer``'s lists).
_WORK_PARTS = ("tracker", "kinematics", "build", "solve", "ik", "compensation", "dynamics")
#: The controller's stages besides the tracker's work the stage timer records (``StageTimer``'s lists).
_TICK_PARTS = ("estimate", "plan")


#: Simulated time of the warm-up walk of each tracker (not timed; its end state is the step-alone yardstick's), s.
WARMUP_S = 0.5


def run(
    scenario: str = DEFAULT_SCENARIO,
    duration_s: float = 3.0,
    repeats: int = 3,
    trackers: tuple[str, ...] = ("qp", "pbc"),
) -> dict:
    """Walk ``scenario`` for ``duration_s`` with each tracker in each log mode, ``repeats`` times, interleaved.

    Returns:
        The report: per ``"{tracker}/{mode}"`` the medians (µs per tick) of the
        controller, MuJoCo and harness times and their sum, the median real-time
        factor, the tracker's own work per tick (``tracker_us_per_tick``), the wall time per tick and the
        harness's mean per tick in MuJoCo
        steps (``tick_per_mujoco``, ``harness_per_mujoco``), the real-time factor
        on the reference's machine state (``realtime_factor_at_reference``),
        MuJoCo's step time alone (``step_alone_us``, the median after each
        walk) and the tick and harness in a tick's worth of such steps
        (``tick_per_step``, ``harness_per_step``: medians of the walks' ratios), the median of
        a single step's time (``step_median_us``) and the controller's tick
        and the tracker's work in such steps (``controller_per_step``,
        ``tracker_per_step``), the same two over MuJoCo's step in the same
        tick, medians over the ticks (``controller_per_loop_step``,
        ``tracker_per_loop_step``: both parts of one tick see the same machine
        state), the tracker's work in its parts in the same unit (``tracker_parts_per_loop_step``,
        :func:`tracker_parts`), the controller's tick in its parts (``controller_parts_per_loop_step``,
        :func:`controller_parts`), the goals of :func:`speed_goals` with their
        verdicts (``speed_goals``), the ticks timed, and whether any walk fell; ``same_summary`` per tracker (the
        two modes' summaries agree, timing fields aside); ``reference`` (the
        reference walk's figures), the goals (``goal_realtime_factor``,
        ``goal_tick_per_mujoco``, ``goal_harness_per_mujoco``) and their verdicts,
        given only for the QP rows (``qp`` and ``qp-gathered``, :data:`VARIANTS`)
        of the reference's scenario (empty otherwise: the goals are set there).

    Raises:
        InputError: An unknown scenario or tracker, a non-positive duration or repeat count.
    """
    sc = get_scenario(scenario)
    known = (*TRACKER_MODULES, *VARIANTS)
    unknown = [t for t in trackers if t not in known]
    if unknown or not trackers:
        raise InputError(f"unknown trackers {unknown or '(none given)'}; known: {', '.join(known)}")
    if repeats < 1 or not duration_s > 0:
        raise InputError(f"bench harness needs repeats >= 1 and a duration > 0 s, got {repeats}, {duration_s}")
    sc = sc.with_(duration_s=duration_s)
    states = {  # warm-up (imports, compiled kernels, caches), and the state the step-alone yardstick replays
        tracker: snapshot_walk(lambda tracker=tracker: build_simulation(sc, tracker_for(sc, tracker)).run(WARMUP_S))
        for tracker in trackers
    }
    per_step: dict[str, dict[str, list[float]]] = {}
    parts: dict[str, dict[str, list[np.ndarray]]] = {}
    rtf: dict[str, list[float]] = {}
    wall: dict[str, float] = {}
    fell: dict[str, bool] = {}
    summaries: dict[str, list[dict]] = {}
    for _ in range(repeats):
        for tracker in trackers:
            for mode in LOG_MODES:
                key = f"{tracker}/{mode}"
                timer = StageTimer()
                sim = build_simulation(sc, tracker_for(sc, tracker), stage_timer=timer)
                result = sim.run(duration_s, log=mode)
                alone = step_time_us(*states[tracker])
                step_us = step_median_us(*states[tracker]) * sim.substeps  # a tick's MuJoCo steps, each timed
                ratios = per_step.setdefault(
                    key, {"alone": [], "tick": [], "harness": [], "step": [], "controller": [], "tracker": []}
                )
                ratios["step"].append(step_us)
                ratios["alone"].append(alone)
                tick_alone = alone * sim.substeps  # a tick's MuJoCo steps, alone
                ratios["tick"].append(result.wall_time_s * 1e6 / len(result.tick_time_us) / tick_alone)
                ratios["harness"].append(float(np.mean(result.harness_time_us)) / tick_alone)
                ratios["controller"].append(float(np.median(result.tick_time_us)) / step_us)
                ratios["tracker"].append(float(np.median(timer.tracker_work_us)) / step_us)
                got = parts.setdefault(
                    key, {name: [] for name in ("controller", "mujoco", "harness", *_WORK_PARTS, *_TICK_PARTS)}
                )
                got["controller"].append(np.asarray(result.tick_time_us))
                got["mujoco"].append(np.asarray(result.mujoco_time_us))
                got["harness"].append(np.asarray(result.harness_time_us))
                got["tracker"].append(np.asarray(timer.tracker_work_us))
                got["kinematics"].append(np.asarray(timer.kinematics_us))
                got["build"].append(np.asarray(timer.build_us))
                got["solve"].append(np.asarray(timer.solve_us))
                for part in ("ik", "compensation", "dynamics"):
                    got[part].append(np.asarray(getattr(timer, f"{part}_us")))
                got["estimate"].append(np.asarray(timer.estimate_us))
                got["plan"].append(np.asarray(timer.plan_us))
                rtf.setdefault(key, []).append(result.sim_time_s / result.wall_time_s)
                wall[key] = wall.get(key, 0.0) + result.wall_time_s
                fell[key] = fell.get(key, False) or bool(result.fell)
                summ = to_jsonable({k: v for k, v in summarize(result).items() if k not in TIMING_FIELDS})
                summaries.setdefault(tracker, []).append(summ)
    report: dict = {"scenario": scenario, "duration_s": duration_s, "repeats": repeats, "runs": {}}
    for key, got in parts.items():
        ticks = {name: np.concatenate(arrays) for name, arrays in got.items()}
        med = {name: float(np.median(a)) for name, a in ticks.items()}
        n = int(ticks["controller"].size)
        mujoco_mean = float(np.mean(ticks["mujoco"]))
        tick_per_mujoco = wall[key] * 1e6 / n / mujoco_mean
        report["runs"][key] = {
            "controller_us_per_tick": med["controller"],
            "mujoco_us_per_tick": med["mujoco"],
            "harness_us_per_tick": med["harness"],
            "sum_us_per_tick": med["controller"] + med["mujoco"] + med["harness"],
            "tracker_us_per_tick": med["tracker"],
            "realtime_factor": float(np.median(rtf[key])),
            "tick_per_mujoco": tick_per_mujoco,
            "harness_per_mujoco": float(np.mean(ticks["harness"])) / mujoco_mean,
            "realtime_factor_at_reference": reference_realtime(tick_per_mujoco),
            "step_alone_us": float(np.median(per_step[key]["alone"])),
            "tick_per_step": float(np.median(per_step[key]["tick"])),
            "harness_per_step": float(np.median(per_step[key]["harness"])),
            "step_median_us": float(np.median(per_step[key]["step"])),
            "controller_per_step": float(np.median(per_step[key]["controller"])),
            "tracker_per_step": float(np.median(per_step[key]["tracker"])),
            "controller_per_loop_step": _per_tick_ratio(ticks["controller"], ticks["mujoco"]),
            "tracker_per_loop_step": _per_tick_ratio(ticks["tracker"], ticks["mujoco"]),
            "tracker_parts_per_loop_step": tracker_parts(ticks),
            "controller_parts_per_loop_step": controller_parts(ticks),
            "ticks": n,
            "fell": fell[key],
        }
        report["runs"][key]["speed_goals"] = speed_goals(sc.robot, scenario, key, report["runs"][key])
    report["same_summary"] = {t: all(s == summaries[t][0] for s in summaries[t]) for t in trackers}
    report["reference"] = {
        "scenario": REFERENCE_SCENARIO,
        "tracker": REFERENCE_TRACKER,
        "tick_per_mujoco": REFERENCE_TICK_PER_MUJOCO,
        "harness_per_mujoco": REFERENCE_HARNESS_PER_MUJOCO,
        "realtime_factor": REFERENCE_REALTIME_FACTOR,
    }
    report["goal_realtime_factor"] = GOAL_REALTIME_FACTOR
    report["goal_harness_per_mujoco"] = GOAL_HARNESS_PER_MUJOCO
    report["goal_tick_per_mujoco"] = GOAL_TICK_PER_MUJOCO
    same_walk = scenario == REFERENCE_SCENARIO
    qp_rows = {
        key: row for key, row in report["runs"].items() if same_walk and key.split("/")[0] in _QP_NAMES
    }  # the goals are set for QP walks: no verdict on another tracker's
    report["qp_meets_realtime_goal"] = {
        key: bool(row["realtime_factor_at_reference"] >= GOAL_REALTIME_FACTOR)
        for key, row in qp_rows.items()
        if key.endswith("/summary")
    }
    report["harness_meets_goal"] = {
        key: bool(row["harness_per_mujoco"] <= GOAL_HARNESS_PER_MUJOCO) for key, row in qp_rows.items()
    }
    return report


#: The QP tracker's names in the report (the goals are set for QP walks).
_QP_NAMES = (REFERENCE_TRACKER, *(name for name, (base, _) in VARIANTS.items() if base == REFERENCE_TRACKER))


def tracker_parts(ticks: dict[str, np.ndarray]) -> dict[str, float]:
    """The tracker's own work per tick in its parts, each over MuJoCo's step in the same tick of the loop,
    medians over the ticks: ``kinematics`` (the update at the measured state), the parts of ``compute``
    the tracker times in its ``info`` (the QP's ``build`` and ``solve``: the problem's build and the
    solver's call; the PBC's ``ik``, ``compensation`` and ``dynamics``: the IK, the swing compensation,
    zero where the tracker has none, and the constrained dynamics' assembly and solve) and ``rest`` (the
    rest of its ``compute``: checks, torques, the result). Empty when the tracker times none of them, or
    when the ticks do not pair up with MuJoCo's (a safe-mode tick)."""
    mujoco = ticks["mujoco"]
    if ticks["tracker"].shape != mujoco.shape:
        return {}
    for names in (("build", "solve"), ("ik", "compensation", "dynamics")):
        timed = {name: ticks[name] for name in names}
        if any(t.shape != mujoco.shape for t in timed.values()) or np.isnan(timed[names[0]]).all():
            continue
        if "compensation" in timed:
            timed["compensation"] = np.nan_to_num(timed["compensation"], nan=0.0)
        rest = ticks["tracker"] - ticks["kinematics"] - sum(timed.values())
        named = {"kinematics": ticks["kinematics"], **timed, "rest": rest}
        return {name: float(np.nanmedian(part / mujoco)) for name, part in named.items()}
    return {}


def controller_parts(ticks: dict[str, np.ndarray]) -> dict[str, float]:
    """The controller's tick in its parts, each over MuJoCo's step in the same tick of the loop, medians
    over the ticks: ``estimate`` (the state estimate, the step clock and its touchdown test, the command's
    speed correction), ``plan`` (the planner's update), ``tracker`` (the tracker's own work: the
    kinematics update and its ``compute``) and ``rest`` (the rest of the controller's ``step``: the
    input checks, the command shaping, the tracking target, the torque limits, the tick's record).
    Empty when the ticks do not pair up with MuJoCo's (a safe-mode tick)."""
    mujoco = ticks["mujoco"]
    if any(ticks[name].shape != mujoco.shape for name in ("controller", "tracker", *_TICK_PARTS)):
        return {}
    rest = ticks["controller"] - ticks["estimate"] - ticks["plan"] - ticks["tracker"]
    named = {"estimate": ticks["estimate"], "plan": ticks["plan"], "tracker": ticks["tracker"], "rest": rest}
    return {name: float(np.median(part / mujoco)) for name, part in named.items()}


def _per_tick_ratio(part_us: np.ndarray, mujoco_us: np.ndarray) -> float:
    """Median over the ticks of ``part / MuJoCo's step`` in the same tick; the ratio of the medians
    when the two do not pair up (a tick without the tracker: the safe mode)."""
    if part_us.shape == mujoco_us.shape:
        return float(np.median(part_us / mujoco_us))
    return float(np.median(part_us) / np.median(mujoco_us))


def speed_goals(robot: str, scenario: str, key: str, row: dict) -> dict:
    """The goals of :mod:`amlip_qp.experiments.bench_goals` that apply to the row ``key`` (``tracker/mode``) and
    their verdicts: ``{name: {"goal": number, "value": number, "met": bool}}`` for ``controller_steps``,
    ``tracker_steps`` (MuJoCo steps, medians) and ``realtime_factor`` (the robot's nominal walk only)."""
    tracker = tracker_base(key.split("/")[0], VARIANTS)
    goals = tick_goals(tracker)
    out: dict = {}
    if "controller" in goals:
        value = row["controller_per_loop_step"]
        out["controller_steps"] = {"goal": goals["controller"], "value": value, "met": value <= goals["controller"]}
    if "tracker" in goals:
        value = row["tracker_per_loop_step"]
        out["tracker_steps"] = {"goal": goals["tracker"], "value": value, "met": value <= goals["tracker"]}
    rt = realtime_goal(robot, scenario, tracker)
    if rt is not None:
        value = row["realtime_factor"]
        out["realtime_factor"] = {"goal": rt, "value": value, "met": value >= rt}
    return out


def tracker_for(scenario, name: str):
    """The tracker ``name`` for :func:`~amlip_qp.sim.scenarios.factory.build_simulation`: the name itself,
    or for a variant of :data:`VARIANTS` a new tracker with its options."""
    if name not in VARIANTS:
        return name
    base, options = VARIANTS[name]
    # The abstract base declares no constructor; the registered trackers take the robot and keywords.
    cls = cast("Callable[..., Tracker]", tracker_class(base))
    return cls(load(scenario.robot), **options)


def reference_realtime(tick_per_mujoco: float) -> float:
    """The real-time factor of a walk costing ``tick_per_mujoco`` MuJoCo steps of wall time per tick,
    on the machine state on which the reference's walk ran at :data:`REFERENCE_REALTIME_FACTOR`."""
    return REFERENCE_REALTIME_FACTOR * REFERENCE_TICK_PER_MUJOCO / tick_per_mujoco


#: ``--scenario robots``: each bundled robot's nominal walk.
EVERY_ROBOT = "robots"


def scenario_names(text: str) -> tuple[str, ...]:
    """The scenarios of ``--scenario``: a comma-separated list, where :data:`EVERY_ROBOT` stands for each
    bundled robot's nominal walk (its profile's ``[compare] nominal_scenario``), in name order.

    Raises:
        InputError: No scenario named, or an unknown one (checked before any walk).
    """
    names: list[str] = []
    for item in (t.strip() for t in text.split(",")):
        if not item:
            continue
        if item == EVERY_ROBOT:
            profiles = (get_profile(robot) for robot in bundled_names())
            names.extend(p.compare.nominal_scenario for p in profiles if p.compare is not None)
        else:
            names.append(item)
    if not names:
        raise InputError(f"--scenario: expected scenario names or {EVERY_ROBOT!r}, got {text!r}")
    for name in names:
        get_scenario(name)
    return tuple(dict.fromkeys(names))


def run_bench(args: argparse.Namespace) -> int:
    """``amlip-qp bench harness``: print the table per scenario (and write JSON: one scenario's report,
    or ``{"scenarios": [report, ...]}`` for several); exit 1 if the two log modes disagree on any walk."""
    from amlip_qp.output_paths import check_output_path, emit_report

    target = getattr(args, "json", None)
    check_output_path("--json", target)
    trackers = tuple(t.strip() for t in str(args.trackers).split(",") if t.strip())
    scenarios = scenario_names(str(args.scenario))
    reports = [run(scenario=s, duration_s=args.duration, repeats=args.repeats, trackers=trackers) for s in scenarios]
    text = "\n\n".join(format_report(r) for r in reports)
    emit_report(text, reports[0] if len(reports) == 1 else {"scenarios": reports}, target)
    return 0 if all(all(r["same_summary"].values()) for r in reports) else 1
