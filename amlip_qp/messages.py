"""The messages of the closed loop: what its parts hand each other every control tick.

Below every part that exchanges them (the plant and its sensors, the
estimators, the planner, the trackers, the walking controller), so that data
flows one way:

- :class:`Measurement` (with its :class:`ImuReading`): what the sensors report,
  into the walking controller;
- :class:`Command` (what the controller asks for), :class:`StateEstimate`
  (the controller's estimate) and, off flat ground, :class:`TerrainPrediction`
  (the ground heights and pitches the controller expects) go into
  :meth:`Planner.update <amlip_qp.alip.planner.Planner.update>`;
  :class:`PlannerOutput` comes out;
- :class:`TrackerResult`: a tracker's torques for one tick.

The planner's messages are frozen, keyword-only dataclasses in SI units,
validated on creation (bad values raise :class:`~amlip_qp.exceptions.InputError`).
The terrain is its own message, not part of the state estimate: it comes from
another source (the footholds of :mod:`amlip_qp.alip.footholds` when blind, a
height function when terrain-aware), and its default, all zeros, is flat
ground with today's numbers bit for bit.

The IMU frame of an :class:`ImuReading` is rigidly attached to the body the
robot's profile names (:attr:`~amlip_qp.robots.robot.Robot.imu_mount`: a body,
a position and axes in its frame; by default the base body's origin and axes).
The EKF takes the reading turned into that of an IMU fixed to the base with
the base's axes (:mod:`~amlip_qp.estimation.imu_to_base`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, fields, replace

import numpy as np

from amlip_qp.exceptions import InputError

_F64 = np.dtype(np.float64)
_VECTOR3 = (3,)


@dataclass(frozen=True, kw_only=True, slots=True)
class Command:
    """What the walking controller asks for. All fields keyword-only, SI units.

    Attributes:
        step_time_s: step duration ``T``, s (> 0).
        com_height_m: desired CoM height over the stance contact ``H``, m (> 0).
        clearance_m: swing-foot clearance ``z_cl`` at mid-step, m (0 <= z_cl < H).
        vx_mps: forward CoM velocity in the heading frame, m/s (mean over a
            step unless the planner uses ``speed_reference="end_of_step"``).
        vy_mps: lateral (left positive) CoM velocity in the heading frame, m/s.
        turn_rate_radps: heading rate, rad/s (positive turns left); the
            planner integrates it over time (module doc, step 2).
        step_width_m: lateral distance between the feet when walking in place, m (>= 0).
    """

    step_time_s: float
    com_height_m: float
    clearance_m: float
    vx_mps: float = 0.0
    vy_mps: float = 0.0
    turn_rate_radps: float = 0.0
    step_width_m: float = 0.0

    def __post_init__(self):
        for name in (
            "step_time_s",
            "com_height_m",
            "clearance_m",
            "vx_mps",
            "vy_mps",
            "turn_rate_radps",
            "step_width_m",
        ):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, float, np.integer, np.floating)) or not math.isfinite(v):
                raise InputError(f"Command.{name} must be a finite number, got {v!r}")
        if not self.step_time_s > 0.0:
            raise InputError(f"Command.step_time_s (T) must be > 0 s, got {self.step_time_s!r}")
        if not self.com_height_m > 0.0:
            raise InputError(f"Command.com_height_m (H) must be > 0 m, got {self.com_height_m!r}")
        if not self.step_width_m >= 0.0:
            raise InputError(f"Command.step_width_m must be >= 0 m, got {self.step_width_m!r}")
        if not 0.0 <= self.clearance_m < self.com_height_m:
            raise InputError(
                f"Command.clearance_m (z_cl) must satisfy 0 <= z_cl < H = {self.com_height_m!r} m, "
                f"got {self.clearance_m!r}"
            )

    def with_speeds(self, vx_mps: float, turn_rate_radps: float) -> Command:
        """``dataclasses.replace(self, vx_mps=vx_mps, turn_rate_radps=turn_rate_radps)`` of a Command, cheaper (tested).

        Only the two new values are checked (the others were when ``self`` was made, and
        neither takes part in the checks between fields), with the constructor's InputError:
        a run's commands while the speed ramps.
        """
        if (
            type(vx_mps) is not float
            or type(turn_rate_radps) is not float
            or not math.isfinite(vx_mps + turn_rate_radps)
        ):
            # anything else: the constructor's checks (and errors) through replace (a finite sum: both finite)
            return replace(self, vx_mps=vx_mps, turn_rate_radps=turn_rate_radps)
        return self._with_motion(vx_mps, self.vy_mps, turn_rate_radps)

    def with_velocity(self, vx_mps: float, vy_mps: float) -> Command:
        """``dataclasses.replace(self, vx_mps=vx_mps, vy_mps=vy_mps)``, cheaper (tested; the speed-corrected
        command). Only the two new values are checked, as in :meth:`with_speeds` (InputError)."""
        if type(vx_mps) is not float or type(vy_mps) is not float or not math.isfinite(vx_mps + vy_mps):
            return replace(self, vx_mps=vx_mps, vy_mps=vy_mps)  # the constructor's checks and errors
        return self._with_motion(vx_mps, vy_mps, self.turn_rate_radps)

    def _with_motion(self, vx_mps: float, vy_mps: float, turn_rate_radps: float) -> Command:
        """This command with the three motion fields replaced, unchecked (the callers check them)."""
        new = object.__new__(Command)
        put_T, put_H, put_cl, put_vx, put_vy, put_turn, put_w = _COMMAND_SETTERS  # the frozen fields' own setters
        put_T(new, self.step_time_s)
        put_H(new, self.com_height_m)
        put_cl(new, self.clearance_m)
        put_vx(new, vx_mps)
        put_vy(new, vy_mps)
        put_turn(new, turn_rate_radps)
        put_w(new, self.step_width_m)
        return new

    def with_step_time(self, step_time_s: float) -> Command:
        """This command with the step duration ``step_time_s`` (s, > 0), cheaper than ``dataclasses.replace``
        (tested): the step-timing MPC's planned duration, every tick.

        Raises:
            InputError: ``step_time_s`` is not a finite number > 0.
        """
        if type(step_time_s) is not float or not 0.0 < step_time_s < math.inf:
            return replace(self, step_time_s=step_time_s)  # the constructor's checks and errors
        new = object.__new__(Command)
        for setter, name in zip(_COMMAND_SETTERS, _COMMAND_FIELDS):
            setter(new, step_time_s if name == "step_time_s" else getattr(self, name))
        return new


#: The slot setters of :class:`Command`'s fields, in field order (``object.__setattr__`` without its lookup).
_COMMAND_SETTERS = tuple(getattr(Command, f.name).__set__ for f in fields(Command))
_COMMAND_FIELDS = tuple(f.name for f in fields(Command))


@dataclass(frozen=True, kw_only=True, slots=True)
class StateEstimate:
    """The controller's estimate at one tick. All fields keyword-only, SI units, world axes.

    Attributes:
        stance: ``"left"`` or ``"right"``, the leg in stance.
        p_st_m: (3,) CoM minus stance contact, m.
        L_Nms: (3,) angular momentum about the stance contact, kg m^2/s.
        v_z_mps: CoM vertical velocity, m/s; used as the prediction of ``v_z`` at
            touchdown in the momentum-transfer correction.
        t_in_step_s: time since the current step started, s (>= 0; may exceed ``T``
            after a late touchdown, then the phase is held at 1).
        com_m: (3,) CoM position, m.

    Arrays are converted to float ``numpy`` arrays; NaN/inf, wrong shapes,
    unknown stance sides and negative times raise InputError.
    """

    stance: str
    p_st_m: np.ndarray
    L_Nms: np.ndarray
    v_z_mps: float
    t_in_step_s: float
    com_m: np.ndarray

    def __post_init__(self):
        if self.stance not in ("left", "right"):
            raise InputError(f"StateEstimate.stance must be 'left' or 'right', got {self.stance!r}")
        # Built every control tick: a fast path for three float64 3-vectors,
        # plain-float arithmetic, no numpy reductions.
        p, L, c = self.p_st_m, self.L_Nms, self.com_m
        if (
            type(p) is np.ndarray
            and type(L) is np.ndarray
            and type(c) is np.ndarray
            and p.dtype is _F64
            and L.dtype is _F64
            and c.dtype is _F64
            and p.shape == L.shape == c.shape == _VECTOR3
        ):
            p0, p1, p2 = p.tolist()
            L0, L1, L2 = L.tolist()
            c0, c1, c2 = c.tolist()
            total = p0 + p1 + p2 + (L0 + L1 + L2) + (c0 + c1 + c2)
        else:
            total = 0.0
            for name in ("p_st_m", "L_Nms", "com_m"):
                a = getattr(self, name)
                if not (isinstance(a, np.ndarray) and a.dtype is _F64):
                    try:
                        a = np.asarray(a, dtype=float)
                    except (TypeError, ValueError) as exc:
                        raise InputError(f"StateEstimate.{name} must be 3 numbers, got {a!r}") from exc
                    object.__setattr__(self, name, a)
                if a.shape != _VECTOR3:
                    raise InputError(f"StateEstimate.{name} must have shape (3,), got {a.shape}")
                x0, x1, x2 = a.tolist()
                total += x0 + x1 + x2
        # One cheap finiteness test: NaN and inf propagate through a sum.
        try:
            total = float(np.float64(total) + self.v_z_mps + self.t_in_step_s)
        except (TypeError, ValueError) as exc:
            raise InputError(
                f"StateEstimate.v_z_mps and t_in_step_s must be numbers, got {self.v_z_mps!r} and {self.t_in_step_s!r}"
            ) from exc
        if not math.isfinite(total):
            bad = [
                n
                for n in ("p_st_m", "L_Nms", "com_m", "v_z_mps", "t_in_step_s")
                if not np.all(np.isfinite(np.asarray(getattr(self, n), dtype=float)))
            ]
            raise InputError(
                f"StateEstimate has NaN or inf in {bad or 'a value too large to add'}; check the estimator"
            )
        if self.t_in_step_s < 0.0:
            raise InputError(f"StateEstimate.t_in_step_s must be >= 0 s, got {self.t_in_step_s!r}")


@dataclass(frozen=True, kw_only=True, slots=True)
class TerrainPrediction:
    """The ground the planner should plan for at one tick (docs/ALIP_SLOPES.md). SI units.

    Heights are world z differences from the current stance contact; pitches
    are the ground's rotation about the heading frame's y axis (the
    convention of the torso and toe pitch outputs: positive = ground
    descending ahead, so an uphill slope of ``a`` rad has pitch ``-a``).
    All default to 0: flat ground, and bit for bit the numbers of a planner
    called without a terrain.

    Attributes:
        dz_next_m: height of the next contact (where the swing foot will land)
            minus the stance contact, m; the placement law's momentum transfer.
        dz_sw_m: ground height at the swing target minus the stance contact, m;
            the end of the swing foot's height reference. Normally equal to
            ``dz_next_m``.
        dz_sw0_m: ground height where the swing foot lifted off (the previous
            stance contact) minus the stance contact, m; the start of the swing
            foot's path and of the CoM height blend (``H + dz_sw0_m`` to ``H``).
        slope_pitch_rad: ground pitch along the heading at the swing target, rad;
            the swing toe pitch reference ends there (the blade lands flat).
        slope_pitch0_rad: ground pitch along the heading where the swing foot
            lifted off, rad; the toe pitch reference starts there.

    Non-finite values and pitches outside ``(-pi/2, pi/2)`` raise InputError;
    the heights are checked against ``H`` and the clearance by the planner.
    """

    dz_next_m: float = 0.0
    dz_sw_m: float = 0.0
    dz_sw0_m: float = 0.0
    slope_pitch_rad: float = 0.0
    slope_pitch0_rad: float = 0.0

    def __post_init__(self):
        for name in ("dz_next_m", "dz_sw_m", "dz_sw0_m", "slope_pitch_rad", "slope_pitch0_rad"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, float, np.integer, np.floating)) or not math.isfinite(v):
                raise InputError(f"TerrainPrediction.{name} must be a finite number, got {v!r}")
            object.__setattr__(self, name, float(v))
        for name in ("slope_pitch_rad", "slope_pitch0_rad"):
            if not abs(getattr(self, name)) < 0.5 * math.pi:
                raise InputError(
                    f"TerrainPrediction.{name} must be within (-pi/2, pi/2) rad, got {getattr(self, name)!r}; "
                    "pass the ground's pitch in radians"
                )


@dataclass(frozen=True, kw_only=True, slots=True)
class PlannerOutput:
    """The planner's answer at one tick (SI units).

    Attributes:
        s: phase in [0, 1] (clipped: held at 1 after a late touchdown).
        t_remaining_s: predictor horizon ``max(T - t_in_step, 0)``, s.
        L_hat_Nms: (2,) predicted ``(L_x, L_y)`` at the end of the step, world axes, kg m^2/s.
        p_hat_m: (2,) predicted ``p_st(T-)`` (x, y), world axes, m.
        L_des_Nms: (2,) desired ``(L_x, L_y)`` at the end of the next step, world axes, kg m^2/s.
        p_sw_des_world_m: (2,) desired CoM minus swing contact at touchdown, world axes, m.
        p_sw_des_heading_m: (2,) the same in the current heading frame ``D_k``, m
            (the end targets of ``com_x_over_swing`` / ``com_y_over_swing``).
        swing_target_world_m: (3,) where the swing contact should land, world, m:
            ``x, y = r_st + p_hat - p_sw_des`` (= predicted CoM at ``T-`` minus
            ``p_sw_des``, with ``r_st = com - p_st`` the stance contact), ``z`` = the
            stance contact's height plus :attr:`TerrainPrediction.dz_sw_m`.
        h_d, dh_d, ddh_d: reference outputs and their first and second time
            derivatives, in the robot's output order
            (:attr:`Planner.output_names <amlip_qp.alip.planner.Planner.output_names>`).
        heading_rad: heading ``D_k`` of the current step, rad.
        heading_next_rad: heading ``D_{k+1}`` of the next step, rad.
        turn_rad: ``D_{k+1} - D_k``, rad (split between the hip yaws).
        v_z_used_mps: the ``v_z`` given to the foot-placement law after clamping, m/s.
    """

    s: float
    t_remaining_s: float
    L_hat_Nms: np.ndarray
    p_hat_m: np.ndarray
    L_des_Nms: np.ndarray
    p_sw_des_world_m: np.ndarray
    p_sw_des_heading_m: np.ndarray
    swing_target_world_m: np.ndarray
    h_d: np.ndarray
    dh_d: np.ndarray
    ddh_d: np.ndarray
    heading_rad: float
    heading_next_rad: float
    turn_rad: float
    v_z_used_mps: float


@dataclass(frozen=True)
class ImuReading:
    """What the IMU reports at one tick (SI units).

    Attributes:
        quat_xyzw: Orientation of the IMU frame in the world, as the IMU's own
            filter reports it (unit quaternion, x y z w), shape (4,).
        gyro_radps: Angular velocity of the IMU frame, IMU axes, rad/s, shape (3,).
        accel_mps2: Specific force ``a - g`` in IMU axes, m/s^2, shape (3,)
            (reads ``+9.81`` on z at rest, level).
    """

    quat_xyzw: np.ndarray
    gyro_radps: np.ndarray
    accel_mps2: np.ndarray

    @classmethod
    def of_packed(cls, packed: np.ndarray, start: int = 0) -> ImuReading:
        """``ImuReading(p[:4], p[4:7], p[7:10])`` of ``p = packed[start:]``: the reading of 10 floats
        (quaternion x y z w, gyro, accelerometer) of one array, holding views of it.

        The same object as the constructor's (tested), made without its three frozen
        ``object.__setattr__`` calls: the harness's per-tick reading.
        """
        reading = object.__new__(cls)
        fields = reading.__dict__
        fields["quat_xyzw"] = packed[start : start + 4]
        fields["gyro_radps"] = packed[start + 4 : start + 7]
        fields["accel_mps2"] = packed[start + 7 : start + 10]
        return reading


@dataclass
class Measurement:
    """What the sensors report at one tick.

    Attributes:
        t_s: Time, s.
        q: Configuration, Pinocchio convention (free-flyer quaternion xyzw).
        v: Velocity, Pinocchio convention (free-flyer twist in the base frame).
        foot_contact: Side -> contact switch (True when the foot carries load);
            an empty dict means "no contact sensing": touchdown is then
            detected from the swing foot's height.
        imu: The IMU reading (:class:`~amlip_qp.messages.ImuReading`),
            or ``None`` without an IMU.
        base_known: False when the base part (``q[:7]``, ``v[:6]``) is not a
            measurement (robot sensors): a base-state estimator must fill it
            (:mod:`amlip_qp.estimation.base_estimator`).
    """

    t_s: float
    q: np.ndarray
    v: np.ndarray
    foot_contact: dict[str, bool] = field(default_factory=dict)
    imu: ImuReading | None = None
    base_known: bool = True


@dataclass
class TrackerResult:
    """A tracker's output for one tick.

    Attributes:
        tau_Nm: Joint-side torques of the actuated joints (robot's actuator
            order), before saturation by the controller, N m. Never NaN.
        ok: ``False`` when the tracker fell back (solver failure, NaN...).
        fallback: Why it fell back, or ``None``.
        info: Diagnostics (solve time, iterations, contact forces, tracking
            error...), numbers only.
        outputs: The output map ``h_0`` the tracker evaluated at this tick's state, for the
            target's stance and heading: ``(y, J, Jdot_v)``, ``y`` the outputs (m or rad, the
            robot's output order), shape (n_outputs,), ``J = dy/dv``, shape (n_outputs, nv),
            ``Jdot_v`` (m/s^2 or rad/s^2), shape (n_outputs,) (as
            :meth:`RobotKinematics.outputs <amlip_qp.robots.kinematics.RobotKinematics.outputs>`;
            treat as read-only). The controller reports these; ``None`` (a tracker that did not
            evaluate them): the controller asks its kinematics.
    """

    tau_Nm: np.ndarray
    ok: bool = True
    fallback: str | None = None
    info: dict = field(default_factory=dict)
    outputs: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None
