"""Walking scenarios: commands over time, pushes, durations, and the plant they run on.

A :class:`Scenario` is everything a run needs besides the robot and the
tracker. The named scenarios (:data:`amlip_qp.sim.scenarios.named.SCENARIOS`)
are data of the robots' profiles (``[scenarios]`` tables,
:mod:`amlip_qp.sim.scenarios.scenario_tables`): the acceptance scenarios; the
CLI, the examples, the comparison and the tests all take them from there. A
profile's ``[settings]`` copy its scenarios onto other plants, sensors and
estimators (Cassie's ``-cc-ekf``: the closed-chain plant, the robot's
sensors, the invariant EKF), and its ``[mismatches]`` copy one scenario
under model mismatch.
"""

from __future__ import annotations

import contextlib
import math
import warnings
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field, replace

from amlip_qp.exceptions import InputError, UnknownRobotError, UnverifiedCommandWarning
from amlip_qp.messages import Command
from amlip_qp.profiles import CommandShaping, GaitSettings, RobotProfile, get_profile
from amlip_qp.sim.loop.run_types import CONTROL_DT_S, PlantSetting, Push
from amlip_qp.sim.scenarios.speed_profile import SpeedProfile


@dataclass(frozen=True)
class Scenario:
    """A walking experiment.

    Attributes:
        name: Identifier.
        robot: A bundled robot's name (:data:`amlip_qp.profiles.PROFILES`) or a robot profile file's path.
        duration_s: Simulated time, s.
        vx: Forward speed profile (heading frame), m/s.
        vy_mps: Lateral speed (heading frame), m/s.
        turn_rate_radps: Turn rate, rad/s.
        turn_start_s: Time the turn starts, s.
        turn_angle_rad: Total turn; the rate drops to 0 once reached (``inf`` = keep turning).
        pushes: Forces on the base.
        gait: Gait parameters (``None``: the robot's profile's).
        shaping: Rate limits of the velocity command before the planner
            (``None``: the robot's profile's; :data:`~amlip_qp.profiles.NO_SHAPING`: none).
        setting: The plant, sensors, base estimator and model mismatch
            (default: the robot's own model, ideal sensors, the true base state).
        description: One line for people.
    """

    name: str
    robot: str
    duration_s: float
    vx: SpeedProfile = field(default_factory=lambda: SpeedProfile.constant(0.0))
    vy_mps: float = 0.0
    turn_rate_radps: float = 0.0
    turn_start_s: float = 0.0
    turn_angle_rad: float = math.inf
    pushes: tuple[Push, ...] = ()
    gait: GaitSettings | None = None
    shaping: CommandShaping | None = None
    setting: PlantSetting = field(default_factory=PlantSetting)
    description: str = ""

    def __post_init__(self):
        try:
            get_profile(self.robot)  # a bundled robot's name or a profile file's path
        except UnknownRobotError as exc:
            raise InputError(f"scenario {self.name!r}: {exc}") from None
        if not (self.duration_s > 0 and math.isfinite(self.duration_s)):
            raise InputError(f"scenario duration must be a positive number of seconds, got {self.duration_s!r}")
        for name in ("vy_mps", "turn_rate_radps", "turn_start_s"):
            if not math.isfinite(getattr(self, name)):
                raise InputError(f"scenario {name} must be finite, got {getattr(self, name)!r}")

    @property
    def gait_settings(self) -> GaitSettings:
        """The gait used (the scenario's, or the robot's profile's)."""
        return self.gait or get_profile(self.robot).gait

    def turn_rate_at(self, t_s: float) -> float:
        """Commanded turn rate at ``t_s``, rad/s."""
        if self.turn_rate_radps == 0.0 or t_s < self.turn_start_s:
            return 0.0
        if math.isinf(self.turn_angle_rad):
            return self.turn_rate_radps
        return self.turn_rate_radps if t_s < self._turn_end_s() else 0.0

    def command(self, t_s: float) -> Command:
        """The :class:`~amlip_qp.alip.planner.Command` at time ``t_s``."""
        return self._command(self.vx(t_s), self.turn_rate_at(t_s))

    def _command(self, vx_mps: float, turn_rate_radps: float) -> Command:
        return Command(**self._command_fields(), vx_mps=vx_mps, turn_rate_radps=turn_rate_radps)

    def _command_fields(self) -> dict[str, float]:
        """The :class:`Command` fields that do not change during a run."""
        g = self.gait_settings
        clearance = self.setting.clearance_m
        return {
            "step_time_s": g.step_time_s,
            "com_height_m": g.com_height_m,
            "clearance_m": g.clearance_m if clearance is None else clearance,
            "vy_mps": self.vy_mps,
            "step_width_m": g.step_width_m,
        }

    def command_function(self) -> Callable[[float], Command]:
        """:meth:`command` for one run: the same commands, each :class:`Command` made once while its values hold.

        The first is made by the constructor, the next ones by its
        :meth:`~amlip_qp.alip.planner.Command.with_speeds` (only the speeds change). Without a
        turn the turn rate is 0.0 throughout (:meth:`turn_rate_at`), and only the speed is compared.
        """
        last: list = [None, None]
        vx_at, turn_rate_at, copysign, fields = self.vx, self.turn_rate_at, math.copysign, self._command_fields()

        def make(vx: float, turn: float) -> Command:
            held = last[1]
            return Command(**fields, vx_mps=vx, turn_rate_radps=turn) if held is None else held.with_speeds(vx, turn)

        if self.turn_rate_radps == 0.0:
            # from the last knot on the speed is held: once last[1] is its command, it is every such time's
            t_held, held = self.vx.times_s[-1], [False]

            def speed_command(t_s: float) -> Command:
                if t_s >= t_held and held[0]:
                    return last[1]
                vx = vx_at(t_s)
                key = (vx, copysign(1.0, vx))  # a zero's sign counts too
                if key != last[0]:
                    last[1] = make(vx, 0.0)
                    last[0] = key
                held[0] = t_s >= t_held
                return last[1]

            return speed_command

        def command(t_s: float) -> Command:
            vx, turn = vx_at(t_s), turn_rate_at(t_s)
            key = (vx, turn, copysign(1.0, vx), copysign(1.0, turn))  # a zero's sign counts too
            if key != last[0]:
                last[1] = make(vx, turn)
                last[0] = key
            return last[1]

        return command

    def _turn_end_s(self) -> float:
        """When a turn of a finite angle ends, s (as :meth:`turn_rate_at`)."""
        return self.turn_start_s + abs(self.turn_angle_rad / self.turn_rate_radps)

    def with_(self, **changes) -> Scenario:
        """A copy with some fields changed."""
        return replace(self, **changes)


@contextlib.contextmanager
def held_warnings() -> Iterator[list[warnings.WarningMessage]]:
    """Hold the warnings raised inside (an :class:`UnverifiedCommandWarning` of :func:`check_scenario`)
    until :func:`release_warnings`: a command that turns out bad input later is refused in one line,
    without the warning before it."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", UnverifiedCommandWarning)
        yield caught


def release_warnings(caught: list[warnings.WarningMessage]) -> None:
    """Warn, in order, the warnings :func:`held_warnings` held (once every input check has passed)."""
    for w in caught:
        warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)


def check_scenario(scenario: Scenario, profile: RobotProfile | None = None) -> None:
    """Refuse a scenario whose commands, duration or pushes are outside its robot's physical bounds.

    The bounds are the profile's :class:`~amlip_qp.profiles.CommandBounds`
    (``profile``: the registry's profile of ``scenario.robot`` by default).
    The CLI calls this before simulating; so may any caller that takes
    commands from people.

    A run must also last at least one control tick
    (:data:`amlip_qp.sim.loop.run_types.CONTROL_DT_S`, 0.5 ms), so that a too short
    one is refused here rather than once its closed loop is built.

    A command inside the bounds but outside what the robot's acceptance
    verifies (its profile's :class:`~amlip_qp.profiles.VerifiedEnvelope`,
    ``[verified]``) passes, with one
    :class:`~amlip_qp.exceptions.UnverifiedCommandWarning` naming it.

    Raises:
        InputError: Naming the bound and the value, e.g. a forward speed
            outside ``CommandBounds.vx_mps``, a lateral command for a planar
            robot, a push that ends after the run, or a run shorter than a tick.
    """
    if not scenario.duration_s >= CONTROL_DT_S:
        raise InputError(
            f"duration {scenario.duration_s!r} s is shorter than one control tick ({CONTROL_DT_S} s); "
            "give --duration of at least that"
        )
    profile = profile or get_profile(scenario.robot)
    if profile.planar:
        lateral = [f"lateral speed ({scenario.vy_mps:g} m/s)"] if scenario.vy_mps != 0.0 else []
        if scenario.turn_rate_radps != 0.0:
            lateral.append(f"turn rate ({math.degrees(scenario.turn_rate_radps):g} deg/s)")
        lateral += [f"push FY ({p.force_N[1]:g} N at {p.t_s:g} s)" for p in scenario.pushes if p.force_N[1] != 0.0]
        if lateral:
            raise InputError(f"{profile.name} is planar: {', '.join(lateral)} must be 0")
    clearance, gait = scenario.setting.clearance_m, scenario.gait_settings
    if clearance is not None and not clearance < gait.com_height_m:
        raise InputError(
            f"--clearance {clearance:g} m must be below the CoM height {gait.com_height_m:g} m of {profile.name}'s gait"
        )
    profile.bounds.check(
        profile.name,
        vx_mps=scenario.vx.speeds_mps,
        vy_mps=scenario.vy_mps,
        turn_rate_radps=scenario.turn_rate_radps,
        duration_s=scenario.duration_s,
        pushes=[(p.t_s, p.force_N, p.duration_s) for p in scenario.pushes],
    )
    unverified = profile.verified.unverified(
        profile.name, vx_mps=scenario.vx.speeds_mps, vy_mps=scenario.vy_mps, turn_rate_radps=scenario.turn_rate_radps
    )
    if unverified is not None:
        warnings.warn(unverified, UnverifiedCommandWarning, stacklevel=2)
