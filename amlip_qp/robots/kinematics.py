"""The robot's kinematics and dynamics on Pinocchio, for the trackers: :class:`RobotKinematics`.

Usage: create one :class:`RobotKinematics` per controller, call
:meth:`RobotKinematics.update` once per control tick with the Pinocchio state
``(q, v)`` (or :meth:`RobotKinematics.update_positions` in iterative
kinematics); the getters afterwards read cached results. The state comes in
through the updates only: no other object writes into this one (its caches
are filled by its own getters), and the output map is chosen when it is
made (``RobotKinematics(robot, output_map=...)``; the compiled map with
:func:`~amlip_qp.control.walking.outputs_compiled.make_kinematics`).

The model's part (Pinocchio's passes, the frames, the CoM, the centroidal
momentum, ``M`` and ``h``, all by frame id) is
:class:`~amlip_qp.robots.model_kinematics.ModelKinematics`, with the update
and caching rules; this class adds what needs the
:class:`~amlip_qp.robots.robot.Robot`: the ALIP contact point of each side,
the root body, ``L`` about a contact, the passive forces and joint couplings
(:mod:`amlip_qp.robots.passive`) and the output map ``h_0``
(:mod:`amlip_qp.robots.outputs`).

All vectors are in world axes and SI units; Jacobians are world-aligned and
map Pinocchio's ``v`` (see :mod:`~amlip_qp.robots.model_kinematics`).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from amlip_qp.exceptions import InputError, MJCFError
from amlip_qp.robots import passive as _passive
from amlip_qp.robots.model_kinematics import ModelKinematics
from amlip_qp.robots.outputs import OutputMap, check_output_map
from amlip_qp.robots.robot import Robot

#: A singular value of the output Jacobian at or below this counts as lost rank (m or rad of output
#: per m or rad of the velocity coordinates): tracking 1 m/s (or 1 rad/s) along it would take 100
#: rad/s of the joints.
RANK_TOL = 1e-2


def stand_output_rank(robot: Robot) -> tuple[int, int, float, str]:
    """The output Jacobian ``dh_0/dv`` at the stand pose (at rest), both stances: ``(rank, outputs,
    smallest singular value, its stance side)``; a singular value at or below :data:`RANK_TOL`
    counts as lost."""
    kin = RobotKinematics(robot)
    kin.update(robot.q_stand, np.zeros(robot.nv))
    smallest, rank, n, side_min = np.inf, 0, 0, ""
    for side in robot.foot_sides:
        _, J, _ = kin.outputs(side)
        s = np.linalg.svd(J, compute_uv=False)
        n = J.shape[0]
        if s[-1] < smallest:
            smallest, rank, side_min = float(s[-1]), int(np.sum(s > RANK_TOL)), side
    return rank, n, smallest, side_min


def check_stand_output_rank(robot: Robot) -> None:
    """Raise :class:`MJCFError` unless the output Jacobian has full rank at the stand pose
    (:func:`stand_output_rank`): each output must be movable on its own there."""
    rank, n, smallest, side = stand_output_rank(robot)
    if rank < n:
        raise MJCFError(
            f"{robot.path}: the output Jacobian has rank {rank} of {n} at the stand pose (smallest singular value "
            f"{smallest:.2g}, {side} stance): a singular pose (a straight knee?); bend the legs in [model.stand]"
        )


class RobotKinematics(ModelKinematics):
    """Pinocchio kinematics/dynamics of one robot at the last ``update(q, v)``.

    Attributes:
        robot: The :class:`~amlip_qp.robots.robot.Robot`.
        model: Its Pinocchio model.
        data: This object's own Pinocchio data.
        q: The configuration of the last update (copy), shape (nq,).
        v: The velocity of the last update (copy), shape (nv,).
    """

    def __init__(self, robot: Robot, output_map: Any = None):
        """Create the Pinocchio data; call :meth:`update` before any getter.

        Args:
            robot: The robot.
            output_map: The evaluator of :meth:`outputs` (:attr:`output_map`), fixed for this
                object's life; ``None``: :class:`~amlip_qp.robots.outputs.OutputMap`.

        Raises:
            InputError: ``output_map`` does not evaluate the robot's outputs
                (:func:`~amlip_qp.robots.outputs.check_output_map`).
        """
        if output_map is not None:
            check_output_map(robot, output_map)
        self.robot = robot
        super().__init__(robot.pin_model)
        self._output_map: Any = output_map  # an OutputMap or a drop-in (see output_map); None: made on first use
        self._out_cache: tuple | None = None
        self._taup: np.ndarray | None = None
        self._passive_forces = _passive.PassiveForces(robot)

    def _invalidate(self, positions_only: bool) -> None:
        """Drop the per-update caches: the model's, the output map's and the passive forces'."""
        super()._invalidate(positions_only)
        self._out_cache = None
        self._taup = None

    # ---------------------------------------------------------- contacts
    def contact_position(self, side: str) -> np.ndarray:
        """World position (m) of the ALIP contact point (``{side}-contact``)."""
        return self.frame_position(self.robot.contact_frame_ids[self._side(side)])

    def contact_jacobian(self, side: str) -> np.ndarray:
        """Translational Jacobian (3 x nv) of the ALIP contact point."""
        return self.frame_jacobian(self.robot.contact_frame_ids[self._side(side)])

    def contact_jdot_v(self, side: str) -> np.ndarray:
        """``Jdot v`` (m/s^2) of the ALIP contact point, shape (3,)."""
        return self.frame_jdot_v(self.robot.contact_frame_ids[self._side(side)])

    def _side(self, side: str) -> str:
        if side not in self.robot.foot_sides:
            raise InputError(f"side must be 'left' or 'right', got {side!r}")
        return side

    # -------------------------------------------------------------- base
    def base_rotation(self) -> np.ndarray:
        """World rotation of the root body (pelvis / torso), shape (3, 3)."""
        return self.frame_rotation(self.robot.base_frame_id)

    def base_angular_jacobian(self) -> np.ndarray:
        """World angular-velocity Jacobian (3 x nv) of the root body."""
        return self.frame_jacobian6(self.robot.base_frame_id)[3:]

    # ------------------------------------------------------------ momentum
    def angular_momentum_about_contact(self, side: str) -> np.ndarray:
        """``L`` (kg m^2/s) about the ``{side}-contact`` point."""
        return self.angular_momentum_about(self.contact_position(side))

    # ---------------------------------------------------- passive elements
    def passive_forces(self) -> np.ndarray:
        """Joint springs, damping and tendon springs (= MuJoCo's qfrc_passive, Pinocchio coordinates).

        Cached until the next :meth:`update` (treat as read-only).
        """
        q, v = self.state()
        if self._taup is None:
            self._taup = self._passive_forces(q, v)
        return self._taup

    def coupling_constraints(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(g, G, Gdot_v)`` of the rigid joint couplings (see :mod:`amlip_qp.robots.passive`)."""
        q, v = self.state()
        return _passive.coupling_constraints(self.robot, q, v)

    # ------------------------------------------------------------- outputs
    @property
    def output_map(self):
        """The evaluator of :meth:`outputs`, given to the constructor: an
        :class:`~amlip_qp.robots.outputs.OutputMap` (the default, created on first use) or a
        drop-in with the same ``names`` and ``evaluate(kin, stance, heading_rad)``, e.g. the
        compiled :class:`~amlip_qp.control.walking.outputs_compiled.CompiledOutputMap`
        (:func:`~amlip_qp.control.walking.outputs_compiled.make_kinematics`)."""
        if self._output_map is None:
            self._output_map = OutputMap(self.robot)
        return self._output_map

    def outputs(self, stance: str, heading_rad: float = 0.0):
        """The output map ``h_0(q)``: ``(y, J, Jdot_v)``, see :mod:`amlip_qp.robots.outputs`.

        Evaluated by :attr:`output_map`; the result is cached until the next :meth:`update`
        for the same ``(stance, heading_rad)``: treat the returned arrays as read-only.
        """
        self._ready()
        cache = self._out_cache
        if cache is not None and cache[0] == stance and cache[1] == heading_rad:
            return cache[2]
        result = self.output_map.evaluate(self, stance, heading_rad)
        self._out_cache = (stance, heading_rad, result)
        return result
