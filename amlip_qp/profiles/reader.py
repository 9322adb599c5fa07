"""Read a robot profile file (TOML) into a :class:`~amlip_qp.profiles.profile.RobotProfile`.

Every key is checked as it is read: an unknown key, a value of the wrong
type, a number out of its range or a missing file gives one
:class:`~amlip_qp.exceptions.ProfileError` naming the file and the key
(``docs/NEW_ROBOT.md`` documents every key). Whether the MJCF file has the
joints, bodies and sites the profile names is checked when the robot is
loaded (:func:`amlip_qp.robots.load_robot`), and each tracker's table when
its configuration is built (:meth:`RobotProfile.tracker_config`).
"""

from __future__ import annotations

import functools
import math
import sys
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

from amlip_qp.exceptions import InputError, ProfileError
from amlip_qp.profiles.commands import CommandBounds, CommandShaping, VerifiedEnvelope, check_gait_schedule
from amlip_qp.profiles.outputs import output_primitives
from amlip_qp.profiles.profile import (
    FORCE_POINT_COUNTS,
    JOINT_ROLES,
    SERVO_POLICIES,
    TRACKER_CONFIG_BUILDERS,
    UNIT_QUATERNION_TOL,
    CompareRanges,
    FootSpec,
    GaitSettings,
    ImuMount,
    ModelSpec,
    RobotProfile,
    StandPose,
    sole_rectangle_corners,
)
from amlip_qp.profiles.toml_table import Table, check_number

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - Python 3.10
    import tomli as tomllib


def read_imu_table(source: Path, where: str, data: Any) -> ImuMount:
    """An :class:`ImuMount` from a table of the ``[imu]`` keys (a profile's ``[imu]``, or the
    ``imu`` of one of its ``[settings]``); ``where`` names it in the errors.

    Raises:
        ProfileError: Not a table, an unknown key, or a bad value (naming ``source`` and the key).
    """
    return _imu(Table(source, where, data))


def _imu(t: Table | None) -> ImuMount:
    """The ``[imu]`` table: ``body`` (default the base body), ``pos_m`` (that body's frame), ``quat_wxyz``."""
    if t is None:
        return ImuMount()
    body = t.string("body", None)
    pos = t.vector("pos_m", 3, (0.0, 0.0, 0.0), unit="m")
    quat = t.vector("quat_wxyz", 4, (1.0, 0.0, 0.0, 0.0), unit="w x y z")
    norm = math.sqrt(sum(c * c for c in quat))
    if abs(norm - 1.0) > UNIT_QUATERNION_TOL:
        within = f"norm within {UNIT_QUATERNION_TOL:g} of 1"
        t.fail(f"must be a unit quaternion w x y z ({within}), got norm {norm:.9g}", "quat_wxyz")
    t.done()
    return ImuMount(body=body, pos_m=pos, quat_wxyz=tuple(c / norm for c in quat) if norm != 1.0 else quat)


def _path(t: Table, key: str, base: Path, default: Any = ...) -> Any:
    text = t.string(key, default)
    if text is default and default is not ...:
        return text
    path = (base / Path(text).expanduser()).resolve()
    if not path.is_file():
        t.fail(f"file not found: {path}", key)
    return path


def _side_template(t: Table, key: str, default: Any = ...) -> Any:
    text = t.string(key, default)
    if text is default and default is not ...:
        return text
    if "{side}" not in text or text.replace("{side}", "").count("{") or text.replace("{side}", "").count("}"):
        t.fail(f"must contain '{{side}}' once (for left / right), got {text!r}", key)
    return text


def _model(t: Table, base: Path) -> ModelSpec:
    stand = None
    s = t.table("stand", required=False)
    if s is not None:
        joints = s.table("joints", required=False)
        angles = {}
        if joints is not None:
            for name in list(joints.data):
                angles[name] = joints.number(name, unit="rad")
            joints.done()
        quat = s.vector("base_quat_wxyz", 4, (1.0, 0.0, 0.0, 0.0))
        norm = math.sqrt(sum(x * x for x in quat))
        if not abs(norm - 1.0) < 1e-6:
            s.fail(f"must be a unit quaternion (norm {norm:.6g})", "base_quat_wxyz")
        stand = StandPose(base_pos_m=s.vector("base_pos_m", 3, unit="m"), base_quat_wxyz=quat, joints_rad=angles)
        s.done()
    spec = ModelSpec(
        path=_path(t, "file", base),
        free_joint_name=t.string("free_joint_name", None),
        # Above 10 ms a 2 kHz controller would run several ticks per physics step; below 10 us
        # the run is needlessly slow.
        timestep_s=t.number("timestep_s", None, low=1e-5, high=1e-2, unit="s"),
        add_floor=t.boolean("add_floor", False),
        stand=stand,
        servos=t.string("servos", "refuse", choices=SERVO_POLICIES),
    )
    t.done()
    return spec


def _outputs(t: Table, planar: bool) -> tuple[str, ...]:
    names = t.raw("outputs")
    if not isinstance(names, list) or not all(isinstance(n, str) for n in names):
        t.fail(f"must be a list of output names, got {names!r}", "outputs")
    try:
        output_primitives(names, planar)
    except InputError as exc:
        t.fail(str(exc), "outputs")
    return tuple(names)


def _feet(t: Table | None) -> FootSpec:
    if t is None:
        return FootSpec()
    body = _side_template(t, "body", None)
    contact = t.vector("contact_point_m", 3, None, unit="m")
    raw_points = t.raw("force_points_m", [])
    if not isinstance(raw_points, list) or len(raw_points) not in FORCE_POINT_COUNTS:
        t.fail(
            "must be a list of 1 point, 2 points (toe, heel) or 4 points (toe left, toe right, heel left, "
            f"heel right), each 3 numbers in m, got {raw_points!r}",
            "force_points_m",
        )
    points: list[tuple[float, float, float]] = []
    for p in raw_points:
        if not isinstance(p, list) or len(p) != 3:
            t.fail(f"each point must be 3 numbers (m), got {p!r}", "force_points_m")
        x, y, z = (check_number(t, "force_points_m", v, -math.inf, math.inf, "m", True) for v in p)
        points.append((x, y, z))
    rectangle = t.table("sole_rectangle_m", required=False)
    if rectangle is not None:
        if points:
            t.fail("give either 'force_points_m' or 'sole_rectangle_m', not both", "sole_rectangle_m")
        points = list(_sole_rectangle(rectangle))
    elif len(points) == 4:
        _check_four_points(t, points)
    passive = t.raw("passive_in_stance", [])
    if not isinstance(passive, list) or any(r not in JOINT_ROLES for r in passive):
        t.fail(f"must be a list of joint roles ({', '.join(JOINT_ROLES)}), got {passive!r}", "passive_in_stance")
    if body is not None and contact is None:
        t.fail("is required with 'body' (the ALIP contact point in the foot body's frame)", "contact_point_m")
    if body is None and (contact is not None or points):
        t.fail(
            "is required with 'contact_point_m' / 'force_points_m' / 'sole_rectangle_m' (the foot body they are in)",
            "body",
        )
    t.done()
    return FootSpec(body=body, contact_point_m=contact, force_points_m=tuple(points), passive_in_stance=tuple(passive))


def _sole_rectangle(t: Table) -> tuple[tuple[float, float, float], ...]:
    """The 4 corners of ``[feet] sole_rectangle_m`` (toe left, toe right, heel left, heel right), m."""
    x_front, x_back = t.number("x_front", unit="m"), t.number("x_back", unit="m")
    half_width = t.number("half_width", low=0.0, unit="m")
    z = t.number("z", unit="m")
    if not x_front > x_back:
        t.fail(f"must be ahead of x_back ({x_back!r} m), got {x_front!r}", "x_front")
    if not half_width > 0.0:
        t.fail(f"must be positive (m), got {half_width!r}", "half_width")
    t.done()
    return sole_rectangle_corners(x_front, x_back, half_width, z)


def _check_four_points(t: Table, points: list[tuple[float, float, float]]) -> None:
    """Four force points are toe left, toe right, heel left, heel right (foot frame: x forward, y left);
    the heel pair may coincide (a triangular sole), the toe pair may not."""
    (x0, y0, _), (x1, y1, _), (x2, y2, _), (x3, y3, _) = points
    if not (x0 + x1 > x2 + x3 and y0 > y1 and y2 >= y3):
        t.fail(
            "four points go toe left, toe right, heel left, heel right (the toe pair ahead of the heel pair, "
            f"each pair's left point first, y larger; only the heel pair may coincide), got {points!r}",
            "force_points_m",
        )


def _roles(t: Table | None) -> dict[str, str]:
    if t is None:
        return {}
    roles = {}
    for key in list(t.data):
        if key not in JOINT_ROLES:
            t.fail(f"unknown joint role {key!r} (known: {', '.join(JOINT_ROLES)})")
        roles[key] = _side_template(t, key)
    t.done()
    return roles


def _dataclass_table(t: Table, make: Callable[..., Any], fields: Mapping[str, tuple[Any, ...]]) -> Any:
    """Read the numbers ``fields`` (key -> (default, low, high, unit[, finite])) and call ``make``."""
    kwargs = {}
    for key, (default, low, high, unit, *finite) in fields.items():
        kwargs[key] = t.number(key, default, low=low, high=high, unit=unit, finite=finite[0] if finite else True)
    t.done()
    return make(**kwargs)


def _realtime_goal(t: Table | None) -> dict[str, float]:
    """``[compare] realtime_goal``: tracker name -> the nominal walk's real-time factor goal."""
    if t is None:
        return {}
    goals = {}
    for tracker in list(t.data):
        if tracker not in TRACKER_CONFIG_BUILDERS:
            t.fail(f"unknown tracker {tracker!r} (known: {', '.join(TRACKER_CONFIG_BUILDERS)})", tracker)
        goals[tracker] = t.number(tracker, low=1e-3, high=1e3)
    t.done()
    return goals


def _bounds(t: Table) -> CommandBounds:
    vx = t.vector("vx_mps", 2, unit="m/s")
    kwargs = {
        "vy_max_mps": t.number("vy_max_mps", low=0.0, unit="m/s"),
        "turn_rate_max_radps": math.radians(t.number("turn_rate_max_degps", low=0.0, unit="deg/s")),
        "duration_max_s": t.number("duration_max_s", 600.0, low=0.0, unit="s"),
        "push_impulse_max_Ns": t.number("push_impulse_max_Ns", 100.0, low=0.0, unit="N s"),
        "push_force_max_N": t.number("push_force_max_N", 3000.0, low=0.0, unit="N"),
        "step_time_min_s": t.number("step_time_min_s", None, low=1e-3, unit="s"),
    }
    t.done()
    try:
        return CommandBounds(vx_mps=vx, **kwargs)
    except Exception as exc:
        t.fail(str(exc))
        raise


def _verified(t: Table | None, bounds: CommandBounds) -> VerifiedEnvelope:
    if t is None:
        return VerifiedEnvelope()
    vx = t.vector("vx_mps", 2, unit="m/s")
    vy = t.number("vy_max_mps", 0.0, low=0.0, unit="m/s")
    turn = math.radians(t.number("turn_rate_max_degps", 0.0, low=0.0, unit="deg/s"))
    t.done()
    try:
        envelope = VerifiedEnvelope(vx_mps=vx, vy_max_mps=vy, turn_rate_max_radps=turn)
    except Exception as exc:
        t.fail(str(exc))
        raise
    if not envelope.within(bounds):
        t.fail("the verified envelope must lie inside [bounds] (a verified command is physically possible)")
    return envelope


def _trackers(t: Table | None) -> dict[str, dict[str, Any]]:
    if t is None:
        return {}
    out = {}
    for name in list(t.data):
        if name not in TRACKER_CONFIG_BUILDERS:
            t.fail(f"unknown tracker {name!r} (known: {', '.join(TRACKER_CONFIG_BUILDERS)})")
        table = t.table(name)
        assert table is not None
        out[name] = table.data
    t.done()
    return out


def read_profile(path: str | Path) -> RobotProfile:
    """Read and check the profile file ``path`` (TOML).

    Raises:
        ProfileError: The file is missing, is not TOML, or a key is unknown, of the wrong type,
            out of range or names a file that does not exist (the message names the key).
    """
    source = Path(path).expanduser().resolve()
    try:
        with open(source, "rb") as f:
            data = tomllib.load(f)
    except FileNotFoundError:
        raise ProfileError(f"robot profile not found: {source}") from None
    except OSError as exc:
        raise ProfileError(f"{source}: cannot read the robot profile: {exc.strerror or exc}") from None
    except tomllib.TOMLDecodeError as exc:
        raise ProfileError(f"{source}: not a valid TOML file: {exc}") from None
    base = source.parent
    top = Table(source, "", data)
    name = top.string("name")
    description = top.string("description", "")
    planar = top.boolean("planar")
    outputs = _outputs(top, planar)
    model_t = top.table("model")
    assert model_t is not None
    model = _model(model_t, base)
    gait_t = top.table("gait")
    assert gait_t is not None
    gait = _dataclass_table(
        gait_t,
        GaitSettings,
        {
            "step_time_s": (..., 0.05, 2.0, "s"),
            "com_height_m": (..., 0.05, 5.0, "m"),
            "clearance_m": (..., 0.0, 1.0, "m"),
            "step_width_m": (..., 0.0, 2.0, "m"),
        },
    )
    bounds_t = top.table("bounds")
    assert bounds_t is not None
    bounds = _bounds(bounds_t)
    verified = _verified(top.table("verified", required=False), bounds)
    shaping_t = top.table("shaping")
    assert shaping_t is not None
    rows = shaping_t.rows("gait_scale_by_speed", 4, (), unit="m/s, dimensionless")
    try:
        check_gait_schedule(rows)
    except InputError as exc:
        shaping_t.fail(str(exc).split(": ", 1)[1], "gait_scale_by_speed")
    shaping = _dataclass_table(
        shaping_t,
        functools.partial(CommandShaping, gait_scale_by_speed=rows),
        {
            "vx_accel_mps2": (..., 1e-9, math.inf, "m/s^2", False),
            "vy_accel_mps2": (..., 1e-9, math.inf, "m/s^2", False),
            "turn_accel_radps2": (..., 1e-9, math.inf, "rad/s^2", False),
            "max_step_length_m": (math.inf, 1e-3, math.inf, "m", False),
        },
    )
    compare_t = top.table("compare", required=False)
    compare = None
    if compare_t is not None:
        compare = CompareRanges(
            nominal_scenario=compare_t.string("nominal_scenario"),
            ramp_end_mps=compare_t.number("ramp_end_mps", low=0.0, unit="m/s"),
            push_max_impulse_Ns=compare_t.number("push_max_impulse_Ns", low=0.0, unit="N s"),
            relative_cost=compare_t.number("relative_cost", 1.0, low=1e-3, high=1e3),
            realtime_goal=_realtime_goal(compare_t.table("realtime_goal", required=False)),
        )
        compare_t.done()
    plants_t = top.table("plants", required=False)
    plants = {name: model.path}
    if plants_t is not None:
        for plant in list(plants_t.data):
            plants[plant] = _path(plants_t, plant, base)
        plants_t.done()
    unsupported_t = top.table("unsupported", required=False)
    unsupported = {}
    if unsupported_t is not None:
        for tracker in list(unsupported_t.data):
            if tracker not in TRACKER_CONFIG_BUILDERS:
                unsupported_t.fail(f"unknown tracker {tracker!r} (known: {', '.join(TRACKER_CONFIG_BUILDERS)})")
            unsupported[tracker] = unsupported_t.string(tracker)
        unsupported_t.done()
    imu = _imu(top.table("imu", required=False))
    raw = {}
    # scenarios, settings, mismatches: checked key by key by amlip_qp.sim.scenarios.scenario_tables;
    # estimator: by amlip_qp.estimation.invariant_ekf.noise_from_table
    for key in ("scenarios", "settings", "mismatches", "estimator"):
        t = top.table(key, required=False)
        raw[key] = {} if t is None else t.data
    profile = RobotProfile(
        name=name,
        source=source,
        model=model,
        outputs=outputs,
        planar=planar,
        gait=gait,
        bounds=bounds,
        verified=verified,
        shaping=shaping,
        trackers=_trackers(top.table("trackers", required=False)),
        compare=compare,
        plants=plants,
        imu=imu,
        joint_roles=_roles(top.table("roles", required=False)),
        feet=_feet(top.table("feet", required=False)),
        description=description,
        scenarios=raw["scenarios"],
        settings=raw["settings"],
        mismatches=raw["mismatches"],
        estimator=raw["estimator"],
        unsupported=unsupported,
    )
    top.done()
    if planar != (gait.step_width_m == 0.0):
        top.fail("a planar robot has gait.step_width_m = 0, and only a planar one", "planar")
    return profile
