"""The controller's base-state estimators: the simulator's truth, or the contact-aided invariant EKF.

:func:`make_base_estimator` makes one by name. :meth:`BaseStateEstimator.fill`
takes this tick's measurement and returns one whose base part (``q[:7]``:
position and ``x y z w`` quaternion; ``v[:6]``: the Pinocchio free-flyer
twist, i.e. the linear velocity of the base origin and the angular velocity,
both in base axes) is the estimate.

- ``truth`` returns the measurement object itself, untouched (the harness put
  the simulator's base state in it).
- ``ekf`` (:class:`EkfBaseEstimator`) runs
  :class:`~amlip_qp.estimation.invariant_ekf.InvariantEKF` on the IMU reading,
  turned first into that of an IMU fixed to the base with the base's axes
  (:class:`~amlip_qp.estimation.imu_to_base.ImuToBase`), and the leg kinematics of the encoder angles
  (:class:`~amlip_qp.estimation.leg_kinematics.LegKinematics`), with the
  foot-contact switches of the measurement (a blade foot counts once it rests
  flat, see :mod:`~amlip_qp.estimation.invariant_ekf`).

**Initialisation of the EKF** (first measurement, and after :meth:`reset`):
the robot is assumed at rest with both feet on the ground. The orientation is
the IMU's own quaternion (turned to the base); the velocity and biases are zero; the contact
points are placed through the leg kinematics. The world origin: the base's
``x, y`` are the first measurement's ``q[0:2]`` when finite (else the robot's
``stand`` keyframe's), and the height puts the two contact sites, on average,
at their height in the ``stand`` keyframe (the plant starts on flat ground at
``z = 0``). Yaw and the horizontal position are unobservable to the filter:
they drift from there.
"""

from __future__ import annotations

import math
import warnings
from typing import TYPE_CHECKING, Protocol

import numpy as np

from amlip_qp.estimation.imu_to_base import ImuToBase
from amlip_qp.estimation.invariant_ekf import EkfNoise, InvariantEKF
from amlip_qp.estimation.leg_kinematics import LegKinematics
from amlip_qp.estimation.rotations import quat_xyzw_to_rot, rot_to_quat_xyzw
from amlip_qp.exceptions import InputError
from amlip_qp.profiles import ImuMount

if TYPE_CHECKING:  # pragma: no cover - typing only
    from amlip_qp.estimation.ekf_compiled import CompiledEkf
    from amlip_qp.robots.robot import Robot

#: The estimator names :func:`make_base_estimator` knows.
ESTIMATORS = ("truth", "ekf")


class BaseStateEstimator(Protocol):
    """What the walking controller needs of a base-state estimator."""

    #: True once the estimate is unusable (the controller then goes to its safe mode).
    diverged: bool

    def fill(self, measurement):
        """This tick's measurement with the estimated base part (``q[:7]``, ``v[:6]``)."""

    def reset(self) -> None:
        """Start over (a new run)."""

    def set_ground_pitch(self, pitch_rad: float) -> None:
        """The ground's pitch under the feet along the heading, rad (positive = descending ahead; 0:
        level ground), which the walking controller passes every tick where it is given the terrain
        (terrain-aware); an estimator that takes a foot's contact from how it lies takes it against
        this ground."""


class TruthBaseEstimator:
    """The simulator's base state, as the harness put it in the measurement."""

    diverged = False

    def fill(self, measurement):
        """Return ``measurement`` itself (its base part is the truth).

        Raises:
            InputError: The measurement has no base state (``base_known`` False).
        """
        if not measurement.base_known:
            raise InputError(
                "--estimator truth needs the true base state in the measurement (base_known=True); "
                "use --estimator ekf with sensors that give no base state"
            )
        return measurement

    def reset(self) -> None:
        """Nothing to forget."""

    def set_ground_pitch(self, pitch_rad: float) -> None:
        """The truth needs no ground."""


class EkfBaseEstimator:
    """The base state from the contact-aided invariant EKF (see the module doc).

    Args:
        robot: A floating-base robot (the controller's model).
        dt_s: Control period, s (used when the measurement times do not advance).
        imu: Where the IMU sits: an :class:`~amlip_qp.profiles.ImuMount` (any body, position and
            axes; :attr:`~amlip_qp.robots.robot.Robot.imu_mount` is the profile's), or 3 numbers:
            its position on the base, m, with the base's axes. Each reading is turned into the
            base IMU's (:class:`~amlip_qp.estimation.imu_to_base.ImuToBase`) before the filter.
        noise: Filter settings (:class:`~amlip_qp.estimation.invariant_ekf.EkfNoise`).
        backend: ``"c"``: the tick as generated C
            (:class:`~amlip_qp.estimation.ekf_compiled.CompiledEkf`; without a
            compiler, numpy with one ``CodegenFallbackWarning``); ``"numpy"``:
            :class:`~amlip_qp.estimation.invariant_ekf.InvariantEKF` (the reference).
        cache_dir: Codegen cache folder (default: the codegen runtime's).

    Attributes:
        ekf: The numpy filter (the initialisation, and the filter itself with ``backend="numpy"``).
        compiled: The generated-C filter, or ``None``.
        to_base: The :class:`~amlip_qp.estimation.imu_to_base.ImuToBase` of the IMU's mounting.
        legs: The :class:`~amlip_qp.estimation.leg_kinematics.LegKinematics`, seen from the base IMU.
        diverged: True once the filter diverged (kept until :meth:`reset`).
    """

    def __init__(
        self, robot: Robot, dt_s: float, imu, noise: EkfNoise | None = None, backend: str = "c", cache_dir=None,
    ):  # fmt: skip
        if not (dt_s > 0 and math.isfinite(dt_s)):
            raise InputError(f"dt_s must be a positive control period in s, got {dt_s!r}")
        if backend not in ("c", "numpy"):
            raise InputError(f"the EKF backend must be 'c' or 'numpy', got {backend!r}")
        if not isinstance(imu, ImuMount):
            imu = ImuMount(pos_m=tuple(np.asarray(imu, dtype=float).reshape(-1).tolist()))
        self.to_base = ImuToBase(robot, imu)
        self.legs = LegKinematics(robot, self.to_base.point_in_base_m)
        self.ekf = InvariantEKF(noise)
        self.compiled: CompiledEkf | None = None
        if backend == "c":
            from amlip_qp.codegen.runtime import CodegenFallbackWarning
            from amlip_qp.estimation.ekf_compiled import GROUND_PITCH_INDEX, CompiledEkf
            from amlip_qp.exceptions import CompilerUnavailableError

            self._ground_index = GROUND_PITCH_INDEX

            try:
                self.compiled = CompiledEkf(self.ekf.noise, self.legs, cache_dir)
            except CompilerUnavailableError as exc:
                warnings.warn(
                    f"no compiled EKF ({exc}); using numpy (same estimate, slower)", CodegenFallbackWarning, 2
                )
        self.dt_s = float(dt_s)
        self.sides = self.legs.sides
        self._imu = self.legs.imu_pos_in_base_m
        self._q_stand = robot.q_stand.copy()
        #: The ground's pitch along the heading the blades are taken flat against, rad (:meth:`set_ground_pitch`).
        self.ground_pitch_rad = 0.0
        stand = self.legs.contacts_in_imu(robot.q_stand) + self._imu  # base frame
        R_stand = quat_xyzw_to_rot(robot.q_stand[3:7])
        #: Mean height of the contact sites in the stand keyframe (world), m.
        self.stand_contact_height_m = float(robot.q_stand[2] + (stand @ R_stand.T)[:, 2].mean())
        n = self.ekf.noise
        self._max_trace, self._max_speed2 = n.max_covariance_trace, n.max_speed_mps**2
        self.diverged = False
        self._t_prev: float | None = None
        self._imu_prev: tuple[np.ndarray, np.ndarray] | None = None

    def reset(self) -> None:
        """Forget the filter; the next :meth:`fill` re-initialises it."""
        self.diverged = False
        self.ground_pitch_rad = 0.0
        self._t_prev = None
        self._imu_prev = None
        self.to_base.reset()

    def state(self):
        """A copy of the filter state (:class:`~amlip_qp.estimation.invariant_ekf.EkfState`)."""
        return self.compiled.unpack() if self.compiled is not None else self.ekf.state()

    def set_ground_pitch(self, pitch_rad: float) -> None:
        """The ground's pitch along the heading, rad (positive = descending ahead; 0: level ground): a
        blade foot counts as a fixed contact while it lies flat on this ground
        (:func:`~amlip_qp.estimation.invariant_ekf.blade_is_flat`), from the next :meth:`fill` on.

        Raises:
            InputError: A pitch that is not finite or not within (-pi/2, pi/2).
        """
        pitch = float(pitch_rad)
        if not (math.isfinite(pitch) and abs(pitch) < 0.5 * math.pi):
            raise InputError(f"the ground's pitch must be a finite angle within (-pi/2, pi/2) rad, got {pitch_rad!r}")
        self.ground_pitch_rad = pitch

    def _contacts(self, measurement) -> tuple[bool, bool]:
        fc = measurement.foot_contact
        if not fc:
            raise InputError("--estimator ekf needs the foot-contact switches in the measurement (foot_contact)")
        return bool(fc.get(self.sides[0], False)), bool(fc.get(self.sides[1], False))

    def _initialise(self, measurement, imu, y: np.ndarray) -> None:
        R = quat_xyzw_to_rot(imu.quat_xyzw)
        xy = np.asarray(measurement.q[0:2], dtype=float)
        if not np.isfinite(xy).all():
            xy = self._q_stand[0:2]
        p = np.empty(3)
        p[0:2] = xy + (R @ self._imu)[0:2]
        p[2] = self.stand_contact_height_m - float((y @ R.T)[:, 2].mean())
        self.ekf.initialise(R, p, y)
        if self.compiled is not None:
            self.compiled.load(self.ekf.state())
            inp = self.compiled.input
            inp[0:7] = 0.0  # no propagation on the first tick
            inp[9:11] = 1.0  # both feet were in contact

    def fill(self, measurement):
        """This tick's measurement with the EKF's base estimate (a new object; the input is not modified).

        Raises:
            InputError: No IMU reading or no foot-contact switches in the measurement.
        """
        imu = measurement.imu
        if imu is None:
            raise InputError("--estimator ekf needs an IMU reading in the measurement (imu)")
        contacts = self._contacts(measurement)
        t = float(measurement.t_s)
        t_prev, compiled = self._t_prev, self.compiled
        self._t_prev = t
        dt = 0.0 if t_prev is None else (t - t_prev if t > t_prev else self.dt_s)  # none on the first tick
        if not self.to_base.identity:  # the base IMU's reading (the base IMU's is passed on untouched)
            imu = self.to_base.estimator_reading(imu, measurement.q, measurement.v, dt)
        if t_prev is None:
            y = self.legs.contacts_in_imu(measurement.q)
            self._initialise(measurement, imu, y)
        if compiled is not None:
            return self._fill_compiled(compiled, measurement, imu, contacts, dt)
        ekf = self.ekf
        if t_prev is not None:
            y = self.legs.contacts_in_imu(measurement.q)
            if self._imu_prev is not None:
                ekf.propagate(self._imu_prev[0], self._imu_prev[1], dt)
        gyro = np.asarray(imu.gyro_radps, dtype=float)
        ekf.set_contacts(contacts, y, self.legs.blades_in_imu(measurement.q), self.ground_pitch_rad)
        ekf.correct(y)
        self._imu_prev = (gyro, np.asarray(imu.accel_mps2, dtype=float))
        if not self.diverged and ekf.diverged():
            self.diverged = True
        return self._measurement(measurement, gyro)

    def _fill_compiled(self, c: CompiledEkf, measurement, imu, contacts: tuple[bool, bool], dt: float):
        inp = c.input
        inp[6] = dt
        inp[7], inp[8] = contacts
        inp[11:14] = imu.gyro_radps
        inp[self._ground_index] = self.ground_pitch_rad
        q = measurement.q
        c.q_joints[:] = q[7:]
        c.tick()
        # The next tick propagates with this tick's IMU, from the contacts the filter used
        # (a blade foot counts only once flat).
        inp[0:3] = imu.gyro_radps
        inp[3:6] = imu.accel_mps2
        inp[9:11] = c.contacts
        base, (tr, speed2) = c.base, c.checks.tolist()
        if not math.isfinite(sum(base.tolist()) + tr + speed2) or tr > self._max_trace or speed2 > self._max_speed2:
            self.diverged = True
        q = q.copy()
        v = measurement.v.copy()
        q[0:7] = base[0:7]
        v[0:6] = base[7:13]
        return type(measurement)(
            t_s=measurement.t_s, q=q, v=v, foot_contact=measurement.foot_contact, imu=measurement.imu, base_known=True
        )

    def _measurement(self, measurement, gyro: np.ndarray):
        ekf, r = self.ekf, self._imu
        R = ekf.R
        w = gyro - ekf.bg  # the base IMU's axes are the base's
        q = np.array(measurement.q, dtype=float)
        v = np.array(measurement.v, dtype=float)
        q[0:3] = ekf.p - R @ r
        q[3:7] = rot_to_quat_xyzw(R) if np.isfinite(R).all() else np.nan
        v[0:3] = R.T @ ekf.v - np.cross(w, r)
        v[3:6] = w
        return type(measurement)(
            t_s=measurement.t_s, q=q, v=v, foot_contact=measurement.foot_contact, imu=measurement.imu, base_known=True
        )


def make_base_estimator(
    name: str, robot: Robot, dt_s: float, imu=None, noise: EkfNoise | None = None, backend: str = "c"
) -> BaseStateEstimator:
    """The base-state estimator ``name`` (``"truth"`` or ``"ekf"``).

    Args:
        name: One of :data:`ESTIMATORS`.
        robot: The controller's robot.
        dt_s: Control period, s.
        imu: Where the IMU sits (required for ``"ekf"``): an :class:`~amlip_qp.profiles.ImuMount`
            (e.g. ``robot.imu_mount``) or its position on the base, m, with the base's axes.
        noise: EKF settings (``"ekf"`` only; default :class:`EkfNoise`).
        backend: The EKF's ``"c"`` (generated C, default) or ``"numpy"`` (:class:`EkfBaseEstimator`).

    Raises:
        InputError: Unknown name, or ``"ekf"`` without the IMU's mounting, with a bad one, or for a
            robot without a floating base.
    """
    if name == "truth":
        return TruthBaseEstimator()
    if name == "ekf":
        if imu is None:
            raise InputError(
                f"{robot.name}: --estimator ekf needs the IMU's mounting (imu: an ImuMount, e.g. robot.imu_mount)"
            )
        return EkfBaseEstimator(robot, dt_s, imu, noise, backend)
    raise InputError(f"unknown estimator {name!r}; choose one of {', '.join(ESTIMATORS)}")
