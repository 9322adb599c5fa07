"""A robot profile: every fact about one robot that is not in its MJCF file.

A :class:`RobotProfile` is read from one TOML file (:mod:`amlip_qp.profiles.reader`;
every key is documented in ``docs/NEW_ROBOT.md``). It says:

- the model (:class:`ModelSpec`): the MJCF file, left as it comes, and the
  edits made to it through ``MjSpec`` when it is loaded (a floor, a ``stand``
  keyframe, the timestep, a name for the free joint, position servos turned
  into torque motors);
- the joints' roles (``joint_roles``: hip yaw, knee, ankle pitch ... -> the
  file's joint names, with ``{side}`` for ``left``/``right``) and the feet
  (:class:`FootSpec`: the body, the contact point, the force points, the
  joints passive in stance);
- where the IMU sits (:class:`ImuMount`: its body, position and axes);
- the outputs the trackers follow (:mod:`amlip_qp.profiles.outputs`), and whether the robot is planar;
- the gait (:class:`GaitSettings`), the command bounds and shaping
  (:mod:`amlip_qp.profiles.commands`), each tracker's tuned configuration (a
  table turned into the tracker's own configuration type on demand,
  :meth:`RobotProfile.tracker_config`), the ``compare`` ranges and the plants
  ``--plant`` may name.

This module imports nothing but :mod:`amlip_qp.exceptions`, so every layer may
use it (``docs/ARCHITECTURE.md``).
"""

from __future__ import annotations

import importlib
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from amlip_qp.exceptions import InputError
from amlip_qp.profiles.commands import CommandBounds, CommandShaping, VerifiedEnvelope

#: Tracker name -> ``"module:function"`` that turns a profile's ``[trackers.NAME]`` table into that
#: tracker's configuration object (imported only when asked for, so this module stays light).
TRACKER_CONFIG_BUILDERS: dict[str, str] = {
    "qp": "amlip_qp.control.wbc.config:config_from_table",
    "pbc": "amlip_qp.control.pbc.gains:gains_from_table",
}

#: The joint roles a profile may name (per side). ``ankle_pitch`` is the joint the foot pitches
#: about (the one the ALIP contact point hangs on).
JOINT_ROLES: tuple[str, ...] = (
    "hip_yaw",
    "hip_roll",
    "hip_pitch",
    "knee",
    "ankle_pitch",
    "ankle_roll",
)

#: What the loader does with a position servo (an actuator with a position or velocity bias).
SERVO_POLICIES: tuple[str, ...] = ("refuse", "convert")


@dataclass(frozen=True)
class GaitSettings:
    """The fixed gait parameters of a robot (SI units).

    Attributes:
        step_time_s: Step duration ``T``, s.
        com_height_m: CoM height over the stance contact ``H``, m.
        clearance_m: Swing clearance ``z_cl``, m.
        step_width_m: Step width ``W`` for walking in place, m (0 for planar robots).
    """

    step_time_s: float
    com_height_m: float
    clearance_m: float
    step_width_m: float


@dataclass(frozen=True)
class CompareRanges:
    """What ``amlip-qp compare`` runs for a robot.

    Attributes:
        nominal_scenario: Name of the nominal scenario (``amlip_qp.sim.scenarios.scenarios``).
        ramp_end_mps: Speed the ramp test reaches, m/s.
        push_max_impulse_Ns: Upper end of the push bisection, N s.
        relative_cost: Relative wall-time cost of one simulated second (schedules the longest first).
        realtime_goal: Tracker name -> the real-time factor (simulated time over wall time, median)
            the nominal walk should reach with it in ``amlip-qp bench harness`` (none: no goal).
    """

    nominal_scenario: str
    ramp_end_mps: float
    push_max_impulse_Ns: float
    relative_cost: float = 1.0
    realtime_goal: Mapping[str, float] = field(default_factory=dict)


@dataclass(frozen=True)
class StandPose:
    """The ``stand`` keyframe a profile adds to its model (SI units).

    Attributes:
        base_pos_m: World position of the free joint's body, m.
        base_quat_wxyz: Its orientation, a unit quaternion (w, x, y, z).
        joints_rad: The file's joint name -> angle, rad (m for a slide joint); every other joint at 0.
    """

    base_pos_m: tuple[float, float, float]
    base_quat_wxyz: tuple[float, float, float, float] = (1.0, 0.0, 0.0, 0.0)
    joints_rad: Mapping[str, float] = field(default_factory=dict)


@dataclass(frozen=True)
class ModelSpec:
    """The MJCF file of a robot and the edits made to it when it is loaded.

    A profile with no edits (``edits_needed`` false) loads its file as it is.

    Attributes:
        path: The MJCF file (resolved; relative paths in the profile are relative to the profile file).
        free_joint_name: Name given to the free joint when the file leaves it unnamed (``None``: no rename).
        timestep_s: The simulation timestep set on the model, s (``None``: the file's).
        add_floor: Add a ground plane when the model has no plane geom.
        stand: A ``stand`` keyframe to add (replacing the file's, if any), or ``None``.
        servos: ``"refuse"``: a position servo is an error; ``"convert"``: it becomes a torque
            motor whose control range is the joint's force range (gain 1, no bias).
    """

    path: Path
    free_joint_name: str | None = None
    timestep_s: float | None = None
    add_floor: bool = False
    stand: StandPose | None = None
    servos: str = "refuse"

    @property
    def edits_needed(self) -> bool:
        """Whether loading changes the file: a name, a timestep, a floor or a keyframe (the servo
        policy changes only a file that has servos, and is applied by the same edit)."""
        return (
            self.free_joint_name is not None
            or self.timestep_s is not None
            or self.add_floor
            or self.stand is not None
            or self.servos == "convert"
        )


#: How many force points a foot may have: a point foot, a line contact (toe, heel), a sole (four corners).
FORCE_POINT_COUNTS = (0, 1, 2, 4)

#: The names of a foot's force sites after ``{side}-``, by their number: two are toe then heel; four are the
#: sole's corners (toe left, toe right, heel left, heel right; left and right in the foot's own frame).
FORCE_SITE_SUFFIXES: dict[int, tuple[str, ...]] = {
    2: ("toe", "heel"),
    4: ("toe-left", "toe-right", "heel-left", "heel-right"),
}


def sole_rectangle_corners(
    x_front: float, x_back: float, half_width: float, z: float
) -> tuple[tuple[float, float, float], ...]:
    """The four corners of a rectangular sole, foot frame, m: toe left, toe right, heel left, heel right."""
    return ((x_front, half_width, z), (x_front, -half_width, z), (x_back, half_width, z), (x_back, -half_width, z))


def sole_line_points(points: tuple[tuple[float, float, float], ...]) -> tuple[tuple[float, float, float], ...]:
    """The ends of a foot's sole line (toe, heel), m, from its 2 or 4 force points: the points themselves,
    or the midpoints of the toe pair and of the heel pair; ``()`` for fewer points."""
    if len(points) == 4:
        (a, b, c, d) = points
        return (
            tuple(0.5 * (u + w) for u, w in zip(a, b)),  # type: ignore[return-value]
            tuple(0.5 * (u + w) for u, w in zip(c, d)),
        )
    return tuple(points) if len(points) == 2 else ()


@dataclass(frozen=True)
class FootSpec:
    """Where each foot touches the ground.

    Either the model already has the library's sites (``{side}-contact``;
    ``{side}-toe`` / ``{side}-heel`` for a two-point foot; for a four-point
    foot its corners ``{side}-toe-left``, ``{side}-toe-right``,
    ``{side}-heel-left``, ``{side}-heel-right`` and its sole line's ends
    ``{side}-toe`` / ``{side}-heel``), or ``body`` names the foot body and the
    loader adds them at the points given.

    Attributes:
        body: The foot body's name, with ``{side}`` (``None``: the model has the sites).
        contact_point_m: The ALIP contact point in the foot body's frame, m.
        force_points_m: Where the contact forces act, in the foot body's frame, m: one point (a
            point foot, the contact point itself), two (toe then heel, a line contact) or four
            (toe left, toe right, heel left, heel right: a sole; the profile's ``sole_rectangle_m``
            gives a rectangle's corners).
        passive_in_stance: Joint roles that carry no torque while the foot is in stance.
    """

    body: str | None = None
    contact_point_m: tuple[float, float, float] | None = None
    force_points_m: tuple[tuple[float, float, float], ...] = ()
    passive_in_stance: tuple[str, ...] = ()


#: How far from 1 the norm of an IMU mounting's ``quat_wxyz`` may be (the profile reader then normalises it).
UNIT_QUATERNION_TOL = 1e-6


@dataclass(frozen=True)
class ImuMount:
    """Where the IMU sits: a body of the model, a position and an orientation in that body's frame.

    Attributes:
        body: The body carrying the IMU; ``None``: the base body.
        pos_m: The IMU's position in ``body``'s frame, m.
        quat_wxyz: The IMU's axes in ``body``'s frame, a unit quaternion ``w x y z`` (the rotation
            from IMU axes to body axes); ``(1, 0, 0, 0)``: the body's own axes.
    """

    body: str | None = None
    pos_m: tuple[float, float, float] = (0.0, 0.0, 0.0)
    quat_wxyz: tuple[float, float, float, float] = (1.0, 0.0, 0.0, 0.0)


@dataclass(frozen=True)
class RobotProfile:
    """Everything about a robot that is not in its MJCF file (see the module doc).

    Attributes:
        name: The robot's name.
        source: The profile file.
        model: The MJCF file and its load-time edits.
        outputs: The outputs the trackers follow, in order (:mod:`amlip_qp.profiles.outputs`).
        planar: True for a robot that walks in the sagittal plane only.
        gait: Default gait.
        bounds: Command bounds (physical: outside them a command is refused).
        verified: The commands the acceptance verifies (outside them, inside ``bounds``,
            a command runs with an :class:`~amlip_qp.exceptions.UnverifiedCommandWarning`).
        shaping: Command shaping (rate limits).
        trackers: Tracker name -> its configuration table (:meth:`tracker_config` builds it).
        compare: ``amlip-qp compare`` ranges.
        plants: Plant name -> MJCF file: the plants ``--plant`` may name
            (:func:`amlip_qp.sim.world.plant_loader.load_plant`); the robot's own model is one of them, under
            the robot's name.
        imu: Where the IMU sits (:class:`ImuMount`; default: the base body's origin, its axes).
        joint_roles: Role (:data:`JOINT_ROLES`) -> the file's joint name, with ``{side}``.
        feet: The feet.
        description: One line for people.
        scenarios: Scenario name (without the robot's prefix) -> its table: the robot's named
            scenarios (:mod:`amlip_qp.sim.scenarios.scenario_tables` builds them, and checks their keys).
        settings: Setting name -> its table: plants, sensors and estimators the robot's
            scenarios are copied onto (each copy named ``SCENARIO-SETTING``).
        mismatches: Name -> table of plant modifiers: copies of one scenario under model mismatch.
        unsupported: Tracker name -> why it cannot run on this robot (a structural reason, said
            in one line when the tracker is asked for; never a silent fallback).
        estimator: The invariant EKF's settings that differ from their defaults (field name ->
            number, :class:`~amlip_qp.estimation.invariant_ekf.EkfNoise`).
    """

    name: str
    source: Path
    model: ModelSpec
    outputs: tuple[str, ...]
    planar: bool
    gait: GaitSettings
    bounds: CommandBounds
    shaping: CommandShaping
    verified: VerifiedEnvelope = field(default_factory=VerifiedEnvelope)
    trackers: Mapping[str, Mapping[str, Any]] = field(default_factory=dict)
    compare: CompareRanges | None = None
    plants: Mapping[str, Path] = field(default_factory=dict)
    imu: ImuMount = field(default_factory=ImuMount)
    joint_roles: Mapping[str, str] = field(default_factory=dict)
    feet: FootSpec = field(default_factory=FootSpec)
    description: str = ""
    scenarios: Mapping[str, Mapping[str, Any]] = field(default_factory=dict)
    settings: Mapping[str, Mapping[str, Any]] = field(default_factory=dict)
    mismatches: Mapping[str, Any] = field(default_factory=dict)
    estimator: Mapping[str, Any] = field(default_factory=dict)
    unsupported: Mapping[str, str] = field(default_factory=dict)
    _built: dict[str, Any] = field(default_factory=dict, init=False, repr=False, compare=False)

    @property
    def tracker_configs(self) -> tuple[str, ...]:
        """The trackers this profile has a configuration for."""
        return tuple(self.trackers)

    def joint_name(self, role: str, side: str) -> str | None:
        """The file's name of the ``side`` joint with ``role``, or ``None`` if the profile names none."""
        template = self.joint_roles.get(role)
        return None if template is None else template.format(side=side)

    def check_supported(self, tracker: str) -> None:
        """Raise :class:`InputError` with the profile's reason if ``tracker`` cannot run on this robot."""
        if tracker in self.unsupported:
            raise InputError(f"the {tracker} tracker does not run on {self.name}: {self.unsupported[tracker]}")

    def tracker_config(self, tracker: str) -> Any:
        """The tuned configuration of ``tracker`` for this robot, built from its table.

        Raises:
            InputError: No configuration for that tracker, the profile says why it does not run on
                this robot (``[unsupported]``), or its table is invalid (the message names the key
                and the profile file).
        """
        self.check_supported(tracker)
        if tracker not in self.trackers:
            known = ", ".join(sorted(self.trackers)) or "none"
            raise InputError(f"robot {self.name!r} has no {tracker!r} tracker configuration; known: {known}")
        if tracker not in self._built:  # built once: every caller shares one object
            module_name, attr = TRACKER_CONFIG_BUILDERS[tracker].split(":")
            build = getattr(importlib.import_module(module_name), attr)
            try:
                self._built[tracker] = build(self.trackers[tracker])
            except InputError as exc:
                raise InputError(f"{self.source}: [trackers.{tracker}]: {exc}") from None
        return self._built[tracker]
