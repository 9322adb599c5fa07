"""Springs held rigid, their constraint forces eliminated from the whole-body QP.

Springs held rigid (Cassie): per leg the knee-tarsus coupling (the achilles
tendon) and the shin spring can be held rigid by constraint forces
``lambda`` (N m). With ``rigid_springs="swing"`` only the swing leg's springs
are held rigid, as in the paper (section "Springs": the swing-leg deflection
is small, the leg is treated as rigid), and the stance leg keeps its exact
spring model (the tendon and shin springs in ``taup``), which the closed
chain through the ground makes controllable. ``"all"`` (the default) holds
both legs rigid, ``"none"`` keeps every spring as a spring. Rigid is not what
the plant does: the swing leg's spring modes are not controllable by an
instantaneous QP (the QP cannot change this tick's spring torque and fights
the 25 Hz tarsus mode with large accelerations); holding them rigid toward
zero deflection matches what the unloaded spring does anyway.

``lambda`` is not a decision variable: the held springs act on as many
passive joints as there are held springs (Cassie: per leg the shin and the
tarsus for the shin spring and the tendon), so those joints' rows ``P`` of
the dynamics, ``(D x + h - taup)_P = G_P^T lambda`` with ``D = [M | -Jf^T]``,
determine it: ``lambda = G_P^-T (D_P x + (h - taup)_P)``, an affine map of
``x``. Substituting it into the other rows (``G^T lambda`` also acts on the
knee) removes ``lambda`` and the P rows from the problem: an exact
elimination that makes the QP smaller (measured: docs/TUNING.md, "QP tracker").

Torques are not variables either; they are the actuated rows,
``tau = M_a vdot + h_a - taup_a - J_a^T f - G_a^T lambda`` (N m), an affine map
``tau = T x + tau0``. One row map ``R`` per stance gives all three:
``R [D | hp]`` stacks the dynamics equalities (kept unactuated rows), the
torque map ``[T | tau0]`` and ``[Lam | lam0]`` (``lambda = Lam x + lam0``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import casadi as ca
import numpy as np

from amlip_qp.alip import other_side
from amlip_qp.control.wbc.inputs import dm
from amlip_qp.exceptions import InputError

if TYPE_CHECKING:
    from amlip_qp.control.wbc.config import QPConfig
    from amlip_qp.control.wbc.inputs import SymbolicInputs, TickInputs
    from amlip_qp.control.wbc.layout import VariableLayout
    from amlip_qp.robots.robot import Robot


@dataclass(frozen=True)
class LegSprings:
    """The springs of one leg the QP can hold rigid: its couplings and its
    passive joints with a spring. Deflection ``g = Gq q - rest`` (rad), rate ``G v``.

    Attributes:
        G: (n, nv) rate rows.
        Gq: (n, nq) configuration rows.
        rest: (n,) rest offsets, rad.
    """

    G: np.ndarray
    Gq: np.ndarray
    rest: np.ndarray

    @classmethod
    def of_robot(cls, robot: Robot) -> dict[str, LegSprings]:
        """Per foot side, the leg's springs (``robot.springs``)."""
        nv, nq = robot.nv, robot.nq
        out = {}
        for side in robot.foot_sides:
            rows = [r for r in robot.springs if r.side == side and (r.kind == "coupling" or r.stiffness > 0)]
            out[side] = cls(
                np.array([r.row_v(nv) for r in rows]).reshape(len(rows), nv),
                np.array([r.row_q(nq) for r in rows]).reshape(len(rows), nq),
                np.array([r.rest for r in rows], dtype=float),
            )
        return out


def springs_per_leg(leg_springs: dict[str, LegSprings]) -> int:
    """The number of springs of each leg.

    Raises:
        InputError: The legs have different numbers.
    """
    n_r = {len(s.G) for s in leg_springs.values()}
    if len(n_r) != 1:
        raise InputError("both legs need the same number of springs/couplings")
    return n_r.pop()


@dataclass(frozen=True)
class StanceRows:
    """Per stance: the row map of the dynamics and the springs held rigid.

    ``R @ [M | -Jf^T]`` stacks the dynamics equalities' matrix (its kept
    unactuated rows, rigid-spring forces substituted), ``T`` and ``Lam``;
    ``R @ hp`` stacks ``-b_dyn``, ``tau0`` and ``lam0``. Without rigid springs
    ``R`` only selects rows.

    Attributes:
        R: (n_dyn + nu + n_lambda, nv) row map.
        G: (n_lambda, nv) rigid-spring rows, stance leg then swing leg: ``G vdot = -kp g - kd G v``.
        kpGq: ``kp`` times the deflections' q-coefficients, (n_lambda, nq).
        kdG: ``kd * G``.
        kp_offs: ``kp`` times the rest offsets.
    """

    R: np.ndarray
    G: np.ndarray
    kpGq: np.ndarray
    kdG: np.ndarray
    kp_offs: np.ndarray


class SpringElimination:
    """The :class:`StanceRows` of both stances (see the module doc), made once.

    Args:
        robot: The robot.
        layout: The variable layout (its ``n_rigid_st``, ``n_rigid_sw``: springs held per leg).
        config: Gains of the rigid-spring rows (``coupling_kp``, ``coupling_kd``,
            ``stance_coupling_kp``, ``stance_coupling_kd``).
        leg_springs: Per side, the leg's springs (default: :meth:`LegSprings.of_robot`).

    Attributes:
        n_dyn: Number of dynamics equalities (unactuated rows less the eliminated ones).
        act_v: Velocity indices of the actuated joints.

    Raises:
        InputError: A held leg does not have exactly one passive joint per
            held spring, or its spring block ``G_P`` is singular: its
            constraint forces cannot be eliminated (use ``rigid_springs="none"``).
    """

    def __init__(
        self, robot: Robot, layout: VariableLayout, config: QPConfig, leg_springs: dict[str, LegSprings] | None = None
    ):
        self.robot = robot
        self.layout = layout
        self.config = config
        self.leg_springs = LegSprings.of_robot(robot) if leg_springs is None else leg_springs
        self.act_v = np.asarray(robot.actuated.pin_v_idx, dtype=int)
        self._unact_v = np.setdiff1d(np.arange(robot.nv), self.act_v)
        self.n_dyn = self._unact_v.size - layout.n_lambda
        L = layout
        self._kp = np.r_[np.full(L.n_rigid_st, config.stance_coupling_kp), np.full(L.n_rigid_sw, config.coupling_kp)]
        self._kd = np.r_[np.full(L.n_rigid_st, config.stance_coupling_kd), np.full(L.n_rigid_sw, config.coupling_kd)]
        self._rows = {side: self._eliminate(side) for side in robot.foot_sides}

    def rows(self, stance: str) -> StanceRows:
        """The :class:`StanceRows` of ``stance``."""
        return self._rows[stance]

    def _eliminate(self, stance: str) -> StanceRows:
        # Every row r reads (D - K D_P) x + (hp - K hp_P) with K = G^T GpiT
        # (zero on P itself), GpiT = G_P^-T: R_r = e_r - K_r S_P.
        L, robot = self.layout, self.robot
        nv = robot.nv
        swing = other_side(stance)
        sides = ([stance] if L.n_rigid_st else []) + ([swing] if L.n_rigid_sw else [])
        eye = np.eye(nv)
        if sides:
            G = np.vstack([self.leg_springs[s].G for s in sides])
            Gq = np.vstack([self.leg_springs[s].Gq for s in sides])
            offs = np.concatenate([self.leg_springs[s].rest for s in sides])
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
        R = np.vstack([reduce[dyn_rows], reduce[self.act_v], lam_rows])
        kp, kd = self._kp, self._kd
        return StanceRows(R=R, G=G, kpGq=kp[:, None] * Gq, kdG=kd[:, None] * G, kp_offs=kp * offs)


@dataclass
class SymbolicDynamics:
    """:class:`ReducedDynamics`' terms as CasADi expressions (one stance)."""

    RD: ca.MX
    Rhp: ca.MX
    T: ca.MX
    tau0: ca.MX
    Lam: ca.MX
    lam0: ca.MX


class ReducedDynamics:
    """The dynamics with the rigid-spring forces eliminated, at the last build.

    Attributes:
        elimination: The :class:`SpringElimination`.
        RD: ``R [M | -Jf^T]`` (n_dyn + nu + n_lambda, n): the dynamics
            equalities' rows, then ``T``, then ``Lam`` (views below).
        Rhp: ``R (h - taup)``: ``-b_dyn``, then ``tau0``, then ``lam0``.
        T, tau0: Torque map ``tau = T x + tau0`` (N m), views of ``RD`` and ``Rhp``.
        Lam, lam0: Rigid-spring forces ``lambda = Lam x + lam0`` (N m), views.
        G: The rigid-spring rows of the last build's stance (n_lambda, nv).
    """

    def __init__(self, elimination: SpringElimination):
        self.elimination = elimination
        L = elimination.layout
        n_dyn, nu, n_lambda = elimination.n_dyn, elimination.act_v.size, L.n_lambda
        self._D = np.zeros((L.nv, L.n))
        self._lower = np.tril_indices(L.nv, -1)
        self.RD = np.zeros((n_dyn + nu + n_lambda, L.n))
        self.Rhp = np.zeros(n_dyn + nu + n_lambda)
        self.T = self.RD[n_dyn : n_dyn + nu]
        self.tau0 = self.Rhp[n_dyn : n_dyn + nu]
        self.Lam = self.RD[n_dyn + nu :]
        self.lam0 = self.Rhp[n_dyn + nu :]
        self.G = np.zeros((n_lambda, L.nv))

    def update(self, inputs: TickInputs) -> None:
        """Fill :attr:`RD` and :attr:`Rhp` from ``inputs`` (numpy)."""
        L, D = self.elimination.layout, self._D
        M = D[:, L.sl_vdot]
        M[...] = inputs.mass_upper
        M[self._lower] = M.T[self._lower]  # the symmetric M from its upper triangle
        np.negative(inputs.Jf.T, out=D[:, L.sl_forces])
        rs = self.elimination.rows(inputs.stance)
        np.matmul(rs.R, D, out=self.RD)
        np.matmul(rs.R, inputs.hp, out=self.Rhp)
        self.G = rs.G

    def filled_for(self, stance: str) -> None:
        """Record that :attr:`RD` and :attr:`Rhp` were filled for ``stance`` by another backend."""
        self.G = self.elimination.rows(stance).G

    def symbolic(self, sym: SymbolicInputs) -> SymbolicDynamics:
        """The same terms as expressions of the symbols ``sym``."""
        R = dm(self.elimination.rows(sym.stance).R)
        n_dyn, nu = self.elimination.n_dyn, self.elimination.act_v.size
        D = ca.horzcat(sym.mass_matrix, -sym.JfT)
        RD = ca.mtimes(R, D)
        Rhp = ca.mtimes(R, sym.hp)
        T, tau0 = RD[n_dyn : n_dyn + nu, :], Rhp[n_dyn : n_dyn + nu]
        return SymbolicDynamics(RD, Rhp, T, tau0, RD[n_dyn + nu :, :], Rhp[n_dyn + nu :])

    def torques(self, x: np.ndarray) -> np.ndarray:
        """Joint torques (N m, actuator order) of a solution of the last built problem."""
        return self.T @ x + self.tau0

    def rigid_forces(self, x: np.ndarray) -> np.ndarray:
        """The rigid-spring constraint forces ``lambda`` (N m; stance leg then
        swing leg, per leg the couplings then the spring joints) of a solution."""
        return self.Lam @ x + self.lam0
