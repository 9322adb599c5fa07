"""The whole-body task-space QP of the tracker: built here, solved elsewhere.

Decision variables ``x = [vdot, f_st, f_sw]`` (accelerations and contact
forces, :mod:`~amlip_qp.control.wbc.layout`); the springs held rigid have
their constraint forces eliminated and the torques are an affine map of ``x``
(:mod:`~amlip_qp.control.wbc.spring_elimination`).

:class:`WholeBodyQP` gathers a tick's inputs
(:func:`~amlip_qp.control.wbc.inputs.gather_inputs`), then iterates its
lists of constraint and cost objects
(:mod:`~amlip_qp.control.wbc.constraints`, :mod:`~amlip_qp.control.wbc.costs`),
each writing its own block of one preallocated
:class:`~amlip_qp.qp.problem.QPProblem`:

- equalities: the unactuated rows of the dynamics, the stance contact, the
  rigid springs;
- inequalities: torque limits (the stance foot motor's bound included), the
  friction pyramids;
- boxes: swing-leg joint limits, contact force boxes with the swing foot's
  force ramp;
- cost: the output task (every output of ``h_0``), a low-weight posture task
  on the actuated joints and a damping task on the passive springs
  (:mod:`~amlip_qp.control.wbc.tasks`), small regularisations of ``vdot``,
  forces, torques and rigid-spring forces, and the stance yaw moment.

:class:`~amlip_qp.control.wbc.compiled.CompiledBuild` fills the same problem
from generated C made from the same lists.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from amlip_qp.control.wbc import constraints as K
from amlip_qp.control.wbc import costs as W
from amlip_qp.control.wbc.config import QPConfig, default_config
from amlip_qp.control.wbc.inputs import PelvisYawFeedback, TickInputs, gather_inputs
from amlip_qp.control.wbc.layout import VariableLayout
from amlip_qp.control.wbc.spring_elimination import LegSprings, ReducedDynamics, SpringElimination, springs_per_leg
from amlip_qp.control.wbc.tasks import Gains, JointTask, OutputTask
from amlip_qp.exceptions import InputError
from amlip_qp.qp.problem import QPProblem
from amlip_qp.robots.outputs import OutputMap

_sum = np.add.reduce

if TYPE_CHECKING:
    from amlip_qp.control.tracker import TrackingTarget
    from amlip_qp.robots.kinematics import RobotKinematics
    from amlip_qp.robots.robot import Robot


class WholeBodyQP:
    """Builds the tracker QP (see the module doc) into preallocated arrays.

    :meth:`build` refills and returns the same :class:`QPProblem` each tick
    (call :meth:`QPProblem.copy` to keep one): blocks that never change are
    written once here, so edit the returned problem only on a copy, or the
    edits persist into later ticks. After a build, :meth:`torques` and
    :meth:`forces` map a solution back to joint torques and contact forces.

    Args:
        robot: The robot.
        config: The :class:`QPConfig` (default: :func:`default_config`).
        leg_springs: Per side, the springs the QP may hold rigid (default:
            :meth:`LegSprings.of_robot <amlip_qp.control.wbc.spring_elimination.LegSprings.of_robot>`).

    Attributes:
        layout: The :class:`VariableLayout`.
        tasks: Output, posture and (with ``spring_weight > 0``) spring-damping tasks.
        inputs: The :class:`TickInputs` of the last build (the in-place build,
            :class:`~amlip_qp.control.wbc.compiled_in_place.InPlaceBuild`, sets only its ``swing_force_weight``).
        dynamics: The :class:`ReducedDynamics` of the last build (torque map ``T, tau0``).
        constraints: The constraint objects, in the order of their rows.
        costs: The cost objects.
        constant_cost: The folded constant part of the cost.
        problem: The problem the builds fill.

    Raises:
        InputError: Gains for another number of outputs, unsupported feet, or springs that cannot be held rigid.
    """

    def __init__(self, robot: Robot, config: QPConfig | None = None, leg_springs: dict[str, LegSprings] | None = None):
        self.robot = robot
        self.config = config = config or default_config(robot)
        outputs = OutputMap(robot)
        if len(config.output_kp) != outputs.size:
            raise InputError(
                f"QPConfig has gains for {len(config.output_kp)} outputs but {robot.name} has {outputs.size}: "
                "use default_config(robot) or a config made for this robot"
            )
        leg_springs = LegSprings.of_robot(robot) if leg_springs is None else leg_springs
        n_r, mode = springs_per_leg(leg_springs), config.rigid_springs
        L = self.layout = VariableLayout.for_robot(robot, n_r if mode == "all" else 0, 0 if mode == "none" else n_r)
        self.output_task = OutputTask(Gains.of(outputs.size, config.output_kp, config.output_kd, config.output_weight))
        self.posture_task, self.spring_task = _joint_tasks(robot, config)
        self.tasks = [t for t in (self.output_task, self.posture_task, self.spring_task) if t is not None]
        elimination = SpringElimination(robot, L, config, leg_springs)
        self.dynamics = ReducedDynamics(elimination)
        self.inputs = TickInputs(robot, L, config, self.output_task, outputs.names)

        self.constraints: list[K.Constraint] = [
            K.DynamicsRows(elimination.n_dyn), K.StanceContact(L, config.contact_kd), K.RigidSprings(L, elimination),
            K.TorqueLimits(robot, config), K.FrictionPyramid(L, config.friction_mu),
            K.JointLimits(robot, L, config), K.ForceBox(L, config),
        ]  # fmt: skip
        ends = {"eq": 0, "in": 0}
        for c in self.constraints:
            if c.kind in ends:
                ends[c.kind] = c.place(ends[c.kind])
        n, n_eq, n_in, inf = L.n, ends["eq"], ends["in"], np.inf
        # One set of buffers for the whole run (QPProblem.allocate: a cheap validation per tick).
        self.problem = P = QPProblem.allocate(
            n, n_eq, n_in,
            variables={"vdot": L.sl_vdot, "forces_stance": L.sl_f_st, "forces_swing": L.sl_f_sw},
            eq_rows=[b for c in self.constraints if c.kind == "eq" for b in c.row_blocks()],
            in_rows=[b for c in self.constraints if c.kind == "in" for b in c.row_blocks()],
        )  # fmt: skip
        P.l[:], P.lb[:], P.ub[:] = -inf, -inf, inf
        for c in self.constraints:
            c.initialize(self.problem)

        self.costs: list[W.Cost] = [
            W.Regularization(L, config.reg_vdot, config.reg_force),
            W.OutputTaskCost(L, self.output_task),
            *(W.JointTaskCost(L, t) for t in (self.posture_task, self.spring_task) if t is not None),
            W.TorqueRegularization(elimination.act_v.size, config.reg_torque),
            W.RigidSpringForceRegularization(L.n_lambda, config.reg_coupling),
        ]
        if W.StanceYawMomentCost.applies(L, config.stance_yaw_moment_weight):
            self.costs.append(W.StanceYawMomentCost(L, config.stance_yaw_moment_weight))
        self.constant_cost = W.ConstantCost(n, L.nv, robot.nq)
        rows = 0
        for cost in self.costs:
            cost.fold(self.constant_cost)
            rows = cost.place(rows)
        # The stacked per-tick least-squares rows ||E x + e||^2.
        self._E = np.zeros((rows, n))
        self._e = np.zeros(rows)
        self._EtE = np.zeros((n, n))
        # The normal components of each foot's points, as strided slices of x (views, no gather).
        d = L.point_dim
        self._normal = tuple(slice(foot.start + d - 1, foot.stop, d) for foot in (L.sl_f_st, L.sl_f_sw))
        # 1 to 7 points a foot: NumPy's sum of so few numbers is the sequential sum from 0 (its pairwise
        # summation starts at 8; tested), which Python's sum of the same floats repeats bit for bit
        points = [len(range(*sl.indices(L.n))) for sl in self._normal]
        self._normal_sum_in_python = all(1 <= k < 8 for k in points)

    # ------------------------------------------------------------------ info
    @property
    def n_variables(self) -> int:
        """Number of decision variables."""
        return self.layout.n

    @property
    def feedback(self) -> PelvisYawFeedback | None:
        """The pelvis-yaw feedback on the swing hip-yaw reference, or ``None`` (off, or no hip-yaw outputs)."""
        return self.inputs.feedback

    def reset(self) -> None:
        """Nothing to forget between runs (the builder is stateless across ticks)."""

    def constraint(self, name: str) -> K.Constraint:
        """The constraint object called ``name``."""
        for c in self.constraints:
            if c.name == name:
                return c
        raise InputError(f"no constraint {name!r}; known: {', '.join(c.name for c in self.constraints)}")

    # ------------------------------------------------------------------ build
    def build(self, kin: RobotKinematics, target: TrackingTarget) -> QPProblem:
        """Fill the problem for the state in ``kin`` (updated this tick) and the references in ``target``."""
        inputs = gather_inputs(kin, target, self.inputs)
        P, dyn = self.problem, self.dynamics
        dyn.update(inputs)
        for c in self.constraints:
            c.write(inputs, dyn, P)
        # Cost: the constant Hessian, the constant tasks' affine gradient, the
        # stacked rows, then the direct Hessian terms.
        H, g, sv, cc = P.H, P.g, self.layout.sl_vdot, self.constant_cost
        np.copyto(H, cc.H0)
        g.fill(0.0)
        gv = np.matmul(cc.Kq, inputs.q, out=g[sv])
        gv += cc.Kv @ inputs.v
        gv += cc.k0
        E, e = self._E, self._e
        for cost in self.costs:
            if cost.size:
                cost.write(inputs, dyn, E[cost.rows], e[cost.rows])
        H += np.matmul(E.T, E, out=self._EtE)
        g += E.T @ e
        for cost in self.costs:
            cost.add_to_hessian(inputs, H)
        return P

    # ------------------------------------------------------------ recovery
    def torques(self, x: np.ndarray) -> np.ndarray:
        """Joint torques (N m, actuator order) of a solution of the last built problem."""
        return self.dynamics.torques(x)

    def forces(self, x: np.ndarray) -> dict[str, np.ndarray]:
        """Contact point forces (N) of a solution: ``{"stance": (k, d), "swing": (k, d)}`` (axes x,y,z or x,z)."""
        L = self.layout
        return {"stance": x[L.sl_f_st].reshape(-1, L.point_dim), "swing": x[L.sl_f_sw].reshape(-1, L.point_dim)}

    def normal_force_totals(self, x: np.ndarray) -> tuple[float, float]:
        """Total normal (vertical) force of the stance and of the swing foot in a solution, N."""
        st, sw = self._normal
        if self._normal_sum_in_python and type(x) is np.ndarray and x.dtype == np.float64 and x.ndim == 1:
            xs = x.tolist()  # one conversion, then Python floats (the same sums, see the constructor)
            return sum(xs[st]), sum(xs[sw])
        return float(_sum(x[st])), float(_sum(x[sw]))

    def rigid_forces(self, x: np.ndarray) -> np.ndarray:
        """The rigid-spring constraint forces ``lambda`` (N m) of a solution; shape (0,) when none is held rigid."""
        return self.dynamics.rigid_forces(x)

    def generalized_contact_force(self, x: np.ndarray) -> np.ndarray:
        """``J_f^T f + G^T lambda`` (nv,) of a solution of the last built problem (for checks).

        Reads :attr:`inputs`' ``Jf``: after a Python build or the compiled build that gathers its inputs
        (:class:`~amlip_qp.control.wbc.compiled.CompiledBuild`), not after the in-place build
        (:class:`~amlip_qp.control.wbc.compiled_in_place.InPlaceBuild`), which leaves it.
        """
        out = self.inputs.Jf.T @ x[self.layout.sl_forces]
        if self.layout.n_lambda:
            out = out + self.dynamics.G.T @ self.rigid_forces(x)
        return out


def _joint_tasks(robot: Robot, config: QPConfig) -> tuple[JointTask, JointTask | None]:
    """The posture task (actuated joints toward ``robot.q_stand``; the joints outside both legs
    with the ``upper_posture_*`` gains when set) and the passive-spring damping task (``None``
    without passive joints or weight)."""
    nv = robot.nv
    act_v = np.asarray(robot.actuated.pin_v_idx, dtype=int)
    act_q = np.asarray(robot.actuated.pin_q_idx, dtype=int)
    pv, pq = np.asarray(robot.passive_v_idx, dtype=int), np.asarray(robot.passive_q_idx, dtype=int)
    qmap = dict(zip(act_v.tolist(), act_q.tolist()))
    qmap.update(zip(pv.tolist(), pq.tolist()))
    nu = act_v.size
    sel = np.zeros((nu, nv))
    sel[np.arange(nu), act_v] = 1.0
    legs = {name for side in robot.foot_sides for name in robot.leg_joint_names.get(side, ())}
    upper = np.array([name not in legs for name in robot.actuated.joint_names], dtype=bool)
    per_joint = []
    for value, upper_value in (
        (config.posture_kp, config.upper_posture_kp),
        (config.posture_kd, config.upper_posture_kd),
        (config.posture_weight, config.upper_posture_weight),
    ):
        arr = np.full(nu, value)
        if upper_value is not None:
            arr[upper] = upper_value
        per_joint.append(arr)
    gains = Gains.of(nu, *per_joint)
    posture = JointTask("posture", sel, qmap, robot.q_stand[act_q], gains)
    if not (pv.size and config.spring_weight > 0):
        return posture, None
    rows = np.zeros((pv.size, nv))
    rows[np.arange(pv.size), pv] = 1.0
    gains = Gains.of(pv.size, 0.0, config.spring_kd, config.spring_weight)
    return posture, JointTask("springs", rows, qmap, robot.q_stand[pq], gains)
