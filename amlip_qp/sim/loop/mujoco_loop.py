"""The walking controller on your own MuJoCo model and data: :class:`MujocoLoop`.

The harness (:class:`~amlip_qp.sim.loop.harness.Simulation`) owns its plant, steps it
and logs every tick. :class:`MujocoLoop` owns nothing of MuJoCo: it runs one
control tick on the ``mujoco.MjModel`` / ``mujoco.MjData`` you step yourself::

    loop = MujocoLoop(robot, QPTracker(robot), model, data)
    while ...:
        loop.step(loop.command(vx_mps=0.5))  # read the state, run the controller, write data.ctrl
        mujoco.mj_step(model, data)

Each :meth:`MujocoLoop.step` does what a harness tick does, through the same
functions: the state as the controller's Pinocchio ``(q, v)``
(:meth:`~amlip_qp.sim.world.plant.Plant.read_state`, on :mod:`amlip_qp.robots.state`),
the ``ideal`` measurement with the feet's contact switches
(:meth:`~amlip_qp.sim.sensing.sensors.PlantSensors.bind`),
:meth:`~amlip_qp.control.walking.controller.WalkingController.step`, and the
torques written as ``data.ctrl = tau / gear`` into the model's actuators of the
same names, clipped to their control ranges
(:meth:`~amlip_qp.sim.world.plant.Plant.ctrl_writer`). The model is matched to the
controller's by name (:class:`~amlip_qp.sim.world.plant.Plant`), so it may be
``robot.mj_model`` itself or a model compiled from the same MJCF file, with
other actuator and joint orders, extra bodies, sensors or options. The base
state is MuJoCo's (the controller's ``truth`` estimator).
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

from amlip_qp.control.tracker import Tracker
from amlip_qp.control.walking.controller import WalkingController
from amlip_qp.control.walking.records import TickInfo
from amlip_qp.exceptions import InputError
from amlip_qp.messages import Command
from amlip_qp.robots.robot import Robot
from amlip_qp.sim.sensing.sensors import PlantSensors
from amlip_qp.sim.world.plant import Plant


class MujocoLoop:
    """A :class:`~amlip_qp.control.walking.controller.WalkingController` on a MuJoCo model and data you step.

    Args:
        robot: The controller's robot (:func:`amlip_qp.load_robot`).
        controller: A tracker for ``robot`` (:class:`~amlip_qp.control.wbc.tracker.QPTracker`,
            :class:`~amlip_qp.control.pbc.tracker.PBCTracker`), around which a
            ``WalkingController`` is built with its defaults (2 kHz, the profile's command
            shaping), or a ready ``WalkingController`` of ``robot``.
        model: The MuJoCo model playing the robot: ``robot.mj_model`` or one compiled from the
            same MJCF; it needs the controller's joints, actuators (torque motors), base body
            and foot bodies, by name, and a timestep that divides the control period.
        data: ``model``'s data at the start pose, forwarded (e.g. ``robot.new_mj_data("stand")``).
        contact_threshold_N: Floor normal force above which a foot's contact switch is on, N.

    Raises:
        InputError: ``data`` is not ``model``'s, ``model`` lacks a joint, actuator or body of the
            controller's model (all named), an actuator is not a torque motor, the timestep does
            not divide the control period, or ``controller`` is neither a tracker nor a controller
            of ``robot``.
    """

    def __init__(
        self,
        robot: Robot,
        controller: Tracker | WalkingController,
        model: mujoco.MjModel,
        data: mujoco.MjData,
        contact_threshold_N: float = 20.0,
    ):
        if not isinstance(model, mujoco.MjModel) or not isinstance(data, mujoco.MjData):
            raise InputError(
                f"MujocoLoop needs a mujoco.MjModel and its mujoco.MjData, got {type(model).__name__} "
                f"and {type(data).__name__}"
            )
        sizes = (data.qpos.size, data.qvel.size, data.ctrl.size, data.sensordata.size)
        if getattr(data, "model", model) is not model or sizes != (model.nq, model.nv, model.nu, model.nsensordata):
            raise InputError("data was not made for model: make it with mujoco.MjData(model)")
        if isinstance(controller, Tracker):
            if getattr(controller, "robot", robot) is not robot:
                raise InputError(f"the tracker {controller.name!r} was built for another robot than {robot.name}")
            controller = WalkingController(robot, controller)
        elif not isinstance(controller, WalkingController):
            raise InputError(
                f"controller must be a tracker (QPTracker, PBCTracker) or a WalkingController, "
                f"got {type(controller).__name__}"
            )
        if controller.robot is not robot:
            raise InputError(f"the controller was built for another robot than {robot.name}")
        if not (contact_threshold_N >= 0 and math.isfinite(contact_threshold_N)):
            raise InputError(f"contact_threshold_N must be a finite force >= 0 N, got {contact_threshold_N!r}")
        model_name = model.names[: model.names.index(b"\0")].decode() or "unnamed"
        #: The model mapped to the controller's by name.
        self.plant = Plant(model, robot, f"MjModel {model_name!r}")
        #: MuJoCo steps between two calls of :meth:`step` (the control period over the timestep).
        self.substeps = self.plant.substeps(controller.dt_s)
        self.robot, self.controller, self.model, self.data = robot, controller, model, data
        controller.reset()  # a walk starts at the first step
        sensors = PlantSensors(self.plant, "ideal", controller.dt_s, contact_threshold_N=contact_threshold_N)
        self._measure = sensors.bind(data, base_known=True)
        self._write = self.plant.ctrl_writer(data)
        self._t_last: float | None = None
        self._zero_tau = np.zeros(robot.nu)

    def command(self, vx_mps: float = 0.0, vy_mps: float = 0.0, turn_rate_radps: float = 0.0) -> Command:
        """A :class:`~amlip_qp.messages.Command` with the robot profile's gait and these speeds.

        Args:
            vx_mps: Forward speed in the heading frame, m/s.
            vy_mps: Lateral (left positive) speed, m/s.
            turn_rate_radps: Heading rate, rad/s (positive turns left).

        Raises:
            InputError: The robot has no profile (give a ``Command`` of your own), or a speed is not finite.
        """
        profile = self.robot.profile
        if profile is None:
            raise InputError(
                f"{self.robot.name} has no profile and so no gait: make the Command yourself "
                "(step_time_s, com_height_m, clearance_m, step_width_m)"
            )
        g = profile.gait
        return Command(
            step_time_s=g.step_time_s, com_height_m=g.com_height_m, clearance_m=g.clearance_m,
            step_width_m=g.step_width_m, vx_mps=vx_mps, vy_mps=vy_mps, turn_rate_radps=turn_rate_radps,
        )  # fmt: skip

    def step(self, command: Command) -> TickInfo:
        """One control tick at ``data.time``: read the state and the feet's contacts, run the controller,
        write ``data.ctrl`` (finite, within the control ranges). Call it once every
        ``controller.dt_s`` of simulated time (every :attr:`substeps` ``mj_step`` calls).

        Returns:
            The controller's :class:`~amlip_qp.control.walking.records.TickInfo` (``tau_Nm``: the
            joint torques in ``robot.actuated`` order, N m).

        Raises:
            InputError: ``data.time`` did not advance by one control period since the last call
                (after resetting ``data``, call :meth:`reset`), or ``qpos`` or ``qvel`` is not
                finite (a diverged simulation: ``data.ctrl`` is then set to 0).
        """
        t = float(self.data.time)
        last, dt_s = self._t_last, self.controller.dt_s
        if last is not None and abs(t - last - dt_s) > 1e-9:
            raise InputError(
                f"MujocoLoop.step runs one control tick per {dt_s} s of simulated time ({self.substeps} mj_step "
                f"between calls); data.time moved by {t - last:.6g} s since the last call (after resetting data, "
                "call loop.reset())"
            )
        try:
            q, v = self.plant.read_state(self.data)
        except InputError as exc:  # NaN or inf in qpos or qvel: motors off rather than NaN controls
            self._write(self._zero_tau)
            msg = f"MujocoLoop.step: {exc} (ctrl set to 0; after resetting data, call loop.reset())"
            raise InputError(msg) from None
        tick = self.controller.step(self._measure(t, q, v), command)
        self._write(tick.tau_Nm)
        self._t_last = t
        return tick

    def reset(self) -> None:
        """Start over (a new walk from ``data``'s state now): the controller forgets its steps and filters."""
        self.controller.reset()
        self._t_last = None

    @property
    def ctrl(self) -> np.ndarray:
        """The controls last written, in the controller's actuator order (a copy of ``data.ctrl``'s entries)."""
        return self.data.ctrl[self.plant.actuator_ids].copy()
