"""Walking scenarios: commands over time, pushes, durations, and the plant they run on.

A :class:`Scenario` is everything a run needs besides the robot and the
tracker. The named scenarios of :data:`SCENARIOS` are the acceptance
scenarios of the walking issues; the CLI, the examples, the comparison and
the tests all take them from here. Each ideal Cassie scenario also exists on
the hardware-like setting :data:`CLOSED_CHAIN_EKF` (name suffix ``-cc-ekf``),
and ``cassie-1mps-cc-ekf`` also under each model mismatch of
:data:`MISMATCHES`.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field, replace

from amlip_qp.alip.planner import Command
from amlip_qp.exceptions import InputError
from amlip_qp.profiles import PROFILES, CommandShaping, GaitSettings, RobotProfile, get_profile
from amlip_qp.sim.plant_modifiers import PlantModifiers
from amlip_qp.sim.run_types import PlantSetting, Push
from amlip_qp.sim.speed_profile import SpeedProfile


@dataclass(frozen=True)
class Scenario:
    """A walking experiment.

    Attributes:
        name: Identifier.
        robot: A bundled robot's name (:data:`amlip_qp.profiles.PROFILES`).
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
        if self.robot not in PROFILES:
            raise InputError(f"unknown robot {self.robot!r} for a scenario; known: {', '.join(PROFILES)}")
        if not (self.duration_s > 0 and math.isfinite(self.duration_s)):
            raise InputError(f"scenario duration must be a positive number of seconds, got {self.duration_s!r}")
        for name in ("vy_mps", "turn_rate_radps", "turn_start_s"):
            if not math.isfinite(getattr(self, name)):
                raise InputError(f"scenario {name} must be finite, got {getattr(self, name)!r}")

    @property
    def gait_settings(self) -> GaitSettings:
        """The gait used (the scenario's, or the robot's profile's)."""
        return self.gait or PROFILES[self.robot].gait

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


def _ramp(v_end: float, t_ramp: float, t0: float = 1.0) -> SpeedProfile:
    return SpeedProfile((0.0, t0, t0 + t_ramp), (0.0, 0.0, v_end))


#: The acceptance scenarios (issue "walking with the baseline tracker", section 5).
SCENARIOS: dict[str, Scenario] = {
    s.name: s
    for s in (
        Scenario("cassie-in-place", "cassie", 20.0, description="Cassie walks in place for 20 s"),
        Scenario("cassie-1mps", "cassie", 10.0, vx=_ramp(1.0, 2.0), description="Cassie walks at 1.0 m/s"),
        Scenario(
            "cassie-ramp-2.1",
            "cassie",
            15.0,
            vx=SpeedProfile((0.0, 10.0), (0.0, 2.1)),
            description="Cassie ramps from 0 to 2.1 m/s over 10 s and holds it",
        ),
        Scenario(
            "cassie-turn-90",
            "cassie",
            12.0,
            vx=_ramp(0.75, 1.5),
            turn_rate_radps=math.radians(18.0),
            turn_start_s=3.0,
            turn_angle_rad=math.radians(90.0),
            description="Cassie turns 90 degrees at 0.75 m/s",
        ),
        Scenario(
            "cassie-diagonal",
            "cassie",
            10.0,
            vx=_ramp(0.5, 1.5),
            vy_mps=0.3,
            description="Cassie walks diagonally, 0.5 m/s forward and 0.3 m/s sideways",
        ),
        Scenario(
            "cassie-push",
            "cassie",
            10.0,
            vx=_ramp(1.0, 2.0),
            pushes=(Push(6.0, (100.0, 0.0, 0.0), 0.2),),
            description="Cassie at 1 m/s takes a 100 N sagittal push for 0.2 s",
        ),
        Scenario(
            "cassie-2.5mps",
            "cassie",
            16.0,
            vx=SpeedProfile((0.0, 1.0, 13.0), (0.0, 0.0, 2.5)),
            gait=GaitSettings(step_time_s=0.25, com_height_m=0.80, clearance_m=0.10, step_width_m=0.25),
            description="Cassie ramps from 0 to 2.5 m/s over 12 s and holds it (shorter steps, T = 0.25 s, "
            "as the paper used a higher step frequency for fast walking)",
        ),
        Scenario("rabbit-0.5mps", "rabbit", 20.0, vx=_ramp(0.5, 2.0), description="Rabbit walks at 0.5 m/s"),
        Scenario("rabbit-1mps", "rabbit", 20.0, vx=_ramp(1.0, 3.0), description="Rabbit walks at 1.0 m/s"),
    )
}

#: The hardware-like setting of issue "a plant it was not built from": the closed-chain Cassie plant
#: (achilles and plantar rods closed by equality constraints), the robot's own sensors (IMU,
#: encoders, contact switches; no base state) and the contact-aided invariant EKF.
CLOSED_CHAIN_EKF = PlantSetting(plant="cassie-closed-chain", sensors="robot", estimator="ekf")

#: Model mismatches under which the QP tracker must still walk ``cassie-1mps-cc-ekf``: name suffix -> modifiers.
MISMATCHES: dict[str, PlantModifiers] = {
    "mass-0.8": PlantModifiers(mass_scale=0.8),
    "mass-1.2": PlantModifiers(mass_scale=1.2),
    "payload-5kg": PlantModifiers(payload_kg=5.0, payload_pos_m=(-0.10, 0.0, 0.0)),
    "friction-0.5": PlantModifiers(friction=0.5),
    "delay-1": PlantModifiers(actuator_delay_ticks=1),
}
_MISMATCH_TEXT = {
    "mass-0.8": "every plant body's mass and inertia x0.8",
    "mass-1.2": "every plant body's mass and inertia x1.2",
    "payload-5kg": "a 5 kg payload 10 cm behind the pelvis",
    "friction-0.5": "foot-floor friction 0.5",
    "delay-1": "a 1-tick (0.5 ms) actuator delay",
}


def _on_closed_chain(s: Scenario) -> Scenario:
    return s.with_(
        name=f"{s.name}-cc-ekf",
        setting=CLOSED_CHAIN_EKF,
        description=f"{s.description}; closed-chain plant, robot sensors, invariant EKF",
    )


SCENARIOS.update({c.name: c for c in [_on_closed_chain(s) for s in SCENARIOS.values() if s.robot == "cassie"]})
SCENARIOS.update(
    {
        f"cassie-1mps-cc-ekf-{key}": SCENARIOS["cassie-1mps-cc-ekf"].with_(
            name=f"cassie-1mps-cc-ekf-{key}",
            setting=replace(CLOSED_CHAIN_EKF, modifiers=mods),
            description=f"{SCENARIOS['cassie-1mps-cc-ekf'].description}; {_MISMATCH_TEXT[key]}",
        )
        for key, mods in MISMATCHES.items()
    }
)


def _terrain(
    name: str, terrain: str, vx_mps: float, duration_s: float, text: str, aware: bool = False, clearance_m=None
) -> Scenario:
    mode = "terrain-aware" if aware else "blind"
    return Scenario(
        name,
        "cassie",
        duration_s,
        vx=_ramp(vx_mps, max(1.0, vx_mps / 0.5)),  # no faster than Cassie's 0.5 m/s^2 command shaping
        setting=PlantSetting(terrain=terrain, terrain_aware=aware, clearance_m=clearance_m),
        description=f"Cassie walks {text} at {vx_mps:g} m/s ({mode})",
    )


def _slopes() -> list[Scenario]:
    out = []
    for deg in (10, 15, 22):
        for way, sign in (("up", 1), ("down", -1)):
            if deg == 22 and way == "down":
                continue  # the issue asks for the 22 degree slope up only
            for aware in (False, True):
                name = f"cassie-slope-{deg}-{way}" + ("-aware" if aware else "")
                out.append(_terrain(name, f"slope:{sign * deg}", 0.5, 15.0, f"{way} a {deg} degree slope", aware))
    return out


#: The terrain scenarios of issue #13 (section 3): slopes (both modes), stairs
#: (terrain-aware), rough ground and waves (blind). Slopes, stairs and waves
#: start 1 m ahead of the robot (:data:`amlip_qp.sim.terrain.START_X_M`).
TERRAIN_SCENARIOS: dict[str, Scenario] = {
    s.name: s
    for s in (
        *_slopes(),
        _terrain(
            "cassie-stairs-10cm",
            "stairs:0.1:0.3",
            0.4,
            14.0,
            "up 4 stairs of 10 cm rise and 30 cm run, across a 1 m landing and down 4 stairs",
            aware=True,
        ),
        _terrain("cassie-rough-4cm", "rough:0.04", 0.75, 20.0, "on rough ground of +-4 cm"),
        _terrain(
            "cassie-waves-30cm",
            "waves:0.3:4",
            0.75,
            15.0,
            "over 30 cm high waves of 4 m wavelength with 20 cm swing clearance",
            clearance_m=0.2,
        ),
    )
}
SCENARIOS.update(TERRAIN_SCENARIOS)


def ideal_scenarios() -> list[str]:
    """The names of the scenarios on each robot's own model with ideal sensors and the true base state."""
    return [name for name, s in SCENARIOS.items() if s.setting == PlantSetting()]


def get_scenario(name: str) -> Scenario:
    """The named scenario; :class:`InputError` listing the names otherwise."""
    try:
        return SCENARIOS[name]
    except KeyError:
        raise InputError(f"unknown scenario {name!r}; known: {', '.join(SCENARIOS)}") from None


def check_scenario(scenario: Scenario, profile: RobotProfile | None = None) -> None:
    """Refuse a scenario whose commands, duration or pushes are outside its robot's physical bounds.

    The bounds are the profile's :class:`~amlip_qp.profiles.CommandBounds`
    (``profile``: the registry's profile of ``scenario.robot`` by default).
    The CLI calls this before simulating; so may any caller that takes
    commands from people.

    A run must also last at least one control tick
    (:data:`amlip_qp.sim.factory.CONTROL_DT_S`, 0.5 ms), so that a too short
    one is refused here rather than once its closed loop is built.

    Raises:
        InputError: Naming the bound and the value, e.g. a forward speed
            outside ``CommandBounds.vx_mps``, a lateral command for a planar
            robot, a push that ends after the run, or a run shorter than a tick.
    """
    from amlip_qp.sim.factory import CONTROL_DT_S  # the closed loop's period (a heavy import, once)

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
