"""The plant: any MJCF model the controller walks on, mapped to the controller's model by name.

The controller keeps its own Pinocchio model (``--robot``); the plant is
MuJoCo running a model that may differ from it (``--plant``): extra passive
joints, loop closures, its own solver options, contact parameters and meshes.
:func:`~amlip_qp.sim.world.plant_loader.load_plant` checks that the plant has what the controller needs and
:class:`Plant` is the one place that maps the two by name:

- every joint of the controller's model (the root joints of a planar robot
  included) -> its ``qpos``/``qvel`` addresses in the plant;
- the controller's actuators, in the controller's order -> the plant's
  actuators of the same names (``ctrl = tau / gear`` with the plant's gears,
  clipped to the plant's control ranges);
- the base body, and the foot bodies (the bodies carrying the controller's
  ``{side}-contact`` sites), by name.

The base pose and velocity come from the base body whatever joints float it.
A free joint on the base body goes through :mod:`amlip_qp.robots.state`
exactly as the controller's own model does (its own model as the plant is
bit-identical to what the harness did before plants existed); otherwise
(slide and ball joints, or any chain of joints above the base) the pose is
the base body's and the twist is MuJoCo's ``mj_objectVelocity`` in the body's
own frame, which is Pinocchio's free-flyer convention.
"""

from __future__ import annotations

from collections.abc import Callable

import mujoco
import numpy as np

from amlip_qp.exceptions import CompilerUnavailableError, InputError, PlantMismatchError
from amlip_qp.robots.model_edits import is_servo
from amlip_qp.robots.robot import Robot
from amlip_qp.robots.state_reader import StateReader
from amlip_qp.sim.world.compiled_io import CompiledCtrlWrite, CompiledStateRead, ReadResult
from amlip_qp.sim.world.contact_sensors import sensor_switcher

#: A change of the plant's model before it is compiled (e.g. a plant modifier).
SpecEdit = Callable[[mujoco.MjSpec], None]

_FREE, _BALL, _SLIDE, _HINGE = 0, 1, 2, 3  # mujoco.mjtJoint values
_QPOS_SIZE = {_FREE: 7, _BALL: 4, _SLIDE: 1, _HINGE: 1}
_DOF_SIZE = {_FREE: 6, _BALL: 3, _SLIDE: 1, _HINGE: 1}


def _id(model: mujoco.MjModel, objtype: mujoco.mjtObj, name: str) -> int:
    return int(mujoco.mj_name2id(model, objtype, name))


class Plant:
    """A compiled MuJoCo plant mapped by name to a controller's :class:`~amlip_qp.robots.robot.Robot`.

    Attributes:
        model: The compiled ``mujoco.MjModel``.
        robot: The controller's robot.
        name: The plant's name (a plant name of the robot, or the file's path).
        base_body_id: Plant body id of the robot's base body.
        foot_body_ids: Side -> plant body id of the body carrying that side's contact site.
        actuator_ids: Plant actuator id of each controller actuator (controller order).
        gear: Plant gear of each controller actuator, shape (nu,).
        ctrl_range: Plant control range of each controller actuator, shape (nu, 2) (+-inf: unlimited).
        free_base: True when a free joint on the base body floats it.
        qpos_adr: Plant qpos address of each entry of the controller's MuJoCo
            qpos, shape (controller nq,); -1 where the plant has none (the
            controller's free joint, for a base floated by other joints).

    Raises:
        PlantMismatchError: The plant lacks joints, actuators or bodies (all named in one line).
    """

    def __init__(self, model: mujoco.MjModel, robot: Robot, name: str):
        self.model = model
        self.robot = robot
        self.name = name
        ctrl_model = robot.mj_model
        missing: list[str] = []
        body_names = [robot.base_body] + [self.body_name_of_site(robot, side) for side in robot.foot_sides]
        body_ids = [_id(model, mujoco.mjtObj.mjOBJ_BODY, n) for n in body_names]
        missing += [f"body {n!r}" for n, b in zip(body_names, body_ids) if b < 0]
        self.base_body_id = body_ids[0]
        self.foot_body_ids = dict(zip(robot.foot_sides, body_ids[1:]))
        # joints: the controller's, by name and type (the free root joint: the base body's free joint)
        qsrc = np.full(int(ctrl_model.nq), -1, dtype=np.intp)
        vsrc = np.empty(int(ctrl_model.nv), dtype=np.intp)
        self.free_base = False
        free_on_base = [
            j for j in range(model.njnt) if model.jnt_bodyid[j] == self.base_body_id and model.jnt_type[j] == _FREE
        ]
        for j in range(ctrl_model.njnt):
            jname = mujoco.mj_id2name(ctrl_model, mujoco.mjtObj.mjOBJ_JOINT, j) or f"joint{j}"
            jtype = int(ctrl_model.jnt_type[j])
            if jtype == _FREE:
                pj = free_on_base[0] if free_on_base else -1
                self.free_base = pj >= 0
                if pj < 0:
                    continue  # floated otherwise: the base body's pose
            else:
                pj = _id(model, mujoco.mjtObj.mjOBJ_JOINT, jname)
                if pj < 0 or int(model.jnt_type[pj]) != jtype:
                    missing.append(f"joint {jname!r}" + ("" if pj < 0 else " (of another type)"))
                    continue
            qa, pqa = int(ctrl_model.jnt_qposadr[j]), int(model.jnt_qposadr[pj])
            da, pda = int(ctrl_model.jnt_dofadr[j]), int(model.jnt_dofadr[pj])
            qsrc[qa : qa + _QPOS_SIZE[jtype]] = np.arange(pqa, pqa + _QPOS_SIZE[jtype])
            vsrc[da : da + _DOF_SIZE[jtype]] = np.arange(pda, pda + _DOF_SIZE[jtype])
        # actuators, in the controller's order
        act = robot.actuated
        self.actuator_ids = np.array([_id(model, mujoco.mjtObj.mjOBJ_ACTUATOR, n) for n in act.names], dtype=np.intp)
        missing += [f"actuator {n!r}" for n, a in zip(act.names, self.actuator_ids) if a < 0]
        if self.base_body_id >= 0 and robot.is_floating and not self.free_base and not self._base_moves():
            missing.append(f"joints floating body {robot.base_body!r}")
        if missing:
            raise PlantMismatchError(
                f"plant {name} does not fit the {robot.name} controller: it lacks {', '.join(missing)} "
                "(a plant needs the controller's actuators, measured joints and base body, by name)"
            )
        servos = [n for n, a in zip(act.names, self.actuator_ids.tolist()) if not self._is_motor(a)]
        if servos:
            raise PlantMismatchError(
                f"plant {name}: actuator {servos[0]!r} (of {len(servos)}) is not a torque motor (gain 1, "
                "no bias): the controller's joint torques are written as ctrl = tau / gear"
            )
        self.qpos_adr = qsrc
        ids = self.actuator_ids
        self.gear = model.actuator_gear[ids, 0].astype(float)
        limited = model.actuator_ctrllimited[ids].astype(bool)
        self.ctrl_range = np.where(limited[:, None], model.actuator_ctrlrange[ids], [-np.inf, np.inf])
        self._ctrl_lo, self._ctrl_hi = self.ctrl_range[:, 0].copy(), self.ctrl_range[:, 1].copy()
        nu = len(ids)
        self._ctrl_prefix = bool(np.array_equal(ids, np.arange(nu)))
        self._nu = nu
        # The controller's own joint layout: qpos and qvel are read as they are.
        same_layout = (self.free_base or not robot.is_floating) and (
            model.nq == ctrl_model.nq
            and model.nv == ctrl_model.nv
            and np.array_equal(qsrc, np.arange(model.nq))
            and np.array_equal(vsrc, np.arange(model.nv))
        )
        # the state as the controller's (q, v): one gather per array (a base not floated by a free joint: own path)
        self._reader: StateReader | None = None
        if same_layout:
            self._reader = StateReader(robot.state_map)
        elif self.free_base or not robot.is_floating:
            self._reader = StateReader(robot.state_map, qsrc, vsrc)
        # contact forces: plant geom -> body, and body -> the sides whose foot it is
        sides_of_body: dict[int, tuple[str, ...]] = {}
        for side, body in self.foot_body_ids.items():
            sides_of_body[body] = sides_of_body.get(body, ()) + (side,)
        geom_body = model.geom_bodyid.tolist()
        sides = [sides_of_body.get(b, ()) for b in geom_body]  # the sides whose foot the geom is on
        world, ng = [b == 0 for b in geom_body], int(model.ngeom)
        # geom pair (g1 + 1) * (ngeom + 1) + g2 + 1 (a flex's geom is -1) -> the sides it adds to: foot-world pairs
        self._pair_stride = ng + 1
        self._pair_sides: dict[int, tuple[str, ...]] = {}
        for f in [g for g in range(ng) if sides[g]]:
            for w in [g for g in range(ng) if world[g]]:
                for g1, g2 in ((f, w), (w, f)):
                    pair = (g1 + 1) * (ng + 1) + g2 + 1
                    self._pair_sides[pair] = (sides[g1] if world[g2] else ()) + (sides[g2] if world[g1] else ())
        self._force6 = np.zeros(6)
        if not self.free_base and robot.is_floating:
            smap = robot.state_map  # every hinge and slide joint of the controller's model
            self._pin_q, self._pin_v = smap.scalar_pin_q, smap.scalar_pin_v
            self._src_q, self._src_v = qsrc[smap.scalar_mj_q], vsrc[smap.scalar_mj_v]
            self._scratch = mujoco.MjData(model)
            self._twist = np.zeros(6)

    @staticmethod
    def body_name_of_site(robot: Robot, side: str) -> str:
        """The name of the body carrying ``robot``'s ``side`` contact site (in the controller's model)."""
        body = int(robot.mj_model.site_bodyid[robot.contact_site_ids[side]])
        return mujoco.mj_id2name(robot.mj_model, mujoco.mjtObj.mjOBJ_BODY, body) or f"body{body}"

    def _is_motor(self, actuator: int) -> bool:
        """Whether the plant's ``actuator`` applies ``gear * ctrl``: gain 1, no bias (not a servo)."""
        return not is_servo(self.model.actuator(actuator)) and self.model.actuator_gainprm[actuator, 0] == 1.0

    def _base_moves(self) -> bool:
        """True when joints between the world and the base body give it 6 degrees of freedom."""
        m, b, ndof = self.model, self.base_body_id, 0
        while b > 0:
            ndof += int(m.body_dofnum[b])
            b = int(m.body_parentid[b])
        return ndof >= 6

    def substeps(self, control_dt_s: float) -> int:
        """Plant steps per control tick of ``control_dt_s`` s: a whole number, or InputError."""
        dt_s = float(self.model.opt.timestep)
        n = int(round(control_dt_s / dt_s))
        if n < 1 or abs(control_dt_s / dt_s - n) > 1e-9:
            msg = f"the control period ({control_dt_s} s) must be a whole multiple of the plant step ({dt_s} s)"
            raise InputError(msg)
        return n

    # ----------------------------------------------------------------- data
    def new_data(self, keyframe: str | None = "stand") -> mujoco.MjData:
        """A fresh ``MjData``, set to the plant's keyframe ``keyframe`` if given (then forwarded)."""
        data = mujoco.MjData(self.model)
        if keyframe is not None:
            key_id = _id(self.model, mujoco.mjtObj.mjOBJ_KEY, keyframe)
            if key_id < 0:
                raise InputError(f"plant {self.name} has no keyframe named {keyframe!r}; add one to its MJCF")
            mujoco.mj_resetDataKeyframe(self.model, data, key_id)
            mujoco.mj_forward(self.model, data)
        return data

    def read_state(self, data: mujoco.MjData) -> tuple[np.ndarray, np.ndarray]:
        """The plant's state as the controller's Pinocchio ``(q, v)`` (new arrays; ``data`` is only read)."""
        if self._reader is not None:
            return self._reader(data.qpos, data.qvel)
        return self._read_body_base(data)

    def array_reader(self, data: mujoco.MjData) -> Callable[..., tuple[np.ndarray, np.ndarray, list[float]]]:
        """``f(qpos_list, qpos_sum=None)``: :meth:`read_state` of ``data`` now, and the base's row.

        The harness's per-tick read, with ``data``'s arrays bound once (MuJoCo keeps them across
        steps). ``qpos_list``: ``data.qpos.tolist()`` (the caller has it); ``qpos_sum``: its
        ``sum`` if the caller has it. Returns ``(q, v, root)``: ``root`` is ``q[pq:pq + 7] +
        v[pv:pv + 6]`` of the controller's first free joint as a list (``[]`` without one), as
        :meth:`~amlip_qp.robots.state_reader.StateReader.arrays`.
        """
        if self._reader is None:  # the base from the base body: the free joint is the root, at 0

            def read_body_base(qpos_list: list[float], qpos_sum: float | None = None):
                q, v = self._read_body_base(data)
                return q, v, q[:7].tolist() + v[:6].tolist()

            return read_body_base
        return self._reader.bind(data.qpos, data.qvel)

    def compiled_reader(self, data: mujoco.MjData) -> Callable[[], ReadResult] | None:
        """``f()``: :meth:`array_reader`'s read of ``data`` now as generated C (the same numbers; tested),
        with ``sum(qpos) + sum(qvel)``: :class:`~amlip_qp.sim.world.compiled_io.CompiledStateRead`.

        ``None`` where it does not apply (a base not floated by one free joint, a ball joint) or
        without a C compiler: the harness then reads with :meth:`array_reader`. A
        :class:`~amlip_qp.exceptions.CodegenError` (a compiler that fails) propagates.
        """
        plan = None if self._reader is None else self._reader.free_joint_plan
        if plan is None:
            return None
        try:
            return CompiledStateRead(plan, data).reader()
        except CompilerUnavailableError:
            return None

    def _read_body_base(self, data: mujoco.MjData) -> tuple[np.ndarray, np.ndarray]:
        """``(q, v)`` with the base from the base body's pose and twist (a base not floated by a free joint)."""
        m, s, b = self.model, self._scratch, self.base_body_id
        s.qpos[:] = data.qpos
        s.qvel[:] = data.qvel
        mujoco.mj_kinematics(m, s)  # the base body's pose at this qpos (data's may be a step old)
        mujoco.mj_comPos(m, s)
        mujoco.mj_comVel(m, s)
        mujoco.mj_objectVelocity(m, s, mujoco.mjtObj.mjOBJ_XBODY, b, self._twist, 1)  # (w, v), body frame
        robot = self.robot
        q = np.zeros(robot.nq)
        v = np.zeros(robot.nv)
        q[self._pin_q] = data.qpos[self._src_q]
        v[self._pin_v] = data.qvel[self._src_v]
        quat = s.xquat[b] / np.linalg.norm(s.xquat[b])
        q[:3] = s.xpos[b]
        q[3:6], q[6] = quat[1:], quat[0]  # xyzw
        v[:3], v[3:6] = self._twist[3:], self._twist[:3]
        return q, v

    def ctrl_from_tau(self, tau_Nm: np.ndarray) -> np.ndarray:
        """Actuator controls (controller order) for joint torques ``tau_Nm``: ``tau / gear``, clipped.

        The clip is ``minimum(maximum(.))`` in place: ``np.clip``'s values (NaN
        stays NaN) at a fraction of its call overhead, paid every tick.
        """
        ctrl = tau_Nm / self.gear
        np.maximum(ctrl, self._ctrl_lo, out=ctrl)
        return np.minimum(ctrl, self._ctrl_hi, out=ctrl)

    def ctrl_writer(self, data: mujoco.MjData, compiled: bool = False) -> Callable[[np.ndarray], None]:
        """``f(tau_Nm)``: :meth:`write_ctrl` into ``data`` (bound once; the same numbers, fewer NumPy calls).

        With the controller's actuators first in the plant's order, ``tau / gear`` and its clip
        are computed in place in ``data.ctrl``; with ``compiled``, as one call of generated C
        (:class:`~amlip_qp.sim.world.compiled_io.CompiledCtrlWrite`; the same numbers: tested) when a C
        compiler is available.
        """
        if not self._ctrl_prefix:
            return lambda tau_Nm: self.write_ctrl(data, tau_Nm)
        out, gear, lo, hi = data.ctrl[: self._nu], self.gear, self._ctrl_lo, self._ctrl_hi
        divide, maximum, minimum = np.divide, np.maximum, np.minimum

        def write(tau_Nm: np.ndarray) -> None:
            divide(tau_Nm, gear, out=out)
            maximum(out, lo, out=out)
            minimum(out, hi, out=out)

        if not compiled:
            return write
        try:
            return CompiledCtrlWrite(out, gear, lo, hi, write).writer()
        except CompilerUnavailableError:
            return write

    def apply_ctrl(self, data: mujoco.MjData, ctrl: np.ndarray) -> None:
        """Write controls in the controller's actuator order to the plant's actuators."""
        if self._ctrl_prefix:
            data.ctrl[: self._nu] = ctrl
        else:
            data.ctrl[self.actuator_ids] = ctrl

    def write_ctrl(self, data: mujoco.MjData, tau_Nm: np.ndarray) -> None:
        """``apply_ctrl(data, ctrl_from_tau(tau_Nm))``."""
        self.apply_ctrl(data, self.ctrl_from_tau(tau_Nm))

    def foot_normal_forces_N(self, data: mujoco.MjData, out: dict[str, float] | None = None) -> dict[str, float]:
        """Side -> normal force of the floor (world body) on that foot's body, N (summed over contacts)."""
        normal = dict.fromkeys(self.foot_body_ids, 0.0) if out is None else out
        m, pair_sides, ng, force6 = self.model, self._pair_sides.get, self._pair_stride, self._force6
        contact_force = mujoco.mj_contactForce
        for i, (g1, g2) in enumerate(data.contact.geom.tolist()):
            for side in pair_sides((g1 + 1) * ng + g2 + 1, ()):
                contact_force(m, data, i, force6)
                normal[side] += abs(force6[0])
        return normal

    def contact_switcher(self, data: mujoco.MjData, threshold_N: float) -> Callable[[], dict[str, bool]]:
        """``f()``: side -> ``foot_normal_forces_N(data)[side] > threshold_N`` now: the same switches, cheaper (tested).

        A side's sum stops once it is above the threshold: the terms are magnitudes, and a
        rounded sum of non-negative numbers never decreases, so the switch is already known.
        (A NaN force, which only a diverged simulation gives, would switch the full sum off.)
        ``data``'s contacts (a live view), the sides each geom pair adds to and the sums' lookups
        are bound once: the harness's per-tick switches. With the feet's contact sensors of
        :func:`~amlip_qp.sim.world.plant_loader.load_plant`, read from them
        (:func:`~amlip_qp.sim.world.contact_sensors.sensor_switcher`).
        """
        general = self._contact_switcher(data, threshold_N)
        return sensor_switcher(self.model, data, self.foot_body_ids, threshold_N, general) or general

    def _contact_switcher(self, data: mujoco.MjData, threshold_N: float) -> Callable[[], dict[str, bool]]:
        """:meth:`contact_switcher` contact by contact."""
        m, contacts, ng = self.model, data.contact, self._pair_stride
        pair_sides = self._pair_sides.get
        off, zero = dict.fromkeys(self.foot_body_ids, 0.0 > threshold_N), dict.fromkeys(self.foot_body_ids, 0.0)
        force6 = np.zeros(6)
        contact_force, normal_of = mujoco.mj_contactForce, force6.item  # item(0): a Python float

        def switches() -> dict[str, bool]:
            on, normal = off.copy(), zero.copy()  # no contact: zero sums
            i = 0
            for g1, g2 in contacts.geom.tolist():
                sides = pair_sides((g1 + 1) * ng + g2 + 1)
                if sides is not None:
                    for side in sides:
                        if not on[side]:
                            contact_force(m, data, i, force6)
                            f = normal[side] + abs(normal_of(0))
                            normal[side] = f
                            on[side] = f > threshold_N
                i += 1
            return on

        return switches
