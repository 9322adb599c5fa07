"""The PBC's constrained dynamics system as generated C that reads Pinocchio's arrays in place.

:meth:`PBCTracker.solve_dynamics <amlip_qp.control.pbc.tracker.PBCTracker.solve_dynamics>`
solves the square system of equations (1)-(3) of :mod:`amlip_qp.control.pbc.tracker` in
``x = (vdot, tau_ctrl, lambda)``. Its Python assembly is the readable reference
(:meth:`PBCTracker.assemble_dynamics <amlip_qp.control.pbc.tracker.PBCTracker.assemble_dynamics>`):
the mass matrix, the stance contact's rows (:mod:`~amlip_qp.control.pbc.contact_rows`:
the contact frame's Jacobian and drift, and for a foot held along its sole line the two
rotation rows normal to it), the passive forces and ``h``, a dozen Pinocchio getters and
numpy calls a tick.
:class:`CompiledDynamics` writes the same matrix and right-hand side with one call
of C code that CasADi generates from the same definitions: its inputs are bound once
per Pinocchio data to Pinocchio's own storage (``M`` read above the diagonal, ``h``,
and :class:`~amlip_qp.codegen.frame_terms.FrameTerms` of the contact frame and the
sole line's ends), plus one small array a call (``q``, ``v`` and the controlled
joints' accelerations ``vdot_a`` of (3)); its outputs are the stance's own buffers
``K`` and ``rhs`` (:class:`~amlip_qp.control.pbc.stance_layout.StanceLayout`), so LAPACK's
solve reads them as they are. The passive forces are
:func:`~amlip_qp.control.passive_symbolic.passive_forces_expression`.

The two give the same system to rounding (``tests/test_control_pbc_dynamics_compiled.py``).
The C source depends on the robot and the stance layouts: it is compiled once into the
codegen cache (:mod:`amlip_qp.codegen.runtime`).
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from typing import TYPE_CHECKING

import casadi as ca
import numpy as np

from amlip_qp.codegen import generate, runtime
from amlip_qp.codegen.frame_terms import FrameTerms
from amlip_qp.control.passive_symbolic import passive_forces_expression

if TYPE_CHECKING:  # pragma: no cover - typing only
    from amlip_qp.control.pbc.stance_layout import StanceLayout
    from amlip_qp.robots.kinematics import RobotKinematics
    from amlip_qp.robots.robot import Robot

SOURCE_FILE = "amlip_pbc_dynamics.c"
LIBRARY_FILE = "libamlip_pbc_dynamics.so"
#: Name stem of the generated functions, ``<stem>_left`` and ``<stem>_right``.
FUNCTION_STEM = "pbc_dynamics"
#: Pinocchio data objects bound at once (a tracker reads the controller's kinematics).
MAX_BINDINGS = 4
#: Below this norm (of the sole line's horizontal part) the first blade normal is taken about x
#: instead of z, as :func:`~amlip_qp.control.pbc.contact_rows.contact_rows` does.
BLADE_NORMAL_MIN = 1e-6


def dynamics_terms(robot: Robot) -> FrameTerms:
    """The Pinocchio terms the functions read: each side's contact frame and sole line's ends."""
    frames: list[int] = []
    for side in robot.foot_sides:
        frames += [robot.contact_frame_ids[side], *robot.sole_line_frame_ids.get(side, ())]
    return FrameTerms(robot.pin_model, frames)


def contact_rows_expression(robot: Robot, terms: FrameTerms, stance: str, blade: bool):
    """The stance contact's rows ``(J, Jdot_v)`` as CasADi expressions (the rows of
    :func:`~amlip_qp.control.pbc.contact_rows.contact_rows`)."""
    cid = robot.contact_frame_ids[stance]
    J6, a6 = terms.jacobian(cid), terms.drift(cid)
    if robot.is_planar:
        return ca.vertcat(J6[0, :], J6[2, :]), ca.vertcat(a6[0], a6[2])
    if not blade:
        return J6[0:3, :], a6[0:3]
    toe_id, heel_id = robot.sole_line_frame_ids[stance]
    u = terms.position(toe_id) - terms.position(heel_id)
    u = u / ca.norm_2(u)
    n_z = ca.sqrt(u[1] * u[1] + u[0] * u[0])
    n_x = ca.sqrt(u[2] * u[2] + u[1] * u[1])
    about_z = n_z >= BLADE_NORMAL_MIN
    a = ca.if_else(about_z, ca.vertcat(u[1], -u[0], 0.0) / n_z, ca.vertcat(0.0, u[2], -u[1]) / n_x)
    b = ca.cross(u, a)
    N = ca.horzcat(a, b).T
    return ca.vertcat(J6[0:3, :], ca.mtimes(N, J6[3:6, :])), ca.vertcat(a6[0:3], ca.mtimes(N, a6[3:6]))


def dynamics_function(
    robot: Robot, stance: str, layout: StanceLayout, terms: FrameTerms, blade: bool, J_springs: np.ndarray
) -> ca.Function:
    """The CasADi function of ``stance``'s system: inputs ``M_upper`` (Pinocchio's ``M``, read
    above the diagonal), ``nle``, the :attr:`FrameTerms.symbols` and ``small`` (``q``, ``v``,
    ``vdot_a``); outputs ``KT`` (the transposed matrix: a C-order buffer holds ``K``) and ``rhs``."""
    nv, nq = robot.nv, robot.nq
    na, ncf, ns = len(layout.ctrl_v), layout.n_contact, len(J_springs)
    Mu, nle = ca.MX.sym("M_upper", nv, nv), ca.MX.sym("nle", nv)
    small = ca.MX.sym("small", nq + nv + na)
    q, v, vdot_a = small[:nq], small[nq : nq + nv], small[nq + nv :]
    M = ca.triu(Mu) + ca.triu(Mu, False).T
    Jf, af = contact_rows_expression(robot, terms, stance, blade)
    K = ca.MX(ca.DM(layout.K))  # the constant entries, as the Python assembly presets them
    K[:nv, :nv] = M
    K[nv : nv + ncf, :nv] = Jf
    K[:nv, nv + na : nv + na + ncf] = -Jf.T  # the springs' rows and columns are among the constants
    rhs = ca.vertcat(passive_forces_expression(robot, q, v) - nle, -af, ca.MX.zeros(ns), vdot_a)
    return ca.Function(
        f"{FUNCTION_STEM}_{stance}", [Mu, nle, *(s for _, s in terms.symbols), small],
        [ca.densify(K.T), ca.densify(rhs)], ["M_upper", "nle", *(nm for nm, _ in terms.symbols), "small"],
        ["KT", "rhs"],
    )  # fmt: skip


class CompiledDynamics:
    """The compiled assembly of a PBC tracker's system (see the module doc).

    Args:
        robot: The robot.
        layouts: The tracker's :class:`~amlip_qp.control.pbc.stance_layout.StanceLayout` per side
            (their ``K`` with the constant entries set, ``rhs``, ``ctrl_v``, ``n_contact``):
            the functions write into these buffers.
        blade: Per side, whether the foot is held along its sole line (two rotation rows).
        J_springs: The rigid springs' rows (in the layouts' constant entries).
        cache_dir: Overrides the codegen cache folder.

    Raises:
        CompilerUnavailableError: No C compiler.
        CodegenError: The compiler rejected the source or the library does not load.
    """

    def __init__(
        self,
        robot: Robot,
        layouts: Mapping[str, StanceLayout],
        blade: Mapping[str, bool],
        J_springs: np.ndarray,
        cache_dir: str | os.PathLike | None = None,
    ):
        runtime.require_compiler()  # before the generation, which takes a second
        self._terms = terms = dynamics_terms(robot)
        functions = {
            side: dynamics_function(robot, side, layouts[side], terms, blade[side], J_springs).expand()
            for side in robot.foot_sides
        }
        source = generate.single_file_source(functions.values(), SOURCE_FILE)
        self._names = {side: fn.name() for side, fn in functions.items()}
        self.library_path, self._functions = runtime.compile_and_load(
            source, list(self._names.values()), SOURCE_FILE, LIBRARY_FILE, cache_dir
        )
        nq, nv = robot.nq, robot.nv
        self._layouts = layouts
        self._small = {side: np.zeros(nq + nv + len(lay.ctrl_v)) for side, lay in layouts.items()}
        self._nq, self._nv = nq, nv
        self._bindings = runtime.PerDataBindings(self._bind, MAX_BINDINGS)

    def _bind(self, data) -> tuple:
        """Bind the functions to ``data``'s arrays: ``(what to keep alive, the evaluator per side)``."""
        views = [data.M, data.nle, *self._terms.views(data)]
        evals, buffers = {}, []
        for side, name in self._names.items():
            lay = self._layouts[side]
            bound = runtime.bind_buffers({name: self._functions[name]}, [*views, self._small[side]], [lay.K, lay.rhs])
            buffers.append(bound[name][0])
            evals[side] = bound[name][1]
        return (views, buffers), evals

    def assemble(self, kin: RobotKinematics, stance: str, vdot_ctrl: np.ndarray) -> None:
        """Write ``stance``'s ``K`` and ``rhs`` (the layout's buffers) for the kinematics ``kin``
        (a full update: ``M`` and ``h``) and the controlled joints' accelerations ``vdot_ctrl``."""
        kin.require_dynamics()
        q, v = kin.state()
        evals = self._bindings.evaluators(kin.data)
        u, nq, nv = self._small[stance], self._nq, self._nv
        u[:nq] = q
        u[nq : nq + nv] = v
        u[nq + nv :] = vdot_ctrl
        evals[stance]()
