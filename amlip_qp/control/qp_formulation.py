"""The whole-body task-space QP of the tracker: built here, solved elsewhere.

Decision variables ``x = [vdot, f_st, f_sw]``:

- ``vdot`` (nv): generalized accelerations (Pinocchio ``v`` coordinates),
  m/s^2 and rad/s^2;
- ``f_st``, ``f_sw``: world-frame contact point forces of the **stance** and
  **swing** foot, N. Cassie: toe then heel sphere centre, 3-D each (6 per
  foot); Rabbit (planar): the point foot, ``(f_x, f_z)`` (2 per foot). The
  stance foot's block always comes first, so the dimensions never change
  and one persistent ProxQP serves the whole walk.

Springs held rigid (Cassie): per leg the knee-tarsus coupling (the achilles
tendon) and the shin spring can be held rigid by constraint forces
``lambda`` (N m). With ``rigid_springs="swing"`` only the swing leg's springs
are held rigid, as in the paper (section "Springs": the swing-leg deflection
is small, the leg is treated as rigid), and the stance leg keeps its exact
spring model (the tendon and shin springs in ``taup``), which the closed
chain through the ground makes controllable. ``"all"`` (the default)
holds both legs rigid, ``"none"`` keeps every spring as a spring. Rigid is not
what the plant does: the swing leg's spring modes are not controllable by an
instantaneous QP (the QP cannot change this tick's spring torque and fights
the 25 Hz tarsus mode with large accelerations); holding them rigid toward
zero deflection matches what the unloaded spring does anyway.

``lambda`` is not a decision variable: the held springs act on as many
passive joints as there are held springs (Cassie: per leg the shin and the
tarsus for the shin spring and the tendon), so those joints' rows of the
dynamics, ``(D x + h - taup)_P = G_P^T lambda``,
determine it: ``lambda = G_P^-T (D_P x + (h - taup)_P)``, an affine map of
``x`` (:meth:`WholeBodyQP.rigid_forces`). Substituting it into the other rows
(``G^T lambda`` also acts on the knee) removes ``lambda`` and the P rows from
the problem, an exact elimination that makes the QP smaller: the warm
ProxQP solve took about 20 % less time (1200 recorded Cassie problems,
83 -> 65 µs median; in the closed loop 108 -> 91 µs).

Torques are not variables; they are recovered from the actuated rows,
``tau = M_a vdot + h_a - taup_a - J_a^T f - G_a^T lambda`` (N m), an affine map
``tau = T x + tau0`` that :meth:`WholeBodyQP.torques` evaluates.

Equalities:

- ``dynamics``: the unactuated rows (floating base and the passive joints of
  legs whose springs are not held rigid) of
  ``M vdot + h - taup = S^T tau + J^T f + G^T lambda`` with the spring,
  tendon and damping torques in ``taup``
  (:meth:`RobotKinematics.passive_forces`) and ``lambda`` substituted;
- ``contact``: the stance foot does not accelerate,
  ``J_c vdot + Jdot_c v = -K_c J_c v`` (velocity Baumgarte term ``K_c``).
  Cassie's blade uses 5 independent rows: the toe's 3 and the heel's 2
  components orthogonal to the toe-heel axis (the third is implied by the
  rigid foot, and dropping it keeps the rows independent for active-set
  solvers);
- ``rigid_stance`` / ``rigid_swing``: ``G vdot + Gdot v = -K_p g - K_d G v``
  with ``g`` the spring deflections (tendon length minus its rest length,
  shin angle minus its spring reference), rad.

Inequalities (rows of ``C``): ``torque`` limits (from
``robot.actuated.torque_limit_Nm``) and the ``friction`` pyramid (4 rows per
3-D point, 2 per planar point) on every force point. Box bounds: the normal
force of the stance points in ``[f_min, f_max]``; swing points bounded to
zero in the air, relaxed with the **force ramp** ``w = max(touchdown_blend *
swing_contact_weight, liftoff ramp)``: ``0 <= f_z <= w f_max`` and
``|f_t| <= mu w f_max``; while ``w = 0`` the swing
foot's pyramid rows are lifted (``u = +inf``), being implied by that box. The
liftoff ramp ``1 - s / liftoff_phase`` lets the previous stance foot unload
smoothly during the first ``liftoff_phase`` of a step. Actuated joint
accelerations of the **swing leg** are bounded so the joint stops inside its
range within the horizon ``joint_limit_horizon_s`` (position and velocity
margins). The stance leg's joints are tied to the base by the contact rows;
bounding them as well made the problem infeasible near a straight stance
knee (measured on Cassie), so they are left to the output tasks.

Cost: ``sum_tasks ||W^(1/2)(J vdot + Jdot v - ydd_des)||^2`` over the output
task (every output of ``h_0``), a low-weight posture task on the actuated
joints and a damping task on the passive springs, plus small regularisation
of ``vdot``, forces, torques and the rigid-spring forces ``lambda``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from amlip_qp.control.tasks import Gains, JointTask, OutputTask
from amlip_qp.exceptions import InputError
from amlip_qp.qp.problem import QPProblem
from amlip_qp.robots.outputs import OutputMap


@dataclass(frozen=True)
class QPConfig:
    """Weights, gains and limits of the whole-body QP (SI units).

    Attributes:
        output_kp: Output PD proportional gains, 1/s^2, one per output of h_0.
        output_kd: Output PD derivative gains, 1/s, one per output.
        output_weight: Output tracking weights, (m/s^2)^-2 or (rad/s^2)^-2.
        posture_kp: Posture task (actuated joints toward ``robot.q_stand``) kp, 1/s^2.
        posture_kd: Posture task kd, 1/s.
        posture_weight: Posture task weight (keep small: a null-space regulariser).
        spring_kd: Damping gain of the passive-spring task, 1/s.
        spring_weight: Weight of the passive-spring damping task (0 disables).
        friction_mu: Friction coefficient of the pyramid (below the plant's 1.0).
        min_normal_force_N: Least normal force on each stance force point, N.
        max_normal_force_N: Largest normal force on each force point, N.
        liftoff_phase: Phase over which the previous stance foot unloads.
        touchdown_blend: Gain (0 to 1, dimensionless) on the controller's
            pre-touchdown ramp ``target.swing_contact_weight`` (0 until phase
            0.9, then up to 1 at the step's end) in the swing foot's force
            box ``w = max(touchdown_blend * swing_contact_weight, liftoff
            ramp)``. 0 (default) keeps them at zero until the touchdown
            switches the stance, after which the liftoff ramp unloads the old
            stance foot; 1 blends the landing foot's forces in before the
            touchdown is detected. Forces planned on a foot still in the air
            do not happen, so the support they stand for is missing and the
            CoM drops before the touchdown (see ``CASSIE_CONFIG`` and
            ``RABBIT_CONFIG``).
        contact_kd: Velocity Baumgarte gain of the stance contact rows, 1/s.
        rigid_springs: Which legs' springs (tendon coupling, passive spring
            joints) the QP holds rigid with constraint forces: ``"swing"``,
            ``"all"`` or ``"none"`` (see the module docstring).
        coupling_kp: Swing leg: stiffness of the rigid-spring constraint toward
            zero deflection (what the unloaded spring does), 1/s^2.
        coupling_kd: Swing leg: damping of the rigid-spring constraint, 1/s.
        stance_coupling_kp: Stance leg (``"all"``): stiffness toward zero
            deflection, 1/s^2. Default 0: the loaded spring keeps its
            deflection (the constraint only damps its rate), so the constraint
            force stays small instead of fighting the spring's static load.
        stance_coupling_kd: Stance leg: damping of the deflection rate, 1/s.
        joint_limit_horizon_s: Horizon of the joint-limit acceleration bounds, s.
        joint_limit_max_recovery: Cap on the acceleration the bounds may force
            (to stay feasible with the torque limits), rad/s^2.
        reg_vdot: Regularisation weight on ``vdot``, (rad/s^2)^-2.
        reg_force: Regularisation weight on forces, N^-2.
        reg_torque: Regularisation weight on joint torques, (N m)^-2.
        reg_coupling: Regularisation weight on the rigid-spring forces
            ``lambda`` (tendon and shin; eliminated, penalised through
            ``Lam x + lam0``), (N m)^-2.
        stance_foot_torque_max_Nm: Bound on the **stance** foot ("toe") motor
            torque, N m (``inf``: only the motor limit). 0 leaves the stance toe
            passive as in the paper (section "Implementing ... on a Real
            Robot"): an ankle torque changes ``L`` about the contact directly
            (``Ldot = p x m g + tau_ankle``), which the ALIP prediction ignores,
            and it shifts the centre of pressure off the blade's middle,
            unloading the toe or the heel (the foot then slips in yaw).
            Applied by :meth:`WholeBodyQP.limit_stance_foot_torque` after
            :meth:`WholeBodyQP.build`. No effect on robots without a foot motor.
        stance_yaw_moment_weight: Cost weight on the yaw moment (about the
            vertical) of the stance foot's contact forces, (N m)^-2. The plant's
            line contact (two friction spheres) yields to a sustained yaw
            moment: the foot creeps in yaw and the robot turns. The moment is
            fixed by the accelerations, so the penalty makes the QP prefer
            motions that need less of it (the pelvis yields in stance hip yaw).
            0 disables. Added by :meth:`WholeBodyQP.add_stance_yaw_moment_cost`
            after :meth:`WholeBodyQP.build`. 3-D feet with two force points only.
        hip_yaw_feedback: Gain (dimensionless, 0 disables) of the pelvis-yaw
            feedback on the swing hip-yaw reference (beyond the paper, whose
            hip-yaw references are open-loop straight lines). Both hip-yaw
            outputs are joint angles, so yaw the stance foot creeps in the plant
            carries over to the pelvis and then to every later step. With the
            feedback the swing hip-yaw reference becomes
            ``h_d[swing_hip_yaw] - k e_psi``, with ``e_psi = wrap(psi_pelvis -
            (D_k - h_d[stance_hip_yaw]))`` the pelvis yaw error against its
            nominal value, and its rate reference
            ``dh_d[swing_hip_yaw] - k (psidot_pelvis + dh_d[stance_hip_yaw])``:
            the swing foot lands along ``D_{k+1}`` (world yaw) whatever the
            pelvis yaw error, and the next stance's hip-yaw line returns the
            pelvis to the heading. Applied by :meth:`WholeBodyQP.build`;
            robots without hip-yaw outputs ignore it.
    """

    output_kp: tuple[float, ...]
    output_kd: tuple[float, ...]
    output_weight: tuple[float, ...]
    posture_kp: float = 20.0
    posture_kd: float = 8.0
    posture_weight: float = 1e-2
    spring_kd: float = 40.0
    spring_weight: float = 0.0
    friction_mu: float = 0.7
    min_normal_force_N: float = 5.0
    max_normal_force_N: float = 1500.0
    liftoff_phase: float = 0.08
    touchdown_blend: float = 0.0
    contact_kd: float = 10.0
    rigid_springs: str = "all"
    coupling_kp: float = 400.0
    coupling_kd: float = 40.0
    stance_coupling_kp: float = 0.0
    stance_coupling_kd: float = 40.0
    joint_limit_horizon_s: float = 0.05
    joint_limit_max_recovery: float = 200.0
    reg_vdot: float = 1e-6
    reg_force: float = 1e-6
    reg_torque: float = 1e-6
    reg_coupling: float = 1e-6
    stance_foot_torque_max_Nm: float = math.inf
    stance_yaw_moment_weight: float = 0.0
    hip_yaw_feedback: float = 0.0

    def __post_init__(self):
        if self.rigid_springs not in ("swing", "all", "none"):
            raise InputError(f"rigid_springs must be 'swing', 'all' or 'none', got {self.rigid_springs!r}")
        n = len(self.output_kp)
        if len(self.output_kd) != n or len(self.output_weight) != n:
            raise InputError("output_kp, output_kd and output_weight need one entry per output")
        scalars = {k: getattr(self, k) for k in self.__dataclass_fields__ if k not in ("rigid_springs",)}
        for name, val in scalars.items():
            arr = np.asarray(val, dtype=float)
            may_be_inf = name == "stance_foot_torque_max_Nm"
            if np.any(np.isnan(arr)) or np.any(arr < 0) or (not may_be_inf and not np.all(np.isfinite(arr))):
                raise InputError(f"QPConfig.{name} must be finite and >= 0, got {val!r}")
        if not 0 < self.friction_mu:
            raise InputError("friction_mu must be > 0")
        if self.min_normal_force_N > self.max_normal_force_N:
            raise InputError("min_normal_force_N must not exceed max_normal_force_N")
        if self.touchdown_blend > 1.0:
            raise InputError(f"touchdown_blend must be in [0, 1], got {self.touchdown_blend!r}")
        if self.joint_limit_horizon_s <= 0:
            raise InputError("joint_limit_horizon_s must be > 0 s")

    def with_(self, **changes) -> "QPConfig":
        """A copy with some fields changed."""
        return replace(self, **changes)


#: Cassie outputs: torso pitch, roll, stance/swing hip yaw, com z over stance,
#: com x/y/z over swing, swing toe pitch.
CASSIE_CONFIG = QPConfig(
    output_kp=(400.0, 400.0, 200.0, 200.0, 400.0, 400.0, 400.0, 400.0, 200.0),
    output_kd=(40.0, 40.0, 25.0, 25.0, 40.0, 40.0, 40.0, 40.0, 25.0),
    output_weight=(10.0, 10.0, 1.0, 1.0, 10.0, 3.0, 3.0, 3.0, 0.5),
    spring_weight=1e-2,
    # The paper's passive stance toe. With the toe motor free (+-45 N m) the QP
    # used it (mean |tau| 16 N m in place, saturated 6% of the ticks), moving
    # the centre of pressure along the blade; the stance foot then slipped in
    # yaw: 172 deg in 20 s walking in place (passive: 4.5 deg). A 0.01 N m band
    # rather than exactly 0: l = u torque rows are degenerate for active-set
    # solvers (quadprog, the cross-check, failed on 9 of 32 recorded problems).
    stance_foot_torque_max_Nm=0.01,
    # Without it the stance foot creeps in yaw at speed (the base yawed 30-60
    # deg) and the 0 -> 2.1 m/s ramp fell at 12.05 s (1.71 m/s). Measured on
    # that ramp: weight 1 held 2.04 m/s once and fell once (14.88 s); weight 3
    # held it in 3 of 3 runs (2.07, 2.06, 2.00 m/s); weight 10 fell (12.35 s).
    stance_yaw_moment_weight=3.0,
    # The stance leg's spring-rate damping. At the default 40 1/s the stance
    # foot bounced at ~17 Hz (plant normal force swinging 0-1000 N while the QP
    # planned ~300 N; toe or heel unloaded in 18% of mid-stance ticks over
    # 0-5 s at 2.5 m/s). Unloaded fraction against this gain: 0 -> 0.57,
    # 40 -> 0.18, 80 -> 0.03, 150 -> 0.005, 300 -> 0.03, 600 -> 0.20.
    stance_coupling_kd=150.0,
    # The planned forces sat on the 0.7 pyramid in 80-90% of the ticks at
    # 2.5 m/s; 0.9 is still inside the plant's 1.0.
    friction_mu=0.9,
    # Pelvis-yaw feedback (see QPConfig): without it the pelvis yawed -62 deg
    # in 20 s walking in place and the 2.5 m/s run fell at 14.2 s after
    # yawing ~90 deg; with it, 1.5 deg in place and no fall.
    hip_yaw_feedback=1.0,
    # No forces on the landing foot before its touchdown is detected (as on
    # Rabbit). With the blend (1.0) the CoM dropped before each touchdown
    # (v_z -0.053 m/s at 1 m/s, -0.156 m/s at 2.5 m/s), the foot landed early
    # (phase 0.953 against 0.996) and the momentum transfer lost speed: at
    # 2.5 m/s the integral speed correction sat at its 0.3 m/s bound and the
    # robot reached 2.436 m/s (now 0.05 m/s and 2.519 m/s). amlip-qp compare,
    # Cassie QP, blend 1 -> 0: foot placement error 0.014 -> 0.011 m, output
    # tracking rms 0.0254 -> 0.0221, torque peak 195.2 (the knee limit) ->
    # 139.3 N m, torque rms 26.2 -> 23.6 N m, velocity error, ramp and pushes
    # unchanged. The end-of-step L error grows, 1.00 -> 1.92 kg m^2/s: a
    # steady offset of the sagittal L (-0.67 kg m^2/s, std 0.05, at an exact
    # 1.001 m/s) and a smaller lateral sway than planned (+-1.05 kg m^2/s by
    # stance side); with the blend the errors were 0.09 and -0.05 kg m^2/s
    # on average (std 0.35 each). 0.3 and 0.6 lie in between.
    touchdown_blend=0.0,
)
#: Rabbit outputs: torso pitch, com z over stance, com x/z over swing.
RABBIT_CONFIG = QPConfig(
    output_kp=(400.0, 400.0, 400.0, 400.0),
    output_kd=(40.0, 40.0, 40.0, 40.0),
    output_weight=(10.0, 10.0, 3.0, 3.0),
    posture_weight=1e-4,
    min_normal_force_N=10.0,
    # No forces on the point foot before its touchdown is detected. With the
    # blend (1.0) the QP planned 70 % (up to 81 %) of the normal force on the
    # airborne foot over the last 10 % of the step at 1 m/s; the CoM fell at
    # 0.12 m/s at touchdown, and the momentum transfer lost the speed: the
    # integral speed correction saturated at +0.3 m/s and the robot still
    # walked at 0.964 m/s, L end-of-step error rms 6.95 kg m^2/s. With 0: CoM v_z -0.011 m/s at
    # touchdown, correction 0.077 m/s, 0.997 m/s, L error 1.19 kg m^2/s; the
    # 1.5 m/s ramp held 1.26 m/s (0.00 within 10 % of the command before).
    touchdown_blend=0.0,
)


def default_config(robot) -> QPConfig:
    """The documented default :class:`QPConfig` for ``robot`` (Cassie layout or planar)."""
    if robot.is_planar:
        return RABBIT_CONFIG
    return CASSIE_CONFIG


@dataclass
class _Layout:
    """Variable slices and sizes (``n_rigid_*``: springs held rigid per leg, no variables)."""

    nv: int
    point_dim: int
    n_points: int  # per foot
    n_rigid_st: int
    n_rigid_sw: int
    sl_vdot: slice = field(init=False)
    sl_f_st: slice = field(init=False)
    sl_f_sw: slice = field(init=False)
    n: int = field(init=False)

    def __post_init__(self):
        nf = self.point_dim * self.n_points
        self.sl_vdot = slice(0, self.nv)
        self.sl_f_st = slice(self.nv, self.nv + nf)
        self.sl_f_sw = slice(self.nv + nf, self.nv + 2 * nf)
        self.n = self.sl_f_sw.stop

    @property
    def n_lambda(self) -> int:
        """Number of rigid-spring constraint forces (eliminated, see the module docstring)."""
        return self.n_rigid_st + self.n_rigid_sw


@dataclass(frozen=True)
class _StanceRows:
    """Per stance: the row map of the dynamics and the springs held rigid.

    With ``D = [M | -Jf^T]`` and ``hp = h - taup``, ``R @ D`` stacks the
    dynamics equalities' matrix (its kept unactuated rows, rigid-spring forces
    substituted), the torque map ``T`` and ``Lam`` (``lambda = Lam x +
    lam0``); ``R @ hp`` stacks ``-b_dyn``, ``tau0`` and ``lam0``. Without
    rigid springs ``R`` only selects rows.
    """

    R: np.ndarray  # (n_dyn + nu + n_lambda, nv)
    G: np.ndarray  # (n_lambda, nv) rigid-spring rows: G vdot = -kp g - kd G v
    kpGq: np.ndarray  # kp * (q-coefficients of the deflections), (n_lambda, nq)
    kdG: np.ndarray  # kd * G
    kp_offs: np.ndarray  # kp * rest offsets


class WholeBodyQP:
    """Builds the tracker QP (see the module docstring) into preallocated arrays.

    :meth:`build` refills and returns the same :class:`QPProblem` each tick
    (call :meth:`QPProblem.copy` to keep one). After a build, :meth:`torques`
    and :meth:`forces` map a solution back to joint torques and contact forces.

    Args:
        robot: The :class:`~amlip_qp.robots.robot.Robot`.
        config: The :class:`QPConfig` (default: :func:`default_config`).
    """

    def __init__(self, robot, config: QPConfig | None = None):
        self.robot = robot
        self.config = config = config or default_config(robot)
        nv = robot.nv
        self._planar = bool(robot.is_planar)
        self._axes = np.array([0, 2]) if self._planar else np.array([0, 1, 2])
        #: The same as an index that avoids a fancy-indexing copy in 3-D.
        self._axes_index = self._axes if self._planar else slice(0, 3)
        n_points = {len(robot.force_frame_ids[s]) for s in robot.foot_sides}
        if len(n_points) != 1 or n_points == {0}:
            raise InputError("both feet need the same (nonzero) number of force points")
        k = n_points.pop()
        if k > 2 or (k == 2 and self._planar):
            raise InputError("supported feet: one point (3-D or planar) or a 3-D blade of two points")
        # Per leg, the springs the QP can hold rigid: its couplings and its
        # passive joints with a spring. Deflection g = Gq q - rest, rate G v.
        self._leg_springs: dict[str, tuple[np.ndarray, np.ndarray, np.ndarray]] = {}
        for side in robot.foot_sides:
            rows = [r for r in robot.springs if r.side == side and (r.kind == "coupling" or r.stiffness > 0)]
            self._leg_springs[side] = (
                np.array([r.row_v(nv) for r in rows]).reshape(len(rows), nv),
                np.array([r.row_q(robot.nq) for r in rows]).reshape(len(rows), robot.nq),
                np.array([r.rest for r in rows], dtype=float),
            )
        n_r = {len(self._leg_springs[s][0]) for s in robot.foot_sides}
        if len(n_r) != 1:
            raise InputError("both legs need the same number of springs/couplings")
        n_r = n_r.pop()
        mode = config.rigid_springs
        L = self._layout = _Layout(nv, len(self._axes), k, n_r if mode == "all" else 0, 0 if mode == "none" else n_r)
        n_lambda = L.n_lambda
        n_out = OutputMap(robot).size
        if len(config.output_kp) != n_out:
            raise InputError(
                f"QPConfig has gains for {len(config.output_kp)} outputs but {robot.name} has {n_out}: "
                "use default_config(robot) or a config made for this robot"
            )
        self.output_task = OutputTask(Gains.of(n_out, config.output_kp, config.output_kd, config.output_weight))
        self._act_v = np.asarray(robot.actuated.pin_v_idx, dtype=int)
        self._act_q = np.asarray(robot.actuated.pin_q_idx, dtype=int)
        self._unact_v = np.setdiff1d(np.arange(nv), self._act_v)
        nu = len(self._act_v)
        qmap = dict(zip(self._act_v.tolist(), self._act_q.tolist()))
        qmap.update(zip(np.asarray(robot.passive_v_idx, int).tolist(), np.asarray(robot.passive_q_idx, int).tolist()))
        sel = np.zeros((nu, nv))
        sel[np.arange(nu), self._act_v] = 1.0
        self.posture_task = JointTask(
            "posture", sel, qmap, robot.q_stand[self._act_q],
            Gains.of(nu, config.posture_kp, config.posture_kd, config.posture_weight),
        )  # fmt: skip
        self.spring_task = None
        pv = np.asarray(robot.passive_v_idx, dtype=int)
        if pv.size and config.spring_weight > 0:
            rows = np.zeros((pv.size, nv))
            rows[np.arange(pv.size), pv] = 1.0
            ref = robot.q_stand[np.asarray(robot.passive_q_idx, int)]
            self.spring_task = JointTask("springs", rows, qmap, ref, Gains.of(pv.size, 0.0, config.spring_kd, config.spring_weight))
        self.tasks = [t for t in (self.output_task, self.posture_task, self.spring_task) if t is not None]

        # Rows: the dynamics equalities are the unactuated rows less the
        # n_lambda passive rows that determine the rigid-spring forces.
        n_dyn = self._unact_v.size - n_lambda
        n_contact = len(self._axes) if k == 1 else 5
        n_eq = n_dyn + n_contact + n_lambda
        n_fric_per_point = 2 * (len(self._axes) - 1)
        n_fric = n_fric_per_point * 2 * k
        n_in = nu + n_fric
        n = L.n
        inf = np.inf
        self.problem = QPProblem(
            H=np.zeros((n, n)), g=np.zeros(n), A=np.zeros((n_eq, n)), b=np.zeros(n_eq),
            C=np.zeros((n_in, n)), l=np.full(n_in, -inf), u=np.zeros(n_in),
            lb=np.full(n, -inf), ub=np.full(n, inf),
            variables={"vdot": L.sl_vdot, "forces_stance": L.sl_f_st, "forces_swing": L.sl_f_sw},
            eq_rows=[("dynamics", slice(0, n_dyn)), ("contact", slice(n_dyn, n_dyn + n_contact)),
                     ("rigid_stance", slice(n_dyn + n_contact, n_dyn + n_contact + L.n_rigid_st)),
                     ("rigid_swing", slice(n_dyn + n_contact + L.n_rigid_st, n_eq))],
            in_rows=[("torque", slice(0, nu)), ("friction", slice(nu, n_in))],
        )  # fmt: skip
        self._sl_dyn = slice(0, n_dyn)
        self._sl_contact = slice(n_dyn, n_dyn + n_contact)
        self._sl_coup = slice(n_dyn + n_contact, n_eq)
        self._sl_tau = slice(0, nu)
        # Friction pyramid: constant rows, l = -inf, u = 0.
        mu = config.friction_mu
        C = self.problem.C
        r = nu
        d = len(self._axes)
        nf = d * k
        for p in range(2 * k):
            c0 = L.nv + d * p
            for t in range(d - 1):
                for sign in (1.0, -1.0):
                    C[r, c0 + t] = sign
                    C[r, c0 + d - 1] = -mu
                    r += 1
        # The swing foot's pyramid rows (the second half): lifted while its
        # box pins its forces to zero (see build).
        self._sl_fric_sw = slice(nu + n_fric // 2, n_in)
        # Force boxes. The stance block always comes first, so its box is
        # constant; the swing block's box is ``w`` times a unit box.
        self._fz_st = L.sl_f_st.start + d * np.arange(k) + d - 1
        self._fz_sw = L.sl_f_sw.start + d * np.arange(k) + d - 1
        self._ft_st = np.array([L.sl_f_st.start + d * p + t for p in range(k) for t in range(d - 1)], dtype=int)
        self._ft_sw = np.array([L.sl_f_sw.start + d * p + t for p in range(k) for t in range(d - 1)], dtype=int)
        fmax = config.max_normal_force_N
        P = self.problem
        P.lb[self._fz_st] = config.min_normal_force_N
        P.ub[self._fz_st] = fmax
        P.lb[self._ft_st] = -mu * fmax
        P.ub[self._ft_st] = mu * fmax
        self._sw_lb_unit = np.zeros(nf)
        self._sw_ub_unit = np.zeros(nf)
        self._sw_ub_unit[self._fz_sw - L.sl_f_sw.start] = fmax
        self._sw_ub_unit[self._ft_sw - L.sl_f_sw.start] = mu * fmax
        self._sw_lb_unit[self._ft_sw - L.sl_f_sw.start] = -mu * fmax
        # Joint limits of the actuated joints, per leg (bounded on the swing leg only).
        lo = np.asarray(robot.pin_model.lowerPositionLimit)[self._act_q]
        hi = np.asarray(robot.pin_model.upperPositionLimit)[self._act_q]
        self._q_lo = np.where(hi > lo, lo, -inf)
        self._q_hi = np.where(hi > lo, hi, inf)
        self._tau_lim = np.asarray(robot.actuated.torque_limit_Nm, dtype=float)
        self._tau_lo = np.ascontiguousarray(self._tau_lim[:, 0])
        self._tau_hi = np.ascontiguousarray(self._tau_lim[:, 1])
        self._act_side = {
            side: np.array([nm.startswith(side) for nm in robot.actuated.joint_names]) for side in robot.foot_sides
        }
        # Per swing side: (v indices, q indices, 2 q_lo / hz^2, 2 q_hi / hz^2, other side's v indices).
        self._limits_by_swing = {}
        c = 2.0 / config.joint_limit_horizon_s**2
        for side in robot.foot_sides:
            m = self._act_side[side]
            self._limits_by_swing[side] = (
                self._act_v[m], self._act_q[m], c * self._q_lo[m], c * self._q_hi[m], self._act_v[~m]
            )  # fmt: skip
        # Per-tick buffers. D = [M | -Jf^T] (nv x n); R @ D (see _StanceRows)
        # gives the dynamics equalities, the torque map T and Lam.
        self._Jf = np.zeros((2 * nf, nv))
        self._D = np.zeros((nv, n))
        # R @ D and R @ hp (see _StanceRows): [dynamics rows; T; Lam] and
        # [-b_dyn; tau0; lam0], so torques tau = T x + tau0 and rigid-spring
        # forces lambda = Lam x + lam0 are views.
        self._RD = np.zeros((n_dyn + nu + n_lambda, n))
        self._Rhp = np.zeros(n_dyn + nu + n_lambda)
        self._T = self._RD[n_dyn : n_dyn + nu]
        self._tau0 = self._Rhp[n_dyn : n_dyn + nu]
        self._Lam = self._RD[n_dyn + nu :]
        self._lam0 = self._Rhp[n_dyn + nu :]
        self._hp = np.zeros(nv)
        self._contact_drift = np.zeros(n_contact)
        self._last_force_weight = 0.0
        self._G = np.zeros((n_lambda, nv))
        self._rigid_kp = np.r_[np.full(L.n_rigid_st, config.stance_coupling_kp), np.full(L.n_rigid_sw, config.coupling_kp)]
        self._rigid_kd = np.r_[np.full(L.n_rigid_st, config.stance_coupling_kd), np.full(L.n_rigid_sw, config.coupling_kd)]
        # The constant part of the Hessian: regularisation and the tasks whose
        # Jacobian never changes (posture, springs).
        H0 = np.zeros((n, n))
        di = np.arange(n)
        H0[di[L.sl_vdot], di[L.sl_vdot]] += config.reg_vdot
        fi = np.arange(L.sl_f_st.start, L.sl_f_sw.stop)
        H0[fi, fi] += config.reg_force
        for task in self.tasks:
            if task.constant_jacobian:
                J = task.jacobian(None, None)
                H0[L.sl_vdot, L.sl_vdot] += (J.T * task.gains.weight) @ J
        self._H0 = H0
        self._varying_tasks = [t for t in self.tasks if not t.constant_jacobian]
        # Constant-Jacobian tasks: their gradient W J^T r is affine in the
        # state, g_c = Kq q + Kv v + k0, precomputed here.
        self._Kq = np.zeros((nv, robot.nq))
        self._Kv = np.zeros((nv, nv))
        self._k0 = np.zeros(nv)
        for task in self.tasks:
            if task.constant_jacobian:
                WJ = task.jacobian(None, None).T * task.gains.weight
                cols_q, Rq, cols_v, Rv, r0 = task.affine_residual()
                self._Kq[:, cols_q] += WJ @ Rq
                self._Kv[:, cols_v] += WJ @ Rv
                self._k0 += WJ @ r0
        # The state-dependent least-squares terms stacked as ||E x + e||^2:
        # sqrt(W) (J vdot + r) of each varying task, then sqrt(reg_torque) (T x + tau0)
        # and sqrt(reg_coupling) (Lam x + lam0).
        self._reg_tau_rows = nu if config.reg_torque > 0 else 0
        self._reg_lam_rows = n_lambda if config.reg_coupling > 0 else 0
        rows = [t.size for t in self._varying_tasks] + [self._reg_tau_rows, self._reg_lam_rows]
        self._E = np.zeros((sum(rows), n))
        self._e = np.zeros(sum(rows))
        self._sqrt_w = [np.sqrt(t.gains.weight) for t in self._varying_tasks]
        self._sqrt_reg_torque = math.sqrt(config.reg_torque)
        self._sqrt_reg_coupling = math.sqrt(config.reg_coupling)
        # Check now that every stance's rigid springs can be eliminated.
        for side in robot.foot_sides:
            self._stance_rows(side)
        self._EtE = np.zeros((n, n))

        # Hip-yaw outputs for the pelvis-yaw feedback (None: not this robot).
        names = OutputMap(robot).names
        self._hip_yaw = None
        if config.hip_yaw_feedback > 0 and "stance_hip_yaw" in names and "swing_hip_yaw" in names:
            self._hip_yaw = (names.index("stance_hip_yaw"), names.index("swing_hip_yaw"))
        # Yaw moment of the stance foot: the nonzero entries of its row.
        self._yaw_idx = None
        if not self._planar and k == 2:
            c = L.sl_f_st.start
            self._yaw_idx = np.array([c, c + 1, c + 3, c + 4])
            self._yaw_flat = (self._yaw_idx[:, None] * n + self._yaw_idx[None, :]).ravel()

    # ------------------------------------------------------------------ info
    @property
    def n_variables(self) -> int:
        """Number of decision variables."""
        return self._layout.n

    @property
    def layout(self) -> _Layout:
        """Variable slices."""
        return self._layout

    def reset(self) -> None:
        """Nothing to forget between runs (the builder is stateless across ticks)."""

    def _stance_rows(self, stance: str) -> _StanceRows:
        """The :class:`_StanceRows` of this stance (cached per stance).

        The rigid-spring forces ``lambda = GpiT (D_P x + hp_P)`` come from the
        rows ``P`` of the held legs' passive joints (``GpiT = G_P^-T``); every
        row ``r`` then reads ``(D - K D_P) x + (hp - K hp_P)`` with ``K = G^T
        GpiT`` (zero on ``P`` itself), i.e. ``R_r = e_r - K_r S_P``.

        Raises:
            InputError: A held leg does not have exactly one passive joint per
                held spring, or its spring block ``G_P`` is singular: its
                constraint forces cannot be eliminated (use ``rigid_springs="none"``).
        """
        cache = self.__dict__.setdefault("_rows_by_stance", {})
        hit = cache.get(stance)
        if hit is not None:
            return hit
        L, robot = self._layout, self.robot
        nv = robot.nv
        swing = robot.other_side(stance)
        sides = ([stance] if L.n_rigid_st else []) + ([swing] if L.n_rigid_sw else [])
        eye = np.eye(nv)
        if sides:
            G = np.vstack([self._leg_springs[s][0] for s in sides])
            Gq = np.vstack([self._leg_springs[s][1] for s in sides])
            offs = np.concatenate([self._leg_springs[s][2] for s in sides])
            # The passive joints the held springs act on (a passive joint
            # without a spring or coupling stays a dynamics equality).
            P_rows = np.array([vi for vi in robot.passive_v_idx if np.any(G[:, vi] != 0.0)], dtype=int)
            Gp = G[:, P_rows]
            if Gp.shape[0] != Gp.shape[1] or np.linalg.cond(Gp) > 1e8:
                raise InputError(
                    f"rigid_springs={self.config.rigid_springs!r}: the held legs ({', '.join(sides)}) have "
                    f"{G.shape[0]} springs but {P_rows.size} passive joints (or a singular spring block); "
                    "their constraint forces cannot be eliminated: use rigid_springs='none'"
                )
            GpiT = np.linalg.inv(Gp).T
            K = G.T @ GpiT  # (nv, n_lambda)
            K[P_rows] = 0.0
            reduce = eye - K @ eye[P_rows]  # rows e_r - K_r S_P
            lam_rows = GpiT @ eye[P_rows]
        else:
            G, Gq, offs = np.zeros((0, nv)), np.zeros((0, robot.nq)), np.zeros(0)
            P_rows = np.zeros(0, dtype=int)
            reduce, lam_rows = eye, np.zeros((0, nv))
        dyn_rows = np.setdiff1d(self._unact_v, P_rows)
        R = np.vstack([reduce[dyn_rows], reduce[self._act_v], lam_rows])
        kp, kd = self._rigid_kp, self._rigid_kd
        hit = _StanceRows(R=R, G=G, kpGq=kp[:, None] * Gq, kdG=kd[:, None] * G, kp_offs=kp * offs)
        cache[stance] = hit
        return hit

    # ------------------------------------------------------------------ build
    def _force_jacobians(self, kin, side: str, rows: slice):
        """Fill the stacked force-point Jacobian rows of one foot; return the per-point (3, nv) list."""
        d, axes = len(self._axes), self._axes_index
        jacs = []
        for p, fid in enumerate(self.robot.force_frame_ids[side]):
            J = kin.frame_jacobian(fid)
            self._Jf[rows.start + d * p : rows.start + d * (p + 1)] = J[axes]
            jacs.append(J)
        return jacs

    def swing_force_weight(self, target) -> float:
        """The force ramp ``w`` of the swing foot (0 in the air, 1 fully loaded)."""
        lift = self.config.liftoff_phase
        w_lift = max(0.0, 1.0 - target.phase / lift) if lift > 0 else 0.0
        w = max(self.config.touchdown_blend * float(target.swing_contact_weight), w_lift)
        if not math.isfinite(w):
            return 0.0
        return min(max(w, 0.0), 1.0)

    def build(self, kin, target) -> QPProblem:
        """Fill the problem for the state in ``kin`` (already updated) and the references in ``target``.

        Every block is written in place into the preallocated arrays; blocks
        that never change (friction rows, the stance force box, the constant
        Hessian part, zero blocks) are written once in the constructor, so
        edit the returned problem only through this class's methods
        (:meth:`limit_stance_foot_torque`, :meth:`add_stance_yaw_moment_cost`)
        or on a :meth:`QPProblem.copy`: other in-place edits would persist
        into later ticks.
        """
        cfg, L, P = self.config, self._layout, self.problem
        stance = target.stance
        swing = "right" if stance == "left" else "left"
        k = L.n_points
        sv = L.sl_vdot
        sf = slice(L.sl_f_st.start, L.sl_f_sw.stop)
        v = kin.v
        # h - taup: the dynamics' right-hand side without contact forces.
        hp = np.subtract(kin.nonlinear_effects(), kin.passive_forces(), out=self._hp)
        # Force Jacobians (world-aligned, selected axes) stacked stance then swing.
        nf = L.sl_f_st.stop - L.sl_f_st.start
        st_jacs = self._force_jacobians(kin, stance, slice(0, nf))
        self._force_jacobians(kin, swing, slice(nf, 2 * nf))
        # D x + hp = S^T tau + G^T lam with D = [M | -Jf^T]. The rigid springs'
        # lam = GpiT (D_P x + hp_P) is substituted (module docstring); then the
        # kept unactuated rows are the dynamics equalities (D_u x = -hp_u) and
        # the actuated rows the torque map tau = T x + tau0 (tau0 = hp_a).
        D, A, b = self._D, P.A, P.b
        D[:, sv] = kin.mass_matrix()
        np.negative(self._Jf.T, out=D[:, sf])
        rs = self._stance_rows(stance)
        RD = np.matmul(rs.R, D, out=self._RD)
        Rhp = np.matmul(rs.R, hp, out=self._Rhp)
        nd = self._sl_dyn.stop
        A[:nd] = RD[:nd]
        np.negative(Rhp[:nd], out=b[:nd])
        T, tau0 = self._T, self._tau0
        if L.n_lambda:
            A[self._sl_coup, sv] = rs.G
            # G vdot = -kp (Gq q - offsets) - kd G v.
            bcp = np.matmul(rs.kpGq, kin.q, out=b[self._sl_coup])
            bcp += rs.kdG @ v
            np.subtract(rs.kp_offs, bcp, out=bcp)
            self._G = rs.G
        # Stance contact acceleration: J_c vdot = -Jdot_c v - K_c J_c v.
        rc = self._sl_contact
        fids = self.robot.force_frame_ids[stance]
        Ac, drift = A[rc, sv], self._contact_drift
        if k == 1:
            Ac[:] = st_jacs[0][self._axes_index]
            drift[:] = kin.frame_jdot_v(fids[0])[self._axes_index]
        else:
            J0, J1 = st_jacs
            ax = kin.frame_position(fids[0]) - kin.frame_position(fids[1])
            ax /= math.sqrt(ax[0] * ax[0] + ax[1] * ax[1] + ax[2] * ax[2])
            # n1: the vertical made orthogonal to the blade; n2 = axis x n1.
            n1 = (-ax[2] * ax[0], -ax[2] * ax[1], 1.0 - ax[2] * ax[2])
            s1 = 1.0 / math.sqrt(n1[0] * n1[0] + n1[1] * n1[1] + n1[2] * n1[2])
            n1 = (n1[0] * s1, n1[1] * s1, n1[2] * s1)
            N = np.array(
                [n1, (ax[1] * n1[2] - ax[2] * n1[1], ax[2] * n1[0] - ax[0] * n1[2], ax[0] * n1[1] - ax[1] * n1[0])]
            )
            Ac[:3] = J0
            np.matmul(N, J1, out=Ac[3:])
            drift[:3] = kin.frame_jdot_v(fids[0])
            np.matmul(N, kin.frame_jdot_v(fids[1]), out=drift[3:])
        bc = np.multiply(Ac @ v, -cfg.contact_kd, out=b[rc])
        bc -= drift
        # Torque limits: tau_lo - tau0 <= T x <= tau_hi - tau0.
        P.C[self._sl_tau] = T
        np.subtract(self._tau_lo, tau0, out=P.l[self._sl_tau])
        np.subtract(self._tau_hi, tau0, out=P.u[self._sl_tau])
        # Joint limits (swing leg): stop inside the range within the horizon.
        vi, qi, c_lo, c_hi, other = self._limits_by_swing[swing]
        hz = cfg.joint_limit_horizon_s
        rec = cfg.joint_limit_max_recovery
        # a_max = 2 (q_hi - q - v hz) / hz^2 = c_hi - t, t = 2 (q + v hz) / hz^2.
        t = kin.q[qi] + v[vi] * hz
        t *= 2.0 / (hz * hz)
        P.ub[vi] = np.maximum(c_hi - t, -rec)
        P.lb[vi] = np.minimum(c_lo - t, rec)
        P.ub[other] = np.inf
        P.lb[other] = -np.inf
        # Swing force box: w times the unit box (the ramp).
        w = self.swing_force_weight(target)
        self._last_force_weight = w
        np.multiply(self._sw_ub_unit, w, out=P.ub[L.sl_f_sw])
        np.multiply(self._sw_lb_unit, w, out=P.lb[L.sl_f_sw])
        # With w = 0 the box pins the swing forces to zero and implies their
        # pyramid, whose rows then sit at 0 <= 0: redundant constraints that
        # ProxQP counted as active (8 of its ~14 active rows on Cassie) and
        # that made the warm solve ~16 % slower. Lift them (u = +inf; the
        # dimensions stay fixed) until the liftoff ramp loads the foot.
        P.u[self._sl_fric_sw] = math.inf if w == 0.0 else 0.0
        # Cost: constant Hessian part, the constant tasks' affine gradient, and
        # the stacked state-dependent terms ||E x + e||^2 (varying tasks,
        # torques, rigid-spring forces).
        H, g = P.H, P.g
        np.copyto(H, self._H0)
        g.fill(0.0)
        gv = np.matmul(self._Kq, kin.q, out=g[sv])
        gv += self._Kv @ v
        gv += self._k0
        E, e = self._E, self._e
        row = 0
        for task, sw in zip(self._varying_tasks, self._sqrt_w):
            J, r = task.least_squares(kin, target)
            m = sw.shape[0]
            np.multiply(J, sw[:, None], out=E[row : row + m, sv])
            np.multiply(r, sw, out=e[row : row + m])
            if task is self.output_task and self._hip_yaw is not None:
                # Pelvis-yaw feedback: the swing hip-yaw reference moves by
                # (dh, ddh); r = ... - K_d (yd_d - J v) - K_p (y_d - y) moves by
                # -(K_d ddh + K_p dh).
                dh, ddh = self._hip_yaw_correction(kin, target)
                i = self._hip_yaw[1]
                gains = task.gains
                e[row + i] -= sw[i] * (gains.kd[i] * ddh + gains.kp[i] * dh)
            row += m
        if self._reg_tau_rows:
            m = self._reg_tau_rows
            np.multiply(T, self._sqrt_reg_torque, out=E[row : row + m])
            np.multiply(tau0, self._sqrt_reg_torque, out=e[row : row + m])
            row += m
        if self._reg_lam_rows:
            np.multiply(self._Lam, self._sqrt_reg_coupling, out=E[row:])
            np.multiply(self._lam0, self._sqrt_reg_coupling, out=e[row:])
        H += np.matmul(E.T, E, out=self._EtE)
        g += E.T @ e
        return P

    def hip_yaw_feedback_target(self, kin, target):
        """``target`` with the pelvis-yaw feedback on the swing hip-yaw
        reference (``config.hip_yaw_feedback``, see :class:`QPConfig`); the
        same object when the feedback is off or the robot has no hip-yaw outputs."""
        if self._hip_yaw is None:
            return target
        dh, ddh = self._hip_yaw_correction(kin, target)
        i_sw = self._hip_yaw[1]
        out = replace(target, h_d=target.h_d.copy(), dh_d=target.dh_d.copy())
        out.h_d[i_sw] += dh
        out.dh_d[i_sw] += ddh
        return out

    def _hip_yaw_correction(self, kin, target) -> tuple[float, float]:
        """The pelvis-yaw feedback's change of the swing hip-yaw reference
        (rad) and of its rate (rad/s): ``(-k e_psi, -k (psidot + dh_d[stance_hip_yaw]))``."""
        i_st = self._hip_yaw[0]
        k = self.config.hip_yaw_feedback
        R = kin.base_rotation()
        psi = math.atan2(R[1, 0], R[0, 0])
        psi_dot = float(kin.base_angular_jacobian()[2] @ kin.v)
        e = psi - (target.heading_rad - float(target.h_d[i_st]))
        e = (e + math.pi) % (2.0 * math.pi) - math.pi
        return -k * e, -k * (psi_dot + float(target.dh_d[i_st]))

    # ------------------------------------------------------- stance foot
    def _stance_foot_index(self, stance: str):
        """Actuator index of the ``stance`` foot ("toe") motor, or ``None`` (no such motor)."""
        cache = self.__dict__.setdefault("_stance_foot_idx", {})
        if stance not in cache:
            names = list(self.robot.actuated.joint_names)
            name = f"{stance}-foot"
            cache[stance] = names.index(name) if name in names else None
        return cache[stance]

    def limit_stance_foot_torque(self, problem: QPProblem, target) -> None:
        """Bound the stance foot motor torque to ``+-config.stance_foot_torque_max_Nm``.

        Call right after :meth:`build` (it edits that problem's torque rows, which
        hold ``tau = T x + tau0``). No-op with an infinite bound or no foot motor.
        """
        lim = self.config.stance_foot_torque_max_Nm
        i = self._stance_foot_index(target.stance)
        if i is None or not math.isfinite(lim):
            return
        r = self._sl_tau.start + i
        problem.l[r] = max(self._tau_lim[i, 0], -lim) - self._tau0[i]
        problem.u[r] = min(self._tau_lim[i, 1], lim) - self._tau0[i]

    def add_stance_yaw_moment_cost(self, problem: QPProblem, kin, target) -> None:
        """Add ``w M_z^2`` to the cost of the problem just built (``w`` =
        ``config.stance_yaw_moment_weight``), with ``M_z`` the yaw moment of the
        stance foot's point forces about their mean point. No-op for ``w = 0``,
        planar robots or one-point feet."""
        w = self.config.stance_yaw_moment_weight
        idx = self._yaw_idx
        if w <= 0 or idx is None:
            return
        fids = self.robot.force_frame_ids[target.stance]
        p0, p1 = kin.frame_position(fids[0]), kin.frame_position(fids[1])
        # M_z = sum_p (r_p - mid) x f_p . e_z; r_0 - mid = -(r_1 - mid) = (p0 - p1) / 2.
        dx, dy = 0.5 * (p0[0] - p1[0]), 0.5 * (p0[1] - p1[1])
        a = np.array([-dy, dx, dy, -dx])
        if problem.H.flags.c_contiguous:
            Hf = problem.H.reshape(-1)  # a view of H
            Hf[self._yaw_flat] += w * np.multiply.outer(a, a).reshape(-1)
        else:
            problem.H[np.ix_(idx, idx)] += w * np.outer(a, a)

    # ------------------------------------------------------------ recovery
    def torques(self, x: np.ndarray) -> np.ndarray:
        """Joint torques (N m, actuator order) of a solution of the last built problem."""
        return self._T @ x + self._tau0

    def forces(self, x: np.ndarray) -> dict[str, np.ndarray]:
        """Contact point forces (N) of a solution: ``{"stance": (k, d), "swing": (k, d)}`` (axes x,y,z or x,z)."""
        L = self._layout
        d = len(self._axes)
        return {"stance": x[L.sl_f_st].reshape(-1, d), "swing": x[L.sl_f_sw].reshape(-1, d)}

    def normal_force_totals(self, x: np.ndarray) -> tuple[float, float]:
        """Total normal (vertical) force of the stance and of the swing foot in a solution, N."""
        return float(x[self._fz_st].sum()), float(x[self._fz_sw].sum())

    def rigid_forces(self, x: np.ndarray) -> np.ndarray:
        """The rigid-spring constraint forces ``lambda`` (N m, stacked stance
        leg then swing leg, per leg the couplings then the spring joints) of a
        solution of the last built problem; shape (0,) when none is held rigid."""
        return self._Lam @ x + self._lam0

    def generalized_contact_force(self, x: np.ndarray) -> np.ndarray:
        """``J_f^T f + G^T lambda`` (nv,) of a solution of the last built problem (for checks)."""
        L = self._layout
        out = self._Jf.T @ x[L.sl_f_st.start : L.sl_f_sw.stop]
        if L.n_lambda:
            out = out + self._G.T @ self.rigid_forces(x)
        return out
