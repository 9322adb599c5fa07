"""The contact points in the IMU frame from the joint encoders (forward kinematics).

The contact-aided filter measures where each foot's contact site is seen from
the IMU: the base IMU, fixed to the base with the base's axes
(:mod:`~amlip_qp.estimation.imu_to_base` turns the robot's IMU's reading into
its). That vector depends on the joint angles only: the kinematics run on
the controller's Pinocchio model with the base at the origin (identity pose),
so the contact site's world position is its position in the base frame; the
base IMU sits at ``imu_pos_in_base_m`` in the base frame with the base's axes,
so the vector from the IMU to the site, in IMU axes, is that position minus
``imu_pos_in_base_m``. This object keeps its own ``pinocchio.Data``.

For a blade foot (toe and heel force sites, Cassie; the sole line of a
four-point foot, ``Robot.sole_line_frame_ids``) it also gives the blade,
the vector from the heel to the toe, in IMU axes: with the estimated
orientation it tells whether the blade rests flat on the ground (see
:meth:`~amlip_qp.estimation.invariant_ekf.InvariantEKF.set_contacts`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from amlip_qp.exceptions import InputError

if TYPE_CHECKING:  # pragma: no cover - typing only
    from amlip_qp.robots.robot import Robot


class LegKinematics:
    """Contact-site positions in the IMU frame from the joint angles.

    Args:
        robot: A floating-base :class:`~amlip_qp.robots.robot.Robot` (free-flyer root).
        imu_pos_in_base_m: Position of the base IMU in the base frame, m, shape (3,).

    Raises:
        InputError: A robot without a free-flyer base, or a bad IMU position.
    """

    def __init__(self, robot: Robot, imu_pos_in_base_m):
        import pinocchio as pin

        if not robot.is_floating:
            raise InputError(
                f"{robot.name}: the contact-aided EKF needs a free-floating base (a free joint); "
                "use --estimator truth for this robot"
            )
        imu = np.array(imu_pos_in_base_m, dtype=float)
        if imu.shape != (3,) or not np.isfinite(imu).all():
            raise InputError(f"imu_pos_in_base_m must be 3 finite numbers in m, got {imu_pos_in_base_m!r}")
        self._pin = pin
        self.model = robot.pin_model
        self.data = self.model.createData()
        self.sides = tuple(robot.foot_sides)
        #: Pinocchio frame ids of the contact sites (``sides`` order).
        self.frame_ids = tuple(robot.contact_frame_ids[s] for s in self.sides)
        #: Pinocchio frame ids of each side's (toe, heel) sites, or ``None`` without blade feet.
        self.blade_frame_ids: tuple[tuple[int, int], ...] | None = None
        if all(len(robot.sole_line_frame_ids.get(s, ())) == 2 for s in self.sides):
            self.blade_frame_ids = tuple(tuple(robot.sole_line_frame_ids[s]) for s in self.sides)  # type: ignore[misc]
        self.imu_pos_in_base_m = imu
        self._q = np.zeros(self.model.nq)
        self._q[6] = 1.0  # identity base quaternion (x y z w)
        self._nq = self.model.nq

    def contacts_in_imu(self, q) -> np.ndarray:
        """Each side's contact site seen from the IMU, IMU axes, m, shape (2, 3) (``self.sides`` order).

        Args:
            q: A Pinocchio configuration, shape (nq,); only its joint part
                ``q[7:]`` (the encoder angles) is used.
        """
        pin = self._pin
        qq = self._q
        qq[7:] = q[7 : self._nq]
        m, d = self.model, self.data
        pin.forwardKinematics(m, d, qq)
        out = np.empty((2, 3))
        for i, fid in enumerate(self.frame_ids):
            out[i] = pin.updateFramePlacement(m, d, fid).translation
        out -= self.imu_pos_in_base_m
        return out

    def blades_in_imu(self, q) -> np.ndarray | None:
        """Each side's blade (toe minus heel site), IMU axes, m, shape (2, 3); ``None`` without blade feet.

        Args:
            q: A Pinocchio configuration; only ``q[7:]`` is used.
        """
        if self.blade_frame_ids is None:
            return None
        pin = self._pin
        qq = self._q
        qq[7:] = q[7 : self._nq]
        m, d = self.model, self.data
        pin.forwardKinematics(m, d, qq)
        out = np.empty((2, 3))
        for i, (toe, heel) in enumerate(self.blade_frame_ids):
            out[i] = pin.updateFramePlacement(m, d, toe).translation - pin.updateFramePlacement(m, d, heel).translation
        return out
