"""The constraints of the whole-body QP, each a :class:`~amlip_qp.control.wbc.constraint_base.Constraint`.

Every constraint owns a block of the problem and writes it with numpy
(the reference) and as CasADi expressions (the generated build); the
interface is in :mod:`~amlip_qp.control.wbc.constraint_base`.
:class:`~amlip_qp.control.wbc.builder.WholeBodyQP` and
:class:`~amlip_qp.control.wbc.compiled.CompiledBuild` iterate the same
list.

Equalities: ``dynamics`` (:class:`DynamicsRows`), ``contact``
(:class:`StanceContact`), ``rigid_stance`` / ``rigid_swing``
(:class:`RigidSprings`). Inequalities: ``torque`` (:class:`TorqueLimits`,
the stance foot motor's bound included), ``friction``
(:class:`FrictionPyramid`). Boxes: :class:`JointLimits` (swing leg
accelerations) and :class:`ForceBox` (contact forces).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import casadi as ca
import numpy as np

from amlip_qp.control.wbc.constraint_base import Constraint
from amlip_qp.control.wbc.inputs import dm

if TYPE_CHECKING:
    from amlip_qp.control.wbc.config import QPConfig
    from amlip_qp.control.wbc.inputs import SymbolicInputs, TickInputs
    from amlip_qp.control.wbc.layout import VariableLayout
    from amlip_qp.control.wbc.spring_elimination import ReducedDynamics, SpringElimination, SymbolicDynamics
    from amlip_qp.qp.problem import QPProblem
    from amlip_qp.robots.robot import Robot


class DynamicsRows(Constraint):
    """The unactuated rows of ``M vdot + h - taup = S^T tau + J^T f + G^T lambda``
    (floating base and the passive joints not held rigid), ``lambda`` substituted:
    ``(R D)_dyn x = -(R hp)_dyn`` (:mod:`~amlip_qp.control.wbc.spring_elimination`)."""

    def __init__(self, n_dyn: int):
        super().__init__("dynamics", slice(0, n_dyn))

    def write(self, inputs: TickInputs, dynamics: ReducedDynamics, problem: QPProblem) -> None:
        nd = self.size
        problem.A[self.rows] = dynamics.RD[:nd]
        np.negative(dynamics.Rhp[:nd], out=problem.b[self.rows])

    def symbolic(self, sym: SymbolicInputs, dyn: SymbolicDynamics) -> dict[str, Any]:
        nd = self.size
        return {"A": dyn.RD[:nd, :], "b": -dyn.Rhp[:nd]}


class StanceContact(Constraint):
    """The stance foot does not accelerate: ``J_c vdot + Jdot_c v = -K_c J_c v``
    (velocity Baumgarte gain ``K_c = contact_kd``, 1/s).

    A point foot gives its components on the layout's axes. Cassie's blade
    uses 5 independent rows: the toe's 3 and the heel's 2 components
    orthogonal to the toe-heel axis (the third is implied by the rigid foot,
    and dropping it keeps the rows independent for active-set solvers).
    A four-point sole (toe left, toe right, heel left, heel right) uses 6: the
    same 5 on its diagonal (toe left as the toe, heel right as the heel), then
    the toe-right point's component along ``a x (p_1 - p_0)`` (``a`` the
    diagonal's direction), the only motion the diagonal leaves it: a rotation
    about the diagonal. The heel pair may coincide (a triangular sole); the
    toe pair, whose right point gives the sixth row, may not (the profile
    reader refuses it).
    """

    def __init__(self, layout: VariableLayout, contact_kd: float):
        super().__init__("contact", slice(0, {1: layout.point_dim, 2: 5, 4: 6}[layout.n_points]))
        self.layout = layout
        self.contact_kd = contact_kd
        self._drift = np.zeros(self.size)

    def initialize(self, problem: QPProblem) -> None:
        problem.A[self.rows, self.layout.sl_forces] = 0.0

    def write(self, inputs: TickInputs, dynamics: ReducedDynamics, problem: QPProblem) -> None:
        L = self.layout
        Ac, drift = problem.A[self.rows, L.sl_vdot], self._drift
        if L.n_points == 1:
            Ac[:] = inputs.point_jacobians[0][L.axes_index]
            drift[:] = inputs.point_drifts[0][L.axes_index]
        else:
            # the blade: toe then heel (a sole's diagonal: toe left, heel right)
            J, P, D = inputs.point_jacobians, inputs.point_positions, inputs.point_drifts
            ax = P[0] - P[-1]
            ax /= math.sqrt(ax[0] * ax[0] + ax[1] * ax[1] + ax[2] * ax[2])
            N = _blade_normals(ax)
            Ac[:3] = J[0]
            np.matmul(N, J[-1], out=Ac[3:5])
            drift[:3] = D[0]
            np.matmul(N, D[-1], out=drift[3:5])
            if L.n_points == 4:
                e = P[1] - P[0]
                m = np.array((ax[1] * e[2] - ax[2] * e[1], ax[2] * e[0] - ax[0] * e[2], ax[0] * e[1] - ax[1] * e[0]))
                m /= math.sqrt(m[0] * m[0] + m[1] * m[1] + m[2] * m[2])
                np.matmul(m, J[1], out=Ac[5])
                drift[5] = m @ D[1]
        bc = np.multiply(Ac @ inputs.v, -self.contact_kd, out=problem.b[self.rows])
        bc -= drift

    def symbolic(self, sym: SymbolicInputs, dyn: SymbolicDynamics) -> dict[str, Any]:
        L = self.layout
        Jf, con, k = sym.JfT.T, sym.contact, L.n_points
        if k in (2, 4):
            last, d = 3 * (k - 1), 3 * k  # the heel's offset in each half; the drifts' offset
            p0, p1, jdv0, jdv1 = con[0:3], con[last : last + 3], con[d : d + 3], con[d + last : d + last + 3]
            ax = p0 - p1
            ax = ax / ca.norm_2(ax)
            n1 = ca.vertcat(-ax[2] * ax[0], -ax[2] * ax[1], 1.0 - ax[2] * ax[2])
            n1 = n1 / ca.norm_2(n1)
            N = ca.horzcat(n1, ca.cross(ax, n1)).T
            Ac = ca.vertcat(Jf[0:3, :], ca.mtimes(N, Jf[last : last + 3, :]))
            drift = ca.vertcat(jdv0, ca.mtimes(N, jdv1))
            if k == 4:
                m = ca.cross(ax, con[3:6] - p0)
                m = m / ca.norm_2(m)
                Ac = ca.vertcat(Ac, ca.mtimes(m.T, Jf[3:6, :]))
                drift = ca.vertcat(drift, ca.dot(m, con[d + 3 : d + 6]))
        else:
            Ac, drift = Jf[0 : L.point_dim, :], con
        bc = -self.contact_kd * ca.mtimes(Ac, sym.v) - drift
        return {"A": ca.horzcat(Ac, ca.MX(Ac.shape[0], L.n - L.nv)), "b": bc}


def _blade_normals(ax: np.ndarray) -> np.ndarray:
    """The two unit directions normal to the unit blade axis ``ax``: the vertical made orthogonal
    to the blade, ``n1``, and ``n2 = ax x n1``, as the rows of a (2, 3) array."""
    n1 = (-ax[2] * ax[0], -ax[2] * ax[1], 1.0 - ax[2] * ax[2])
    s1 = 1.0 / math.sqrt(n1[0] * n1[0] + n1[1] * n1[1] + n1[2] * n1[2])
    n1 = (n1[0] * s1, n1[1] * s1, n1[2] * s1)
    return np.array([n1, (ax[1] * n1[2] - ax[2] * n1[1], ax[2] * n1[0] - ax[0] * n1[2], ax[0] * n1[1] - ax[1] * n1[0])])


class RigidSprings(Constraint):
    """The held springs' rows ``G vdot + Gdot v = -K_p g - K_d G v`` (``g``
    the deflections, rad; ``Gdot = 0`` for these linear rows): the stance
    leg's (block ``rigid_stance``), then the swing leg's (``rigid_swing``)."""

    def __init__(self, layout: VariableLayout, elimination: SpringElimination):
        super().__init__("rigid_springs", slice(0, layout.n_lambda))
        self.layout = layout
        self.elimination = elimination

    def row_blocks(self) -> list[tuple[str, slice]]:
        mid = self.rows.start + self.layout.n_rigid_st
        return [("rigid_stance", slice(self.rows.start, mid)), ("rigid_swing", slice(mid, self.rows.stop))]

    def initialize(self, problem: QPProblem) -> None:
        problem.A[self.rows, self.layout.sl_forces] = 0.0

    def write(self, inputs: TickInputs, dynamics: ReducedDynamics, problem: QPProblem) -> None:
        if not self.size:
            return
        rs = self.elimination.rows(inputs.stance)
        problem.A[self.rows, self.layout.sl_vdot] = rs.G
        # G vdot = -kp (Gq q - offsets) - kd G v.
        bcp = np.matmul(rs.kpGq, inputs.q, out=problem.b[self.rows])
        bcp += rs.kdG @ inputs.v
        np.subtract(rs.kp_offs, bcp, out=bcp)

    def symbolic(self, sym: SymbolicInputs, dyn: SymbolicDynamics) -> dict[str, Any]:
        if not self.size:
            return {}
        rs, L = self.elimination.rows(sym.stance), self.layout
        b = dm(rs.kp_offs) - ca.mtimes(dm(rs.kpGq), sym.q) - ca.mtimes(dm(rs.kdG), sym.v)
        return {"A": ca.horzcat(dm(rs.G), ca.MX(L.n_lambda, L.n - L.nv)), "b": b}


class TorqueLimits(Constraint):
    """Motor torque limits on ``tau = T x + tau0``: ``lo - tau0 <= T x <= hi - tau0``.

    ``lo, hi`` are ``robot.actuated.torque_limit_Nm``, with the motors of the
    **stance** foot's joints that are passive in stance (the profile's
    ``feet.passive_in_stance``; without a profile, the ``ankle_pitch`` role,
    Cassie's foot "toe") further bounded to ``+-stance_foot_torque_max_Nm``
    (no effect with ``inf`` or without such a motor).
    """

    kind = "in"

    def __init__(self, robot: Robot, config: QPConfig):
        tau_lim = np.asarray(robot.actuated.torque_limit_Nm, dtype=float)
        super().__init__("torque", slice(0, tau_lim.shape[0]))
        names = list(robot.actuated.joint_names)
        lim = config.stance_foot_torque_max_Nm
        #: Per stance side: (lower, upper) torque bounds, N m.
        self.bounds: dict[str, tuple[np.ndarray, np.ndarray]] = {}
        for side in robot.foot_sides:
            lo, hi = tau_lim[:, 0].copy(), tau_lim[:, 1].copy()
            for foot in robot.passive_in_stance(side):
                if foot in names and math.isfinite(lim):
                    i = names.index(foot)
                    lo[i] = max(tau_lim[i, 0], -lim)
                    hi[i] = min(tau_lim[i, 1], lim)
            self.bounds[side] = (lo, hi)

    def write(self, inputs: TickInputs, dynamics: ReducedDynamics, problem: QPProblem) -> None:
        lo, hi = self.bounds[inputs.stance]
        problem.C[self.rows] = dynamics.T
        np.subtract(lo, dynamics.tau0, out=problem.l[self.rows])
        np.subtract(hi, dynamics.tau0, out=problem.u[self.rows])

    def symbolic(self, sym: SymbolicInputs, dyn: SymbolicDynamics) -> dict[str, Any]:
        lo, hi = self.bounds[sym.stance]
        return {"C": dyn.T, "l": dm(lo) - dyn.tau0, "u": dm(hi) - dyn.tau0}


class FrictionPyramid(Constraint):
    """``|f_t| <= mu f_z`` per tangential axis of every force point (4 rows
    per 3-D point, 2 per planar point), stance foot's rows then swing foot's.

    The rows are constant (``l = -inf``, ``u = 0``). While the swing ramp
    ``w`` is 0 the :class:`ForceBox` pins the swing forces to zero and implies
    their pyramid: those rows are lifted (``u = +inf``, the dimensions stay
    fixed) until the liftoff ramp loads the foot (measured: docs/TUNING.md).
    """

    kind = "in"

    def __init__(self, layout: VariableLayout, friction_mu: float):
        super().__init__("friction", slice(0, 2 * (layout.point_dim - 1) * 2 * layout.n_points))
        self.layout = layout
        self.mu = friction_mu

    @property
    def swing_rows(self) -> slice:
        """The swing foot's rows (the second half)."""
        return slice(self.rows.start + self.size // 2, self.rows.stop)

    def initialize(self, problem: QPProblem) -> None:
        L, C, r = self.layout, problem.C, self.rows.start
        C[self.rows] = 0.0
        d = L.point_dim
        for p in range(2 * L.n_points):
            c0 = L.nv + d * p
            for t in range(d - 1):
                for sign in (1.0, -1.0):
                    C[r, c0 + t] = sign
                    C[r, c0 + d - 1] = -self.mu
                    r += 1
        problem.l[self.rows] = -math.inf
        problem.u[self.rows] = 0.0

    def write(self, inputs: TickInputs, dynamics: ReducedDynamics, problem: QPProblem) -> None:
        problem.u[self.swing_rows] = math.inf if inputs.swing_force_weight == 0.0 else 0.0

    def tilt_stance_rows(self, problem: QPProblem, ground_pitch_rad: float, heading_rad: float) -> None:
        """Turn the stance foot's pyramid about the ground's normal (3-D points only; constant rows).

        The ground is inclined along the heading ``heading_rad`` (rad) by
        ``ground_pitch_rad`` (rad, positive = descending ahead, the toe pitch
        output's convention): its tangents are ``t1`` (up or down the slope
        along the heading) and ``t2`` (across it, horizontal), its normal
        ``n = t1 x t2``, and each point's rows become ``+-t_i . f - mu n . f <= 0``.
        A pitch of 0 and a heading of 0 give the world-axes rows of :meth:`initialize`
        up to the signs of zeros. Only the rows change; the compiled assembly
        leaves them as they are (they are constant there).
        """
        L = self.layout
        if L.point_dim != 3:
            return
        a = -ground_pitch_rad  # uphill angle along the heading, rad
        ca_, sa, cD, sD = math.cos(a), math.sin(a), math.cos(heading_rad), math.sin(heading_rad)
        t1 = np.array((ca_ * cD, ca_ * sD, sa))
        t2 = np.array((-sD, cD, 0.0))
        n = np.cross(t1, t2)
        C, r = problem.C, self.rows.start
        for p in range(L.n_points):
            c0 = L.nv + 3 * p
            for t in (t1, t2):
                for sign in (1.0, -1.0):
                    C[r, c0 : c0 + 3] = sign * t - self.mu * n
                    r += 1

    def symbolic(self, sym: SymbolicInputs, dyn: SymbolicDynamics) -> dict[str, Any]:
        half = self.size // 2
        lifted = ca.if_else(sym.swing_force_weight == 0.0, math.inf, 0.0)
        return {"C": None, "l": None, "u": ca.vertcat(ca.DM.zeros(half), ca.repmat(lifted, half, 1))}


class JointLimits(Constraint):
    """Accelerations of the **swing** leg's actuated joints bounded so each
    joint stops inside its range within ``joint_limit_horizon_s``:
    ``2 (q_lo - q - v hz) / hz^2 <= vdot <= 2 (q_hi - q - v hz) / hz^2``,
    capped at ``joint_limit_max_recovery``. The stance leg is left to the
    output tasks (measured: docs/TUNING.md)."""

    kind = "box"

    def __init__(self, robot: Robot, layout: VariableLayout, config: QPConfig):
        super().__init__("joint_limits", layout.sl_vdot)
        self.layout = layout
        self.horizon_s = config.joint_limit_horizon_s
        self.max_recovery = config.joint_limit_max_recovery
        act_v = np.asarray(robot.actuated.pin_v_idx, dtype=int)
        act_q = np.asarray(robot.actuated.pin_q_idx, dtype=int)
        lo = np.asarray(robot.pin_model.lowerPositionLimit)[act_q]
        hi = np.asarray(robot.pin_model.upperPositionLimit)[act_q]
        q_lo, q_hi = np.where(hi > lo, lo, -math.inf), np.where(hi > lo, hi, math.inf)
        #: Per swing side: (v indices, q indices, 2 q_lo / hz^2, 2 q_hi / hz^2, other side's v indices).
        self.by_swing: dict[str, tuple[np.ndarray, ...]] = {}
        c = 2.0 / config.joint_limit_horizon_s**2
        for side in robot.foot_sides:
            leg = set(robot.leg_joint_names[side])
            m = np.array([nm in leg for nm in robot.actuated.joint_names], dtype=bool)
            self.by_swing[side] = (act_v[m], act_q[m], c * q_lo[m], c * q_hi[m], act_v[~m])

    def initialize(self, problem: QPProblem) -> None:
        problem.lb[self.rows] = -np.inf  # the floating base and passive joints stay free
        problem.ub[self.rows] = np.inf

    def write(self, inputs: TickInputs, dynamics: ReducedDynamics, problem: QPProblem) -> None:
        vi, qi, c_lo, c_hi, other = self.by_swing[inputs.swing]
        hz, rec = self.horizon_s, self.max_recovery
        # a_max = 2 (q_hi - q - v hz) / hz^2 = c_hi - t, t = 2 (q + v hz) / hz^2.
        t = inputs.q[qi] + inputs.v[vi] * hz
        t *= 2.0 / (hz * hz)
        problem.ub[vi] = np.maximum(c_hi - t, -rec)
        problem.lb[vi] = np.minimum(c_lo - t, rec)
        problem.ub[other] = np.inf
        problem.lb[other] = -np.inf

    def symbolic(self, sym: SymbolicInputs, dyn: SymbolicDynamics) -> dict[str, Any]:
        L = self.layout
        nv, nq, n = L.nv, sym.q.shape[0], L.n
        vi, qi, c_lo, c_hi, _ = self.by_swing[sym.swing]
        hz, rec = self.horizon_s, self.max_recovery
        Sv = np.zeros((vi.size, nv))
        Sv[np.arange(vi.size), vi] = 1.0
        Sq = np.zeros((qi.size, nq))
        Sq[np.arange(qi.size), qi] = 1.0
        t = (ca.mtimes(dm(Sq), sym.q) + ca.mtimes(dm(Sv), sym.v) * hz) * (2.0 / (hz * hz))
        ub_v = ca.fmax(dm(c_hi) - t, -rec)
        lb_v = ca.fmin(dm(c_lo) - t, rec)
        place = ca.DM(ca.sparsify(dm(_placement(n, vi))))
        lb0, ub0 = np.zeros(n), np.zeros(n)
        lb0[L.sl_vdot], ub0[L.sl_vdot] = -np.inf, np.inf
        lb0[vi], ub0[vi] = 0.0, 0.0
        return {"lb": dm(lb0) + ca.mtimes(place, lb_v), "ub": dm(ub0) + ca.mtimes(place, ub_v)}


class ForceBox(Constraint):
    """Box bounds of the contact forces. Stance points: normal force in
    ``[min_normal_force_N, max_normal_force_N]``, tangential ``|f_t| <= mu
    f_max``. Swing points: ``w`` times that box with a zero floor,
    ``0 <= f_z <= w f_max``, ``|f_t| <= mu w f_max``, with ``w`` the swing
    force ramp (:func:`~amlip_qp.control.wbc.inputs.swing_force_weight`)."""

    kind = "box"

    def __init__(self, layout: VariableLayout, config: QPConfig):
        super().__init__("forces", layout.sl_forces)
        self.layout = layout
        L, fmax, mu = layout, config.max_normal_force_N, config.friction_mu
        self.fmin, self.fmax, self.mu = config.min_normal_force_N, fmax, mu
        fz_sw, ft_sw = L.normal_index(L.sl_f_sw) - L.sl_f_sw.start, L.tangential_index(L.sl_f_sw) - L.sl_f_sw.start
        #: The swing foot's box at ``w = 1`` (its lower and upper bounds, N).
        self.swing_lb_unit, self.swing_ub_unit = np.zeros(L.n_force), np.zeros(L.n_force)
        self.swing_ub_unit[fz_sw] = fmax
        self.swing_ub_unit[ft_sw] = mu * fmax
        self.swing_lb_unit[ft_sw] = -mu * fmax

    def initialize(self, problem: QPProblem) -> None:
        self._stance_box(problem.lb, problem.ub)

    def _stance_box(self, lb: np.ndarray, ub: np.ndarray) -> None:
        L = self.layout
        fz, ft = L.normal_index(L.sl_f_st), L.tangential_index(L.sl_f_st)
        lb[fz] = self.fmin
        ub[fz] = self.fmax
        lb[ft] = -self.mu * self.fmax
        ub[ft] = self.mu * self.fmax

    def write(self, inputs: TickInputs, dynamics: ReducedDynamics, problem: QPProblem) -> None:
        w, sw = inputs.swing_force_weight, self.layout.sl_f_sw
        np.multiply(self.swing_ub_unit, w, out=problem.ub[sw])
        np.multiply(self.swing_lb_unit, w, out=problem.lb[sw])

    def symbolic(self, sym: SymbolicInputs, dyn: SymbolicDynamics) -> dict[str, Any]:
        L, n = self.layout, self.layout.n
        lb0, ub0 = np.zeros(n), np.zeros(n)
        self._stance_box(lb0, ub0)
        unit_lb, unit_ub = np.zeros(n), np.zeros(n)
        unit_lb[L.sl_f_sw], unit_ub[L.sl_f_sw] = self.swing_lb_unit, self.swing_ub_unit
        w = sym.swing_force_weight
        return {"lb": dm(lb0) + w * ca.sparsify(dm(unit_lb)), "ub": dm(ub0) + w * ca.sparsify(dm(unit_ub))}


def _placement(n: int, idx: np.ndarray) -> np.ndarray:
    """The (n, len(idx)) matrix that puts a vector at the entries ``idx`` of an n-vector."""
    place = np.zeros((n, idx.size))
    place[idx, np.arange(idx.size)] = 1.0
    return place
