"""The interface every tracker implements.

A tracker turns the planner's reference outputs ``h_d(s)`` (with their time
derivatives) into joint torques for the actuated joints, given the state
estimate in Pinocchio coordinates (through the controller's kinematics
object, updated once per tick). The paper's baseline (iterative IK plus a
passivity-based controller, :mod:`amlip_qp.control.pbc`) and the whole-body
QP both implement it, so the walking loop
(:class:`amlip_qp.control.walking.controller.WalkingController`) runs either one.
"""

from __future__ import annotations

import abc
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from amlip_qp.messages import TrackerResult

if TYPE_CHECKING:  # pragma: no cover - typing only
    from amlip_qp.robots.kinematics import RobotKinematics


@dataclass
class TrackingTarget:
    """What the tracker must follow at this tick.

    Attributes:
        stance: ``"left"`` or ``"right"``: the stance side of the current step.
        phase: Phase ``s`` in [0, 1] (clipped; late steps stay at 1).
        heading_rad: Heading ``D_k`` of the current step (yaw), rad.
        h_d: Reference outputs in the robot's output order (m or rad).
        dh_d: Their time derivatives (m/s or rad/s).
        ddh_d: Their second time derivatives (m/s^2 or rad/s^2).
        swing_contact_weight: 0 while the swing foot is in the air, rising to 1
            when it touches down: trackers use it to ramp contact forces in.
        stance_ground_pitch_rad: The ground's pitch under the stance foot along
            the heading, rad (positive = descending ahead), for a tracker that
            orients its friction cone on it; ``None`` (flat-ground controller):
            the cone is about the world's vertical.
    """

    stance: str
    phase: float
    heading_rad: float
    h_d: np.ndarray
    dh_d: np.ndarray
    ddh_d: np.ndarray
    swing_contact_weight: float = 0.0
    stance_ground_pitch_rad: float | None = None


class Tracker(abc.ABC):
    """Follows reference outputs with joint torques.

    Subclasses set :attr:`name` and implement :meth:`compute`.
    """

    #: Short name used by the CLI and in summaries (``"pbc"``, ``"qp"``).
    name: str = "tracker"
    #: The shortest step this tracker's swing leg follows, s (0: no bound of its own). The
    #: step-timing MPC plans no step shorter than this (nor than the command's ``T``:
    #: :attr:`amlip_qp.alip.mpc_planner.MPCSettings.step_time_min_s`, set by the walking loop).
    shortest_step_s: float = 0.0

    @abc.abstractmethod
    def compute(self, kin: RobotKinematics, target: TrackingTarget) -> TrackerResult:
        """Torques for the state in ``kin`` and the references in ``target``.

        Args:
            kin: The controller's :class:`~amlip_qp.robots.kinematics.RobotKinematics`,
                already updated at this tick's estimated ``(q, v)`` (read
                ``kin.state()``); trackers must not update it again.
            target: This tick's references.
        """

    def reset(self) -> None:  # noqa: B027 (optional hook: a no-op by design)
        """Forget internal state (warm starts, filters) before a new run.

        The default does nothing: a tracker without such state need not override it.
        """
