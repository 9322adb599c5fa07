"""The closed-loop conformance checks: one control tick at the stand pose per tracker, a walk in place.

Part of ``amlip-qp check-robot`` (:mod:`amlip_qp.experiments.conformance`, which runs
them after the model checks). The controller is built as
:func:`amlip_qp.sim.scenarios.factory.build_simulation` builds it; a tracker the
profile has no ``[trackers.NAME]`` table for is skipped, not failed.
"""

from __future__ import annotations

import numpy as np

from amlip_qp.control import registry
from amlip_qp.control.tracker import Tracker, TrackingTarget
from amlip_qp.control.walking.controller import WalkingController
from amlip_qp.exceptions import InputError
from amlip_qp.experiments.conformance import SKIP, CheckResult, result
from amlip_qp.messages import Command, Measurement, TrackerResult
from amlip_qp.robots.kinematics import RobotKinematics
from amlip_qp.robots.robot import Robot
from amlip_qp.sim.loop.run_types import CONTROL_DT_S
from amlip_qp.sim.scenarios import factory
from amlip_qp.sim.scenarios.scenarios import Scenario, check_scenario

#: The trackers whose single tick is checked, in order.
TICK_TRACKERS: tuple[str, ...] = ("qp", "pbc")
#: The tracker of the walk in place.
WALK_TRACKER = "qp"
#: Simulated time of the walk in place, s.
WALK_DURATION_S = 3.0
#: How far a torque may lie outside its limit and still count as inside, N m (N for a slide joint):
#: ten times the QP tracker's ProxQP tolerance (1e-3), which bounds its torque-limit rows' residual.
TORQUE_LIMIT_TOL_NM = 1e-2


def walk_name(duration_s: float) -> str:
    """The name of the walk check of ``duration_s``."""
    return f"walk in place for {duration_s:g} s ({WALK_TRACKER.upper()})"


#: The walk check's name.
WALK_NAME = walk_name(WALK_DURATION_S)


def tick_name(tracker: str) -> str:
    """The name of the single-tick check of ``tracker``."""
    return f"one {tracker.upper()} tick at stand"


def _skip(name: str, tracker: str) -> CheckResult:
    return CheckResult(name, SKIP, None, "", f"the profile has no {tracker} configuration")


class _Recorder(Tracker):
    """Runs a tracker and keeps its last result (the torques before the controller saturates them)."""

    def __init__(self, inner: Tracker):
        self.inner = inner
        self.name = inner.name
        self.last: TrackerResult | None = None

    def compute(self, kin: RobotKinematics, target: TrackingTarget) -> TrackerResult:
        self.last = self.inner.compute(kin, target)
        return self.last

    def reset(self) -> None:
        self.inner.reset()


def stand_tick(robot: Robot, tracker: str) -> TrackerResult:
    """The tracker's result of the controller's first tick at the stand pose, at rest, both feet in contact.

    The controller is built as :func:`amlip_qp.sim.scenarios.factory.build_simulation` builds it (the
    profile's command shaping, the control period :data:`~amlip_qp.sim.loop.run_types.CONTROL_DT_S`),
    commanded to walk in place with the profile's gait.

    Raises:
        InputError: The robot has no profile, or its stand pose is not finite.
    """
    profile = robot.profile
    if profile is None:
        raise InputError(f"{robot.name}: a stand tick needs the robot's profile (its gait and tracker tables)")
    recorder = _Recorder(registry.make_tracker(tracker, robot))
    controller = WalkingController(
        robot,
        recorder,
        dt_s=CONTROL_DT_S,
        command_shaping=profile.shaping,
    )
    gait = profile.gait
    command = Command(
        step_time_s=gait.step_time_s,
        com_height_m=gait.com_height_m,
        clearance_m=gait.clearance_m,
        step_width_m=gait.step_width_m,
    )
    contact = dict.fromkeys(robot.foot_sides, True)
    controller.step(Measurement(0.0, robot.q_stand.copy(), np.zeros(robot.nv), contact), command)
    if recorder.last is None:  # the controller's safe mode: it runs no tracker on a non-finite state
        raise InputError(f"{robot.name}: the stand pose is not finite; check [model.stand]")
    return recorder.last


def check_tick(robot: Robot, tracker: str) -> CheckResult:
    """One control tick at the stand pose with ``tracker``: solved (no fallback, no relaxed QP), finite
    torques inside the torque limits; the measured number is the largest torque magnitude, N m."""
    name = tick_name(tracker)
    if robot.profile is None or tracker not in robot.profile.trackers:
        return _skip(name, tracker)
    res = stand_tick(robot, tracker)
    tau = np.asarray(res.tau_Nm, dtype=float)
    names = robot.actuated.names
    if not res.ok:
        return result(name, False, None, "N m", f"the tracker fell back: {res.fallback}")
    if not np.all(np.isfinite(tau)):
        bad = [names[i] for i in np.flatnonzero(~np.isfinite(tau))]
        return result(name, False, None, "N m", f"non-finite torques at {', '.join(bad)}")
    lim = robot.actuated.torque_limit_Nm
    margin = np.minimum(tau - lim[:, 0], lim[:, 1] - tau)
    i_max, i_tight = int(np.argmax(np.abs(tau))), int(np.argmin(margin))
    tau_max = float(abs(tau[i_max]))
    relaxed = bool(res.info.get("relaxed", 0.0))
    tight = float(margin[i_tight])
    if tight < -TORQUE_LIMIT_TOL_NM:
        lo, hi = lim[i_tight]
        why = " (the QP is infeasible with the torque limits; solved without them)" if relaxed else ""
        return result(
            name,
            False,
            tau_max,
            "N m",
            f"{names[i_tight]} needs {tau[i_tight]:.4g} N m, outside its limits [{lo:.4g}, {hi:.4g}] N m{why}",
        )
    if relaxed:
        return result(name, False, tau_max, "N m", "the QP is infeasible with the torque limits")
    inside = f"inside the limits (margin {max(tight, 0.0):.3g} N m at {names[i_tight]})"
    if not np.isfinite(tight):
        inside = "no torque limits"
    return result(name, True, tau_max, "N m", f"solved, |tau| max {tau_max:.3g} N m ({names[i_max]}), {inside}")


def check_walk(robot_arg: str, robot: Robot, duration_s: float = WALK_DURATION_S) -> CheckResult:
    """A walk in place of ``duration_s`` with the QP tracker on the robot's own model, ideal sensors:
    it must not fall; the measured number is the CoM's horizontal drift from start to end, m."""
    name = walk_name(duration_s)
    if robot.profile is None or WALK_TRACKER not in robot.profile.trackers:
        return _skip(name, WALK_TRACKER)
    scenario = Scenario("check-robot-in-place", robot_arg, duration_s, description="walk in place")
    check_scenario(scenario)
    run = factory.run_scenario(scenario, WALK_TRACKER, log="summary")
    com = run.log["com"]
    drift = float(np.hypot(*(com[-1, :2] - com[0, :2])))
    steps = f"{len(run.steps)} step{'s' if len(run.steps) != 1 else ''}"
    if run.fallback_ticks:
        steps += f", {run.fallback_ticks} fallback ticks"
    if run.fell:
        return result(name, False, drift, "m", f"fell at {run.fall_time_s:.2f} s ({steps})")
    return result(name, True, drift, "m", f"no fall, CoM drift {drift:.3f} m ({steps})")
