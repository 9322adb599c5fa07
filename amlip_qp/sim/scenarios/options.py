"""The options of one walk, typed and checked: what ``amlip-qp walk`` takes and a sweep cell sets.

:class:`WalkOptions` holds every option of a walk that shapes its outcome
(the scenario, the command, the plant, the tracker, the seed...; not its
outputs). :meth:`WalkOptions.from_mapping` checks each value with
:mod:`amlip_qp.option_values` (the checks the command line's value types are
made of) and :func:`amlip_qp.sim.scenarios.from_options.scenario_from_options`
makes the options a :class:`~amlip_qp.sim.scenarios.scenarios.Scenario`. The
command line (its parsed namespace, :meth:`WalkOptions.from_namespace`) and a
sweep cell (its parameter table) both come through here. This module is light
(no NumPy): the command line takes its name lists from it.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field, fields
from typing import Any

import amlip_qp.option_values as V
from amlip_qp.exceptions import InputError

#: Trackers (``amlip_qp.control.registry.TRACKER_MODULES``, held equal by the tests).
TRACKERS: tuple[str, ...] = ("pbc", "qp")
#: Foot-placement planners (``amlip_qp.control.walking.planners.PLANNERS``, held equal by the tests).
PLANNERS: tuple[str, ...] = ("one-step", "mpc")
#: Sensor models (``amlip_qp.sim.sensing.sensors.SENSOR_MODELS``, held equal by the tests).
SENSORS: tuple[str, ...] = ("ideal", "robot")
#: Base estimators (``amlip_qp.sim.scenarios.factory.ESTIMATORS``, held equal by the tests).
ESTIMATORS: tuple[str, ...] = ("truth", "ekf")

#: Largest seed: 2**32 - 1, a 32-bit seed like the terrain's ``rough:AMPLITUDE_M:SEED`` (a sweep
#: cell derives a 31-bit one). A longer number is a typo.
MAX_SEED = 2**32 - 1

#: Largest ``accel_limit``, m/s^2: 100 (about 10 g). A speed command rate-limited at 100 m/s^2
#: reaches every speed of the robots' bounds (at most 4.14 m/s) within 42 ms, a sixth of a step: that is
#: no shaping at all, which ``no_command_shaping`` says.
MAX_ACCEL_LIMIT_MPS2 = 100.0


def _option(default: Any, check: V.Check) -> Any:
    return field(default=default, metadata={"check": check})


def _pushes(value: Any) -> tuple[V.PushSpec, ...]:
    """One push (its text) or a sequence of pushes (each its text or its tuple)."""
    items = [value] if isinstance(value, str) else value
    if not isinstance(items, (list, tuple)):
        raise InputError(f"expected pushes T:FX,FY,FZ:DUR (s:N,N,N:s), got {value!r}")
    return tuple(V.push_spec(p) for p in items)


@dataclass(frozen=True)
class WalkOptions:
    """The options of one walk (``None``: the scenario's, else the default given). SI units but the turn rate.

    Attributes:
        robot: A bundled robot's name or a robot profile's path, resolved (default: the
            scenario's, else :data:`amlip_qp.profiles.DEFAULT_ROBOT`).
        tracker: The tracker, one of :data:`TRACKERS`.
        planner: The foot-placement planner, one of :data:`PLANNERS`.
        scenario: A named scenario to start from (the other options override it); ``None``: a steady walk.
        vx: Constant forward speed, m/s.
        speed_profile: Piecewise-linear forward speed ``"T:V,..."`` (s:m/s); not with ``vx``.
        vy: Lateral speed, m/s (left positive).
        turn_rate: Turn rate, deg/s (left positive; the scenario takes rad/s).
        duration: Simulated time, s (default: the scenario's, else
            :data:`amlip_qp.sim.scenarios.from_options.DEFAULT_WALK_DURATION_S`).
        push: Pushes on the base added to the scenario's, each ``(t_s, (fx_N, fy_N, fz_N), duration_s)``.
        accel_limit: Rate limit of the forward and lateral speed commands, m/s^2, in
            ``(0, MAX_ACCEL_LIMIT_MPS2]``; not with ``no_command_shaping``.
        no_command_shaping: Give the planner the raw command.
        seed: Seed of the sensor noise, ``0`` to :data:`MAX_SEED`.
        noise: Gaussian noise on the ideal sensors.
        plant: A plant name of the robot or an MJCF file.
        sensors: The sensor model, one of :data:`SENSORS`.
        estimator: The base estimator, one of :data:`ESTIMATORS`.
        terrain: A terrain spec (``amlip_qp.sim.world.terrain``: ``flat``, ``slope:DEG``, ...).
        terrain_aware: Give the controller the terrain's height function.
        clearance: Swing-foot clearance at mid-step, m (>= 0).
        plant_mass_scale: Scale of the plant's masses and inertias.
        payload: A payload ``"KG[@X,Y,Z]"`` (kg, m in the base frame) welded to the base.
        plant_spring_scale: Scale of the plant's joint and tendon springs.
        friction: Sliding friction coefficient of the foot-floor contacts.
        limb_collisions: The limbs collide with each other (the legs cannot pass through each other).
        actuator_delay: Delay of the actuator commands, control ticks (0.5 ms each).

    The plant modifiers' and the terrain's bounds are checked where they are
    applied (``amlip_qp.sim.world``), the command's against the robot's bounds by
    :func:`~amlip_qp.sim.scenarios.scenarios.check_scenario`.
    """

    robot: str | None = _option(None, V.robot_name_or_path)
    tracker: str = _option("qp", V.one_of(TRACKERS))
    planner: str = _option("one-step", V.one_of(PLANNERS))
    scenario: str | None = _option(None, V.text)
    vx: float | None = _option(None, V.finite_float)
    speed_profile: str | None = _option(None, V.text)
    vy: float | None = _option(None, V.finite_float)
    turn_rate: float | None = _option(None, V.finite_float)
    duration: float | None = _option(None, V.positive_float)
    push: tuple[V.PushSpec, ...] = _option((), _pushes)
    accel_limit: float | None = _option(None, V.float_in(0.0, MAX_ACCEL_LIMIT_MPS2, "m/s^2"))
    no_command_shaping: bool = _option(False, V.flag)
    seed: int = _option(0, V.int_in(0, MAX_SEED, "seed"))
    noise: bool = _option(False, V.flag)
    plant: str | None = _option(None, V.text)
    sensors: str | None = _option(None, V.one_of(SENSORS))
    estimator: str | None = _option(None, V.one_of(ESTIMATORS))
    terrain: str | None = _option(None, V.text)
    terrain_aware: bool | None = _option(None, V.flag)
    clearance: float | None = _option(None, V.non_negative_float)
    plant_mass_scale: float | None = _option(None, V.number)
    payload: str | None = _option(None, V.text)
    plant_spring_scale: float | None = _option(None, V.number)
    friction: float | None = _option(None, V.number)
    limb_collisions: bool = _option(False, V.flag)
    actuator_delay: int | None = _option(None, V.whole_number)

    @classmethod
    def names(cls) -> tuple[str, ...]:
        """Every option's name, in the order of ``amlip-qp walk --help``."""
        return tuple(f.name for f in fields(cls))

    @classmethod
    def defaults(cls) -> dict[str, Any]:
        """Every option's default, by name."""
        return {f.name: f.default for f in fields(cls)}

    @classmethod
    def value_check(cls, name: str) -> V.Check:
        """The check of one value of the option ``name`` (the command line's value type of its option)."""
        return {f.name: f.metadata["check"] for f in fields(cls)}[name]

    @classmethod
    def check(cls, name: str, value: Any) -> Any:
        """``value`` of the option ``name`` in its type (``None`` only for an option whose default is ``None``).

        Raises:
            InputError: An unknown option, or a bad value (one line naming the option).
        """
        known = {f.name: f for f in fields(cls)}
        if name not in known:
            raise InputError(f"unknown walk option {name!r}; known: {', '.join(known)}")
        f = known[name]
        if value is None and f.default is None:
            return None
        try:
            return f.metadata["check"](value)
        except InputError as exc:
            raise InputError(f"{name}: {exc}") from None

    @classmethod
    def from_mapping(cls, values: Mapping[str, Any]) -> WalkOptions:
        """The options of ``values`` (option name -> value, text or typed), the others at their defaults.

        Raises:
            InputError: An unknown option, a bad value, ``vx`` with ``speed_profile``, or
                ``accel_limit`` with ``no_command_shaping`` (one line naming the options).
        """
        checked = {name: cls.check(name, value) for name, value in values.items()}
        options = cls(**checked)
        if options.vx is not None and options.speed_profile is not None:
            raise InputError("vx (--vx) and speed_profile (--speed-profile) both set the forward speed: give one")
        if options.accel_limit is not None and options.no_command_shaping:
            raise InputError(
                "accel_limit (--accel-limit) and no_command_shaping (--no-command-shaping) contradict: give one"
            )
        return options

    @classmethod
    def from_namespace(cls, args: Any, names: Iterable[str] | None = None) -> WalkOptions:
        """The options of a parsed command line: the attributes of ``args`` named ``names`` (default: every
        option ``args`` has; a command without some, e.g. ``view`` without ``--planner``, keeps their defaults).

        Raises:
            InputError: As :meth:`from_mapping`.
        """
        wanted = cls.names() if names is None else tuple(names)
        return cls.from_mapping({n: getattr(args, n) for n in wanted if hasattr(args, n)})


#: The options of the plant setting (:func:`~amlip_qp.sim.scenarios.from_options.setting_from_options`),
#: ``noise`` included (it needs the ideal sensors).
SETTING_OPTIONS: tuple[str, ...] = (
    "noise",
    "plant",
    "sensors",
    "estimator",
    "terrain",
    "terrain_aware",
    "clearance",
    "plant_mass_scale",
    "payload",
    "plant_spring_scale",
    "friction",
    "limb_collisions",
    "actuator_delay",
)
