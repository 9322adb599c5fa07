"""Acceleration-level tasks for the whole-body QP (TSID vocabulary, Pink-style classes).

A task is a vector function ``y(q)`` that the QP should drive along a
reference. Each task gives

- its **error** ``e = y_d - y`` (the task's unit: m or rad),
- its **Jacobian** ``J = dy/dq`` mapping Pinocchio's ``v`` to ``dy/dt``
  (task unit per (m/s or rad/s)),
- its **drift** ``Jdot v`` (task unit / s^2): ``ydd = J vdot + Jdot v``,
- its **desired acceleration** ``ydd_des = ydd_d + K_d (yd_d - J v) + K_p e``
  (task unit / s^2), with ``K_p`` in 1/s^2 and ``K_d`` in 1/s.

The QP turns a task into the weighted least-squares cost
``|| W^(1/2) (J vdot + Jdot v - ydd_des) ||^2``.

Tasks read the controller's :class:`~amlip_qp.robots.kinematics.RobotKinematics`
(already updated at this tick) and the :class:`~amlip_qp.control.tracker.TrackingTarget`;
they never update the kinematics themselves. A task evaluates its map once per
tick (keyed on the ``kin.q`` array object, which ``update`` replaces) and
serves every getter from that cache.
"""

from __future__ import annotations

import abc
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from amlip_qp.exceptions import InputError

if TYPE_CHECKING:
    from amlip_qp.control.tracker import TrackingTarget
    from amlip_qp.robots.kinematics import RobotKinematics


@dataclass(frozen=True)
class Gains:
    """Per-component PD gains and weights of a task.

    Attributes:
        kp: Proportional gains, 1/s^2, shape (n,).
        kd: Derivative gains, 1/s, shape (n,).
        weight: Cost weights (dimensionless multipliers of the squared task
            acceleration error, (task unit/s^2)^-2), shape (n,).
    """

    kp: np.ndarray
    kd: np.ndarray
    weight: np.ndarray

    @classmethod
    def of(cls, n: int, kp, kd, weight) -> Gains:
        """Broadcast scalars or sequences to ``n`` components (validated, finite, >= 0)."""
        out = []
        for name, val in (("kp", kp), ("kd", kd), ("weight", weight)):
            arr = np.broadcast_to(np.asarray(val, dtype=float), (n,)).copy()
            if not np.all(np.isfinite(arr)) or np.any(arr < 0):
                raise InputError(f"task {name} must be finite and >= 0, got {val!r}")
            arr.setflags(write=False)
            out.append(arr)
        return cls(*out)


class Task(abc.ABC):
    """An acceleration-level task ``y(q)`` with PD feedback (see the module docstring).

    Subclasses implement :meth:`_evaluate`, returning ``(y, J, Jdot_v)`` at the
    current state, and :meth:`reference`, returning ``(y_d, yd_d, ydd_d)``.

    Attributes:
        name: Task name (used in diagnostics).
        gains: The task's :class:`Gains`.
    """

    name: str = "task"
    #: True when :meth:`jacobian` does not depend on the state (a builder may
    #: then precompute its Hessian block once). Such tasks also implement
    #: :meth:`affine_residual`.
    constant_jacobian: bool = False

    def __init__(self, gains: Gains):
        self.gains = gains
        self._q_ref: np.ndarray | None = None
        self._key: object = None
        self._cache: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None

    @property
    def size(self) -> int:
        """Number of task components."""
        return self.gains.kp.shape[0]

    @abc.abstractmethod
    def _evaluate(self, kin: RobotKinematics, target: TrackingTarget) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(y, J, Jdot_v)`` at the state of ``kin`` (shapes (n,), (n, nv), (n,))."""

    @abc.abstractmethod
    def reference(self, kin: RobotKinematics, target: TrackingTarget) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(y_d, yd_d, ydd_d)``: desired value, rate and acceleration, shape (n,) each."""

    def _terms(self, kin: RobotKinematics, target: TrackingTarget) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        key = self._cache_key(target)
        # Holding a reference to kin.q keeps its id unique until the next update.
        if self._cache is None or self._q_ref is not kin.q or key != self._key:
            self._cache = self._evaluate(kin, target)
            self._q_ref = kin.q
            self._key = key
        return self._cache

    def _cache_key(self, target: TrackingTarget) -> object:
        """What besides the state changes the map (e.g. the stance side)."""
        return None

    def value(self, kin: RobotKinematics, target: TrackingTarget) -> np.ndarray:
        """Task value ``y`` (task unit: m or rad)."""
        return self._terms(kin, target)[0]

    def error(self, kin: RobotKinematics, target: TrackingTarget) -> np.ndarray:
        """Task error ``e = y_d - y`` (m or rad)."""
        return self.reference(kin, target)[0] - self._terms(kin, target)[0]

    def jacobian(self, kin: RobotKinematics, target: TrackingTarget) -> np.ndarray:
        """Task Jacobian ``J`` (n, nv): ``dy/dt = J v``."""
        return self._terms(kin, target)[1]

    def drift(self, kin: RobotKinematics, target: TrackingTarget) -> np.ndarray:
        """``Jdot v`` (task unit / s^2): the task acceleration at ``vdot = 0``."""
        return self._terms(kin, target)[2]

    def desired_acceleration(self, kin: RobotKinematics, target: TrackingTarget) -> np.ndarray:
        """``ydd_des = ydd_d + K_d (yd_d - J v) + K_p (y_d - y)`` (task unit / s^2)."""
        y, J, _ = self._terms(kin, target)
        y_d, yd_d, ydd_d = self.reference(kin, target)
        return ydd_d + self.gains.kd * (yd_d - J @ kin.v) + self.gains.kp * (y_d - y)

    def least_squares(self, kin: RobotKinematics, target: TrackingTarget) -> tuple[np.ndarray, np.ndarray]:
        """``(J, r)`` of the task's cost ``||W^(1/2) (J vdot + r)||^2``, with
        ``r = Jdot v - ydd_des`` (task unit / s^2), from one evaluation."""
        y, J, jdv = self._terms(kin, target)
        y_d, yd_d, ydd_d = self.reference(kin, target)
        return J, jdv - ydd_d - self.gains.kd * (yd_d - J @ kin.v) - self.gains.kp * (y_d - y)


class OutputTask(Task):
    """All outputs ``h_0(q)`` of the robot (docs/ARCHITECTURE.md) in one task.

    The reference is the planner's ``h_d(s)`` and its time derivatives from the
    :class:`~amlip_qp.control.tracker.TrackingTarget`; the map is evaluated
    with the target's stance side and heading. Units per component: m or rad.
    """

    name = "outputs"

    def _cache_key(self, target: TrackingTarget) -> object:
        return (target.stance, float(target.heading_rad))

    def _evaluate(self, kin: RobotKinematics, target: TrackingTarget) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        return kin.outputs(target.stance, target.heading_rad)

    def reference(
        self, kin: RobotKinematics | None, target: TrackingTarget
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        return target.h_d, target.dh_d, target.ddh_d


class JointTask(Task):
    """Linear combinations of scalar joints: ``y = C q_joints`` toward a constant ``y_ref``.

    Used for the low-weight posture regularisation of the actuated joints and
    for damping the passive spring joints (rad; rad/s^2 accelerations).

    Args:
        name: Task name.
        rows_v: (n, nv) matrix ``C`` acting on ``v`` (its entries select
            Pinocchio velocity indices of hinge/slide joints).
        q_idx: For each velocity index with a nonzero column, the matching
            Pinocchio configuration index, as a dict ``{v_idx: q_idx}``.
        y_ref: Constant reference (rad), shape (n,).
        gains: Gains (kp may be 0 for a pure damping task).
    """

    constant_jacobian = True

    def __init__(self, name: str, rows_v: np.ndarray, q_idx: dict[int, int], y_ref, gains: Gains):
        super().__init__(gains)
        self.name = name
        self._C = np.asarray(rows_v, dtype=float)
        cols = np.flatnonzero(np.any(self._C != 0.0, axis=0))
        missing = [int(c) for c in cols if int(c) not in q_idx]
        if missing:
            raise InputError(f"JointTask {name!r}: no configuration index for velocity indices {missing}")
        self._cols_v = cols
        self._cols_q = np.array([q_idx[int(c)] for c in cols], dtype=int)
        self._Cc = self._C[:, cols]
        self._y_ref = np.broadcast_to(np.asarray(y_ref, dtype=float), (self._C.shape[0],)).copy()
        self._zero = np.zeros(self._C.shape[0])

    def _evaluate(self, kin: RobotKinematics, target: TrackingTarget) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        q, _ = _state(kin)
        return self._Cc @ q[self._cols_q], self._C, self._zero

    def jacobian(self, kin: RobotKinematics | None = None, target: TrackingTarget | None = None) -> np.ndarray:
        """The constant matrix ``C`` (n, nv); no state needed."""
        return self._C

    def desired_acceleration(self, kin: RobotKinematics, target: TrackingTarget | None) -> np.ndarray:
        """``K_d (0 - C v) + K_p (y_ref - C q)`` (rad/s^2), without the task cache."""
        q, v = _state(kin)
        y = self._Cc @ q[self._cols_q]
        return self.gains.kp * (self._y_ref - y) - self.gains.kd * (self._Cc @ v[self._cols_v])

    def least_squares(self, kin: RobotKinematics, target: TrackingTarget | None) -> tuple[np.ndarray, np.ndarray]:
        """``(C, -ydd_des)``: the drift of a linear task is zero."""
        return self._C, -self.desired_acceleration(kin, target)

    def affine_residual(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """The residual ``r = -ydd_des`` of :meth:`least_squares` as an affine
        map of the state: ``r = Rq q[cols_q] + Rv v[cols_v] + r0``.

        Returns:
            ``(cols_q, Rq, cols_v, Rv, r0)``; ``Rq = K_p C``, ``Rv = K_d C``
            (per component), ``r0 = -K_p y_ref`` (rad/s^2).
        """
        kp, kd = self.gains.kp[:, None], self.gains.kd[:, None]
        return self._cols_q, kp * self._Cc, self._cols_v, kd * self._Cc, -self.gains.kp * self._y_ref

    def reference(
        self, kin: RobotKinematics | None, target: TrackingTarget | None
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        return self._y_ref, self._zero, self._zero


def _state(kin: RobotKinematics) -> tuple[np.ndarray, np.ndarray]:
    """``(kin.q, kin.v)``; :class:`InputError` before the first update."""
    if kin.q is None or kin.v is None:
        raise InputError("RobotKinematics: call update(q, v) first")
    return kin.q, kin.v
