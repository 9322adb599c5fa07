"""The costs of the whole-body QP, as objects of one shape.

The objective is ``1/2 x^T H x + g^T x`` with

- a constant part, folded once into :class:`ConstantCost`: the Hessian
  ``H0`` and, on ``vdot``, the affine gradient ``Kq q + Kv v + k0``
  (regularisation of ``vdot`` and forces, tasks with a constant Jacobian);
- stacked least-squares rows ``||E x + e||^2`` refilled every tick (the
  output task, the torque and rigid-spring force regularisations), giving
  ``H += E^T E`` and ``g += E^T e``;
- terms added straight to ``H`` after those products (the stance yaw
  moment, a rank-one term).

A :class:`Cost` may contribute to each: :meth:`~Cost.fold` (once),
:meth:`~Cost.write` (its :attr:`~Cost.rows` of ``E, e``) and
:meth:`~Cost.add_to_hessian` (per tick, numpy), and :meth:`~Cost.symbolic`
gives its per-tick terms as rows of ``E, e`` for the generated build.
:class:`~amlip_qp.control.wbc.builder.WholeBodyQP` and
:class:`~amlip_qp.control.wbc.compiled.CompiledBuild` iterate the same list.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import casadi as ca
import numpy as np

from amlip_qp.control.wbc.inputs import dm

if TYPE_CHECKING:
    from amlip_qp.control.wbc.inputs import SymbolicInputs, TickInputs
    from amlip_qp.control.wbc.layout import VariableLayout
    from amlip_qp.control.wbc.spring_elimination import ReducedDynamics, SymbolicDynamics
    from amlip_qp.control.wbc.tasks import JointTask, OutputTask


class ConstantCost:
    """The state-independent part of the cost (filled by :meth:`Cost.fold`).

    Attributes:
        H0: Constant Hessian (n, n).
        Kq: Gradient on ``vdot`` per configuration, (nv, nq).
        Kv: Gradient on ``vdot`` per velocity, (nv, nv).
        k0: Constant gradient on ``vdot``, (nv,).
    """

    def __init__(self, n: int, nv: int, nq: int):
        self.H0 = np.zeros((n, n))
        self.Kq = np.zeros((nv, nq))
        self.Kv = np.zeros((nv, nv))
        self.k0 = np.zeros(nv)


class Cost:
    """One term of the objective (see the module doc).

    Attributes:
        name: Name (diagnostics).
        rows: Its rows of ``E, e`` in the numpy build (set by :meth:`place`; may be empty).
    """

    def __init__(self, name: str, size: int = 0):
        self.name = name
        self.rows = slice(0, size)

    @property
    def size(self) -> int:
        """Number of rows of ``E, e`` in the numpy build."""
        return self.rows.stop - self.rows.start

    def place(self, start: int) -> int:
        """Put the rows at ``start``; return the next free row."""
        self.rows = slice(start, start + self.size)
        return self.rows.stop

    def fold(self, constant: ConstantCost) -> None:
        """Add the state-independent part (once)."""

    def write(self, inputs: TickInputs, dynamics: ReducedDynamics, E: np.ndarray, e: np.ndarray) -> None:
        """Write this tick's rows ``E`` (size x n) and ``e`` (size), views of the stacked rows."""

    def add_to_hessian(self, inputs: TickInputs, H: np.ndarray) -> None:
        """Add this tick's direct Hessian term to ``H`` (C-contiguous), after ``E^T E``."""

    def symbolic(self, sym: SymbolicInputs, dyn: SymbolicDynamics) -> list[tuple[ca.MX, ca.MX]]:
        """This tick's terms as ``(E rows, e rows)`` expressions."""
        return []


class Regularization(Cost):
    """``reg_vdot |vdot|^2 + reg_force |f|^2`` (constant Hessian diagonal)."""

    def __init__(self, layout: VariableLayout, reg_vdot: float, reg_force: float):
        super().__init__("regularization")
        self.layout, self.reg_vdot, self.reg_force = layout, reg_vdot, reg_force

    def fold(self, constant: ConstantCost) -> None:
        L, H0 = self.layout, constant.H0
        di = np.arange(L.n)
        H0[di[L.sl_vdot], di[L.sl_vdot]] += self.reg_vdot
        fi = np.arange(L.sl_f_st.start, L.sl_f_sw.stop)
        H0[fi, fi] += self.reg_force


class JointTaskCost(Cost):
    """A task with a constant Jacobian (:class:`~amlip_qp.control.wbc.tasks.JointTask`):
    ``||W^(1/2) (C vdot + r)||^2`` with ``r`` affine in the state, all folded once."""

    def __init__(self, layout: VariableLayout, task: JointTask):
        super().__init__(task.name)
        self.layout, self.task = layout, task

    def fold(self, constant: ConstantCost) -> None:
        task, sv = self.task, self.layout.sl_vdot
        J = task.jacobian(None, None)
        constant.H0[sv, sv] += (J.T * task.gains.weight) @ J
        # The gradient W J^T r is affine in the state: Kq q + Kv v + k0.
        WJ = J.T * task.gains.weight
        cols_q, Rq, cols_v, Rv, r0 = task.affine_residual()
        constant.Kq[:, cols_q] += WJ @ Rq
        constant.Kv[:, cols_v] += WJ @ Rv
        constant.k0 += WJ @ r0


class OutputTaskCost(Cost):
    """The output task ``||W^(1/2) (J vdot + r)||^2``
    (:class:`~amlip_qp.control.wbc.tasks.OutputTask`), its residual lowered
    by the pelvis-yaw feedback's shift
    (:class:`~amlip_qp.control.pelvis_yaw.PelvisYawFeedback`)."""

    def __init__(self, layout: VariableLayout, task: OutputTask):
        super().__init__(task.name, task.size)
        self.layout, self.task = layout, task
        self.sqrt_weight = np.sqrt(task.gains.weight)

    def write(self, inputs: TickInputs, dynamics: ReducedDynamics, E: np.ndarray, e: np.ndarray) -> None:
        sw = self.sqrt_weight
        np.multiply(inputs.output_jacobian, sw[:, None], out=E[:, self.layout.sl_vdot])
        np.multiply(inputs.output_residual, sw, out=e)
        if inputs.feedback is not None:
            i = inputs.feedback.swing_index
            e[i] -= sw[i] * inputs.residual_shift

    def symbolic(self, sym: SymbolicInputs, dyn: SymbolicDynamics) -> list[tuple[ca.MX, ca.MX]]:
        L, sw = self.layout, self.sqrt_weight
        E = ca.horzcat(ca.mtimes(ca.diag(dm(sw)), sym.JoT.T), ca.MX(sw.size, L.n - L.nv))
        return [(E, dm(sw) * sym.output_residual)]


class TorqueRegularization(Cost):
    """``reg_torque |tau|^2`` with ``tau = T x + tau0`` (rows ``sqrt(reg) (T x + tau0)``; none for 0)."""

    def __init__(self, nu: int, reg_torque: float):
        super().__init__("torque_regularization", nu if reg_torque > 0 else 0)
        self.scale = math.sqrt(reg_torque)

    def write(self, inputs: TickInputs, dynamics: ReducedDynamics, E: np.ndarray, e: np.ndarray) -> None:
        np.multiply(dynamics.T, self.scale, out=E)
        np.multiply(dynamics.tau0, self.scale, out=e)

    def symbolic(self, sym: SymbolicInputs, dyn: SymbolicDynamics) -> list[tuple[ca.MX, ca.MX]]:
        return [(self.scale * dyn.T, self.scale * dyn.tau0)] if self.size else []


class RigidSpringForceRegularization(Cost):
    """``reg_coupling |lambda|^2`` with ``lambda = Lam x + lam0`` (the eliminated rigid-spring forces)."""

    def __init__(self, n_lambda: int, reg_coupling: float):
        super().__init__("rigid_spring_force_regularization", n_lambda if reg_coupling > 0 else 0)
        self.scale = math.sqrt(reg_coupling)

    def write(self, inputs: TickInputs, dynamics: ReducedDynamics, E: np.ndarray, e: np.ndarray) -> None:
        np.multiply(dynamics.Lam, self.scale, out=E)
        np.multiply(dynamics.lam0, self.scale, out=e)

    def symbolic(self, sym: SymbolicInputs, dyn: SymbolicDynamics) -> list[tuple[ca.MX, ca.MX]]:
        return [(self.scale * dyn.Lam, self.scale * dyn.lam0)] if self.size else []


class StanceYawMomentCost(Cost):
    """``w M_z^2``: the yaw moment of the stance foot's point forces about
    their mean point (3-D feet of two or four points). Two points:
    ``M_z = a . (f0_x, f0_y, f1_x, f1_y)`` with ``a = (-dy, dx, dy, -dx)``,
    ``(dx, dy) = (p0 - p1)_xy / 2``. Four points: ``M_z = sum_p a_p . (fp_x, fp_y)``
    with ``a_p = (-dy_p, dx_p)``, ``(dx_p, dy_p) = (p_p - mean)_xy``.

    The numpy build adds the rank-one ``w a a^T`` to ``H`` after ``E^T E``;
    the generated build stacks it as the row ``sqrt(w) a^T`` of ``E``.
    """

    def __init__(self, layout: VariableLayout, weight: float):
        super().__init__("stance_yaw_moment")
        self.layout, self.weight = layout, weight
        c, n = layout.sl_f_st.start, layout.n
        #: The stance force entries the moment depends on: each point's x and y.
        self.index = np.array([c + 3 * p + t for p in range(layout.n_points) for t in (0, 1)])
        self._flat = (self.index[:, None] * n + self.index[None, :]).ravel()

    @staticmethod
    def applies(layout: VariableLayout, weight: float) -> bool:
        """True for a positive weight and 3-D feet of two or four points."""
        return weight > 0 and not layout.planar and layout.n_points in (2, 4)

    def add_to_hessian(self, inputs: TickInputs, H: np.ndarray) -> None:
        if self.layout.n_points == 2:
            p0, p1 = inputs.point_positions
            # M_z = sum_p (r_p - mid) x f_p . e_z; r_0 - mid = -(r_1 - mid) = (p0 - p1) / 2.
            dx, dy = 0.5 * (p0[0] - p1[0]), 0.5 * (p0[1] - p1[1])
            a = np.array([-dy, dx, dy, -dx])
        else:
            P = inputs.point_positions
            mx = 0.25 * (P[0][0] + P[1][0] + P[2][0] + P[3][0])
            my = 0.25 * (P[0][1] + P[1][1] + P[2][1] + P[3][1])
            a = np.array([c for p in P for c in (my - p[1], p[0] - mx)])
        Hf = H.reshape(-1)  # a view of the C-contiguous H
        Hf[self._flat] += self.weight * np.multiply.outer(a, a).reshape(-1)

    def symbolic(self, sym: SymbolicInputs, dyn: SymbolicDynamics) -> list[tuple[ca.MX, ca.MX]]:
        con, n, k = sym.contact, self.layout.n, self.layout.n_points
        if k == 2:
            dxy = 0.5 * (con[0:2] - con[3:5])
            a = ca.vertcat(-dxy[1], dxy[0], dxy[1], -dxy[0])
        else:
            mid = 0.25 * (con[0:2] + con[3:5] + con[6:8] + con[9:11])
            a = ca.vertcat(*[c for p in range(4) for c in (mid[1] - con[3 * p + 1], con[3 * p] - mid[0])])
        place = np.zeros((n, 2 * k))
        place[self.index, np.arange(2 * k)] = 1.0
        return [(math.sqrt(self.weight) * ca.mtimes(ca.DM(ca.sparsify(dm(place))), a).T, ca.MX(1, 1))]
