"""The decision variables of the whole-body QP and where each lives in ``x``.

``x = [vdot, f_st, f_sw]``:

- ``vdot`` (nv): generalized accelerations (Pinocchio ``v`` coordinates),
  m/s^2 and rad/s^2;
- ``f_st``, ``f_sw``: world-frame contact point forces of the **stance** and
  **swing** foot, N. Cassie: toe then heel sphere centre, 3-D each (6 per
  foot); a four-point sole: its corners, toe left, toe right, heel left,
  heel right (12 per foot); Rabbit (planar): the point foot, ``(f_x, f_z)``
  (2 per foot). The stance foot's block always comes first, so the dimensions never change
  and one persistent solver serves the whole walk (two with
  ``QPTracker(airborne_reduction=True)``, the default: the problem without
  the airborne swing foot's block is the other).

The rigid-spring constraint forces ``lambda`` are not variables (they are
eliminated, :mod:`amlip_qp.control.wbc.spring_elimination`); the layout only
counts them.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from amlip_qp.exceptions import InputError

if TYPE_CHECKING:
    from amlip_qp.robots.robot import Robot


@dataclass
class VariableLayout:
    """Variable slices and sizes of the whole-body QP.

    Attributes:
        nv: Number of generalized accelerations.
        point_dim: Force components per point: 3 (x, y, z) or 2 for a planar robot (x, z).
        n_points: Force points per foot (1: point foot, 2: Cassie's blade, toe then heel; 4: a
            sole's corners, toe left, toe right, heel left, heel right).
        n_rigid_st: Springs of the stance leg held rigid (eliminated forces, no variables).
        n_rigid_sw: Springs of the swing leg held rigid.
        sl_vdot: Slice of ``vdot`` in ``x``.
        sl_f_st: Slice of the stance foot's forces.
        sl_f_sw: Slice of the swing foot's forces.
        n: Number of variables.
        axes: World axes of the force components: ``[0, 2]`` (planar) or ``[0, 1, 2]``.
        axes_index: :attr:`axes` as an index; a slice in 3-D, which avoids a fancy-indexing copy.
    """

    nv: int
    point_dim: int
    n_points: int
    n_rigid_st: int
    n_rigid_sw: int
    sl_vdot: slice = field(init=False)
    sl_f_st: slice = field(init=False)
    sl_f_sw: slice = field(init=False)
    n: int = field(init=False)
    axes: np.ndarray = field(init=False, repr=False, compare=False)
    axes_index: np.ndarray | slice = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        nf = self.point_dim * self.n_points
        self.sl_vdot = slice(0, self.nv)
        self.sl_f_st = slice(self.nv, self.nv + nf)
        self.sl_f_sw = slice(self.nv + nf, self.nv + 2 * nf)
        self.n = self.sl_f_sw.stop
        self.axes = np.array([0, 2]) if self.planar else np.array([0, 1, 2])
        self.axes_index = self.axes if self.planar else slice(0, 3)

    @classmethod
    def for_robot(cls, robot: Robot, n_rigid_st: int, n_rigid_sw: int) -> VariableLayout:
        """The layout of ``robot``'s feet (point feet, a 3-D two-point blade or a 3-D four-point sole).

        Raises:
            InputError: Feet with different or zero numbers of force points, or an unsupported foot.
        """
        n_points = {len(robot.force_frame_ids[s]) for s in robot.foot_sides}
        if len(n_points) != 1 or n_points == {0}:
            raise InputError("both feet need the same (nonzero) number of force points")
        k = n_points.pop()
        if k not in (1, 2, 4) or (k > 1 and robot.is_planar):
            raise InputError(
                "supported feet: one point (3-D or planar), a 3-D blade of two points or a 3-D sole of four"
            )
        return cls(robot.nv, 2 if robot.is_planar else 3, k, n_rigid_st, n_rigid_sw)

    @property
    def n_lambda(self) -> int:
        """Number of rigid-spring constraint forces (eliminated, not variables)."""
        return self.n_rigid_st + self.n_rigid_sw

    @property
    def n_force(self) -> int:
        """Force variables per foot."""
        return self.point_dim * self.n_points

    @property
    def sl_forces(self) -> slice:
        """Slice of both feet's forces, stance then swing."""
        return slice(self.sl_f_st.start, self.sl_f_sw.stop)

    @property
    def planar(self) -> bool:
        """True when the force points have the planar components (x, z)."""
        return self.point_dim == 2

    def normal_index(self, foot: slice) -> np.ndarray:
        """Indices in ``x`` of the normal (vertical) component of each point of ``foot`` (a force slice)."""
        d = self.point_dim
        return foot.start + d * np.arange(self.n_points) + d - 1

    def tangential_index(self, foot: slice) -> np.ndarray:
        """Indices in ``x`` of the tangential components of each point of ``foot`` (a force slice)."""
        d = self.point_dim
        return np.array([foot.start + d * p + t for p in range(self.n_points) for t in range(d - 1)], dtype=int)
