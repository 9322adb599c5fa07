"""Frame Jacobians and drifts as CasADi expressions of Pinocchio's joint terms, read in place.

After ``computeAllTerms`` and ``updateFramePlacements`` (what
:meth:`ModelKinematics.update <amlip_qp.robots.model_kinematics.ModelKinematics.update>`
runs), Pinocchio's data holds every joint's world Jacobian columns ``data.J``,
its world rotation ``data.oMi[i].rotation``, its spatial velocity and its
acceleration at ``vdot = 0`` in its own frame (``data.v[i]``, ``data.a[i]``),
the frames' positions ``data.oMf[f].translation`` and the CoM terms. Python
reads a frame's world-aligned Jacobian and drift through one Pinocchio call
each (``getFrameJacobian``, ``getFrameClassicalAcceleration``), a new array a
call. :class:`FrameTerms` forms the same quantities as expressions of those
arrays, so that generated code can read Pinocchio's storage directly: the
arrays are bound once to a generated function's inputs (:meth:`FrameTerms.views`)
and every later update overwrites them in place.

For a frame ``f`` on joint ``i`` at ``p`` (world, m), with ``S`` the velocity
columns of ``i``'s supporting joints (Pinocchio's ``getFrameJacobian`` with
``LOCAL_WORLD_ALIGNED``):

- Jacobian: linear rows ``J_lin[:, S] - p x J_ang[:, S]``, angular rows
  ``J_ang[:, S]``, zero outside ``S``;
- classical drift (``getFrameClassicalAcceleration``, world-aligned): with the
  frame's offset ``o`` in joint ``i``'s frame and ``R = oMi[i].rotation``,
  ``v_o = R (v_lin + w x o)``, ``w_o = R w``, linear ``R (a_lin + alpha x o) + w_o x v_o``,
  angular ``R alpha`` (m/s^2, rad/s^2).
"""

from __future__ import annotations

from collections.abc import Iterable

import casadi as ca
import numpy as np

from amlip_qp.codegen.output_map import skew


class FrameTerms:
    """Symbols of Pinocchio's terms for some frames, and expressions of their Jacobians and drifts.

    Args:
        model: The Pinocchio model.
        frame_ids: The frames whose terms are needed.
        rotation_frame_ids: Frames whose world rotation is needed too (e.g. the base).

    Attributes:
        symbols: ``(name, MX symbol)`` of every input, in a fixed order.
    """

    def __init__(self, model, frame_ids: Iterable[int], rotation_frame_ids: Iterable[int] = ()):
        nv = model.nv
        self.nv = nv
        self.frame_ids = tuple(dict.fromkeys(int(f) for f in frame_ids))
        self.rotation_frame_ids = tuple(dict.fromkeys(int(f) for f in rotation_frame_ids))
        self._joint = {f: int(model.frames[f].parentJoint) for f in self.frame_ids}
        self._offset = {f: np.array(model.frames[f].placement.translation, dtype=float) for f in self.frame_ids}
        self.joint_ids = tuple(dict.fromkeys(self._joint.values()))
        self._columns = {}
        for j in self.joint_ids:
            cols: list[int] = []
            for k in model.supports[j]:
                if k > 0:
                    joint = model.joints[k]
                    cols.extend(range(joint.idx_v, joint.idx_v + joint.nv))
            self._columns[j] = sorted(cols)
        sym = ca.MX.sym
        self.J = sym("J", 6, nv)
        self.Jcom = sym("Jcom", 3, nv)
        self.com = sym("com", 3)
        self.acom = sym("acom", 3)
        self._R = {j: sym(f"R_joint{j}", 3, 3) for j in self.joint_ids}
        self._v = {j: sym(f"v_joint{j}", 6) for j in self.joint_ids}
        self._a = {j: sym(f"a_joint{j}", 6) for j in self.joint_ids}
        self._p = {f: sym(f"p_frame{f}", 3) for f in self.frame_ids}
        self._Rf = {f: sym(f"R_frame{f}", 3, 3) for f in self.rotation_frame_ids}
        self.symbols: tuple[tuple[str, ca.MX], ...] = (
            ("J", self.J), ("Jcom", self.Jcom), ("com", self.com), ("acom", self.acom),
            *((f"R_joint{j}", self._R[j]) for j in self.joint_ids),
            *((f"v_joint{j}", self._v[j]) for j in self.joint_ids),
            *((f"a_joint{j}", self._a[j]) for j in self.joint_ids),
            *((f"p_frame{f}", self._p[f]) for f in self.frame_ids),
            *((f"R_frame{f}", self._Rf[f]) for f in self.rotation_frame_ids),
        )  # fmt: skip

    def views(self, data) -> list[np.ndarray]:
        """Live views of ``data``'s arrays, in the order of :attr:`symbols` (column-major
        where a matrix: Pinocchio's own storage, which every update overwrites in place)."""
        out = [data.J, data.Jcom, data.com[0], data.acom[0]]
        out += [data.oMi[j].rotation for j in self.joint_ids]
        out += [data.v[j].vector for j in self.joint_ids]
        out += [data.a[j].vector for j in self.joint_ids]
        out += [data.oMf[f].translation for f in self.frame_ids]
        out += [data.oMf[f].rotation for f in self.rotation_frame_ids]
        return out

    def position(self, frame_id: int) -> ca.MX:
        """The frame's world position (m), (3,)."""
        return self._p[frame_id]

    def rotation(self, frame_id: int) -> ca.MX:
        """The world rotation of a frame of ``rotation_frame_ids``, (3, 3)."""
        return self._Rf[frame_id]

    def jacobian(self, frame_id: int) -> ca.MX:
        """The frame's world-aligned Jacobian (6, nv): linear rows, then angular."""
        cols = self._columns[self._joint[frame_id]]
        lin, ang = self.J[0:3, cols], self.J[3:6, cols]
        local = ca.vertcat(lin - ca.mtimes(skew(self._p[frame_id]), ang), ang)
        full = ca.MX(6, self.nv)
        full[:, cols] = local
        return full

    def drift(self, frame_id: int) -> ca.MX:
        """The frame's world-aligned classical acceleration at ``vdot = 0`` (6,): linear, angular."""
        j = self._joint[frame_id]
        R, vj, aj = self._R[j], self._v[j], self._a[j]
        o = ca.DM(self._offset[frame_id])
        w, alpha = vj[3:6], aj[3:6]
        v_o = ca.mtimes(R, vj[0:3] + ca.cross(w, o))
        w_o = ca.mtimes(R, w)
        lin = ca.mtimes(R, aj[0:3] + ca.cross(alpha, o)) + ca.cross(w_o, v_o)
        return ca.vertcat(lin, ca.mtimes(R, alpha))


def output_frame_terms(output_map, also: Iterable[int] = ()) -> FrameTerms:
    """The Pinocchio terms an output map reads (both stances: the base, the points and the rotating
    frames; :func:`~amlip_qp.codegen.output_map.output_map_on_terms`), and the frames ``also``
    (their positions and rotations too).

    Args:
        output_map: The robot's :class:`~amlip_qp.robots.outputs.OutputMap`.
        also: More frame ids.
    """
    robot = output_map.robot
    frames: list[int] = [robot.base_frame_id]
    rotating: list[int] = []
    for side in robot.foot_sides:
        frames += output_map.points(side)
        rotating += output_map.rotating_frames(side)
    also = [int(f) for f in also]
    return FrameTerms(robot.pin_model, frames + rotating + also, [robot.base_frame_id, *rotating, *also])
