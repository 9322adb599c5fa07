"""One evaluation of the iterative IK's system at an iterate, in Python: the readable reference.

:class:`~amlip_qp.control.pbc.ik.IterativeIK` solves the square system ``F(q) = 0`` of
:mod:`~amlip_qp.control.pbc.ik_equations` by Newton steps. Each step needs, at the iterate
``q``: the varying rows of the matrix ``A`` (the outputs' Jacobian, then the stance contact
frame's world-aligned Jacobian rows), the residual

- ``F[:n] = y(q) - h_d`` (the outputs against their references),
- the stance contact pose against its estimate: position ``p(q) - p_est`` (m) and orientation
  ``log3(R(q) R_est^T)`` (rad, a world-axes rotation vector); a planar robot keeps x, z and
  pitch,
- ``F[n_var:] = L_q q - b`` (the linear rows: held ankle, posture, springs),

and, after the last iterate of a tick updated with a velocity ``v``, the drift ``Adot v`` of
the varying rows.

Two classes give these with the same interface: :class:`PythonIKEvaluation` here (Pinocchio's
getters and ``pinocchio.log3``) and
:class:`~amlip_qp.control.pbc.ik_compiled.CompiledIKEvaluation` (one call of generated C
reading Pinocchio's arrays in place; the same bits on the generated output map). Both keep
the values of the last evaluation (:meth:`PythonIKEvaluation.keep`) so that the next tick's
first Newton step re-forms the residual at the same ``q`` with that tick's targets
(:meth:`PythonIKEvaluation.kept_residual`) without evaluating the kinematics again.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:  # pragma: no cover - typing only
    from amlip_qp.control.pbc.ik_equations import IKEquations, StanceRows
    from amlip_qp.robots.kinematics import RobotKinematics


class PythonIKEvaluation:
    """The IK's evaluation with Pinocchio's getters (see the module doc).

    Args:
        equations: The IK's :class:`~amlip_qp.control.pbc.ik_equations.IKEquations`.
        n_out: Number of outputs ``n``.

    Attributes:
        backend: ``"python"``.
        y: The outputs (m, rad) of the last :meth:`evaluate` (read-only).
    """

    backend = "python"

    def __init__(self, equations: IKEquations, n_out: int):
        import pinocchio as pin

        robot = equations.robot
        self._log3 = pin.log3
        self._robot = robot
        self._rows = equations.rows
        self._n = n_out
        self._npose = len(equations.pose_rows)
        # the pose rows as a slice (x, z, pitch: every other row; all six), read as a view
        self._pose = slice(0, 5, 2) if robot.is_planar else slice(0, 6)
        self._planar = robot.is_planar
        self._targets: tuple = ()
        self.y = np.zeros(n_out)
        self._last: tuple = ()
        self._kept: tuple = ()

    def set_targets(self, stance: str, h_d: np.ndarray, fixed: dict) -> None:
        """This tick's references ``h_d`` and held quantities (``fixed``: ``contact_pos``,
        ``contact_rot``, ``lin``; :meth:`IterativeIK.solve <amlip_qp.control.pbc.ik.IterativeIK.solve>`)."""
        self._targets = (h_d, fixed)

    def evaluate(self, kin: RobotKinematics, stance: str, q, heading_rad: float, v=None, eps: bool = False):
        """Update ``kin`` at ``q`` (with ``v``: the kinematics-only update, whose drifts
        :meth:`drift` reads; without: the light position update), fill the varying rows of the
        stance's ``A`` (of ``A_eps`` if ``eps``) and return the residual ``F`` (the stance's
        buffer; ``None`` if ``eps``)."""
        if v is None:
            kin.update_positions(q)
        else:
            kin.update_kinematics(q, v)
        y, J, _ = kin.outputs(stance, heading_rad)
        rows = self._rows[stance]
        A = rows.A_eps if eps else rows.A
        n = self._n
        A[:n] = J
        cid = self._robot.contact_frame_ids[stance]
        A[n : n + self._npose] = kin.frame_jacobian6(cid)[self._pose]
        if eps:
            return None
        pos, rot = kin.frame_position(cid), kin.frame_rotation(cid)
        self.y = y
        self._last = (y, pos, rot)
        return self._residual(rows, q, y, pos, rot)

    def keep(self, stance: str) -> None:
        """Keep the last evaluation's values (of ``stance``) for :meth:`kept_residual`."""
        self._kept = self._last

    def kept_residual(self, stance: str, q) -> np.ndarray:
        """``F`` at the kept evaluation (its ``q``, given again) with the current targets."""
        y, pos, rot = self._kept
        return self._residual(self._rows[stance], q, y, pos, rot)

    def drift(self, kin: RobotKinematics, stance: str, heading_rad: float) -> np.ndarray:
        """``Adot v`` of the varying rows at the last :meth:`evaluate` with a ``v`` (the stance's buffer)."""
        out = self._rows[stance].drift
        n = self._n
        out[:n] = kin.outputs(stance, heading_rad)[2]
        out[n : n + self._npose] = kin.frame_jdot_v6(self._robot.contact_frame_ids[stance])[self._pose]
        return out

    def _residual(self, rows: StanceRows, q, y, pos, rot) -> np.ndarray:
        """Fill and return ``F(q)`` from the evaluated values and this tick's targets/estimates."""
        h_d, fixed = self._targets
        F, n = rows.F, self._n
        np.subtract(y, h_d, out=F[:n])
        r_err = self._log3(rot @ fixed["contact_rot"].T)
        if self._planar:
            p_err = pos - fixed["contact_pos"]
            F[n], F[n + 1], F[n + 2] = p_err[0], p_err[2], r_err[1]
        else:
            np.subtract(pos, fixed["contact_pos"], out=F[n : n + 3])
            F[n + 3 : n + 6] = r_err
        np.subtract(np.dot(rows.lin_q, q), fixed["lin"], out=F[rows.n_var :])
        return F
