"""The iterative IK's evaluation as generated C that reads Pinocchio's arrays in place.

:class:`~amlip_qp.control.pbc.ik_evaluation.PythonIKEvaluation` is the readable reference:
at an iterate ``q`` it reads the outputs, the stance contact frame's Jacobian, position and
rotation through a handful of Pinocchio getters and forms the residual with numpy.
:class:`CompiledIKEvaluation` gives the same numbers, to the last bit, with one call of C code
that CasADi generates from the same definitions, after Pinocchio's update of the IK's own
kinematics: the varying rows of ``A`` (the outputs' Jacobian, then the contact frame's
Jacobian rows), the residual's rows of the outputs, the contact position and the linear rows,
the outputs' drift, ``y`` and the contact frame's pose. Its inputs are bound once per Pinocchio
data to Pinocchio's storage (:class:`~amlip_qp.codegen.frame_terms.FrameTerms` of the output
map's frames and both contact frames) plus one small array (``q``, ``v``, the heading, ``h_d``,
the contact position's estimate and the linear rows' values); its outputs are the IK's own
buffers (the stance's ``A`` rows, ``F``, drift), so LAPACK reads them as they are. A second,
small function re-forms ``F`` from the kept values of the last evaluation with new targets
(the first Newton step of a warm tick).

Two pieces stay in Python so that the numbers are the reference's bits (a rounding
difference there changes a chaotic walk's outcome): the orientation rows of the residual,
``pinocchio.log3(R R_est^T)`` of the rotation the C call wrote (two calls), and the contact
frame's drift rows (Pinocchio's getter, once a tick).

The outputs are those of :class:`~amlip_qp.robots.outputs.OutputMap` (the robot's standard
``h_0``, :func:`~amlip_qp.codegen.output_map.output_map_on_terms`, the expressions of
:class:`~amlip_qp.control.walking.outputs_compiled.CompiledOutputMap`); a kinematics object
with another output map is evaluated by the Python reference
(:class:`~amlip_qp.control.pbc.ik.IterativeIK` picks). ``tests/test_control_pbc_ik_compiled.py``
checks the two bit for bit. The C source depends on the robot only: it is compiled once into
the codegen cache (:mod:`amlip_qp.codegen.runtime`).
"""

from __future__ import annotations

import os
from typing import TYPE_CHECKING

import casadi as ca
import numpy as np

from amlip_qp.codegen import generate, runtime
from amlip_qp.codegen.frame_terms import FrameTerms, output_frame_terms
from amlip_qp.codegen.output_map import output_map_on_terms

if TYPE_CHECKING:  # pragma: no cover - typing only
    from amlip_qp.control.pbc.ik_equations import IKEquations
    from amlip_qp.robots.kinematics import RobotKinematics
    from amlip_qp.robots.outputs import OutputMap

SOURCE_FILE = "amlip_pbc_ik.c"
LIBRARY_FILE = "libamlip_pbc_ik.so"
#: Name stem of the generated functions: ``<stem>_evaluate_<side>`` and ``<stem>_residual_<side>``.
FUNCTION_STEM = "pbc_ik"
#: Pinocchio data objects bound at once (the IK's own kinematics; a new one per output map adopted).
MAX_BINDINGS = 4


def ik_frame_terms(output_map: OutputMap) -> FrameTerms:
    """The Pinocchio terms the functions read: the output map's, and both contact frames
    (positions and rotations)."""
    robot = output_map.robot
    return output_frame_terms(output_map, also=[robot.contact_frame_ids[side] for side in robot.foot_sides])


class _Small:
    """Offsets of the small input array: ``q | v | heading | h_d | contact position | linear
    rows' values``."""

    def __init__(self, nq: int, nv: int, n: int, n_lin: int):
        self.q = slice(0, nq)
        self.v = slice(nq, nq + nv)
        self.heading = nq + nv
        k = nq + nv + 1
        self.h_d = slice(k, k + n)
        self.pos = slice(k + n, k + n + 3)
        self.lin = slice(k + n + 3, k + n + 3 + n_lin)
        self.size = k + n + 3 + n_lin


def ik_functions(equations: IKEquations, output_map: OutputMap, terms: FrameTerms) -> dict[str, ca.Function]:
    """Per stance side, the evaluation ``(FrameTerms symbols, small) -> (AT, F, jdv, y, pos, rot)``
    and the residual ``(y, pos, small) -> F``, both expanded to scalar code. ``AT`` is the varying
    rows of ``A`` transposed (a C-order buffer holds the rows), ``rot`` the contact frame's
    rotation transposed (a C-order buffer holds ``R``), ``jdv`` the outputs' drift; ``F``'s
    orientation rows are left 0 (module doc)."""
    robot = equations.robot
    nq, nv, n = robot.nq, robot.nv, output_map.size
    n_lin = nv - n - len(equations.pose_rows)
    lay = _Small(nq, nv, n, n_lin)
    pose = [int(k) for k in equations.pose_rows]
    functions = {}
    for side in robot.foot_sides:
        lin_q = ca.DM(equations.rows[side].lin_q)
        small = ca.MX.sym("small", lay.size)
        q, h_d = small[lay.q], small[lay.h_d]
        y_s, pos_s = ca.MX.sym("y", n), ca.MX.sym("pos", 3)
        p_err = pos_s - small[lay.pos]
        pose_err = ca.vertcat(p_err[0], p_err[2], 0.0) if robot.is_planar else ca.vertcat(p_err, ca.MX.zeros(3))
        F = ca.vertcat(y_s - h_d, pose_err, ca.mtimes(lin_q, q) - small[lay.lin])
        residual = ca.Function(
            f"{FUNCTION_STEM}_residual_{side}", [y_s, pos_s, small], [ca.densify(F)], ["y", "pos", "small"], ["F"]
        )
        cid = robot.contact_frame_ids[side]
        y, JyT, jdv = output_map_on_terms(output_map, terms, side, q, small[lay.v], small[lay.heading])
        AT = ca.horzcat(JyT, terms.jacobian(cid)[pose, :].T)
        pos, rot = terms.position(cid), ca.reshape(terms.rotation(cid).T, 9, 1)
        evaluate = ca.Function(
            f"{FUNCTION_STEM}_evaluate_{side}", [*(s for _, s in terms.symbols), small],
            [ca.densify(AT), residual(y, pos, small), ca.densify(jdv), ca.densify(y), pos, rot],
            [*(nm for nm, _ in terms.symbols), "small"], ["AT", "F", "jdv", "y", "pos", "rot"],
        )  # fmt: skip
        functions[f"evaluate_{side}"] = evaluate.expand()
        functions[f"residual_{side}"] = residual.expand()
    return functions


class CompiledIKEvaluation:
    """The IK's evaluation in generated C (see the module doc); the interface of
    :class:`~amlip_qp.control.pbc.ik_evaluation.PythonIKEvaluation`.

    Args:
        equations: The IK's :class:`~amlip_qp.control.pbc.ik_equations.IKEquations` (the
            functions write into their rows' buffers).
        output_map: The robot's :class:`~amlip_qp.robots.outputs.OutputMap`.
        cache_dir: Overrides the codegen cache folder.

    Attributes:
        backend: ``"c-in-place"``.
        y: The outputs of the last :meth:`evaluate` (a view of a buffer the next evaluation
            overwrites).

    Raises:
        CompilerUnavailableError: No C compiler.
        CodegenError: The compiler rejected the source or the library does not load.
    """

    backend = "c-in-place"

    def __init__(self, equations: IKEquations, output_map: OutputMap, cache_dir: str | os.PathLike | None = None):
        import pinocchio as pin

        runtime.require_compiler()  # before the generation, which takes a second
        robot = equations.robot
        self._terms = terms = ik_frame_terms(output_map)
        functions = ik_functions(equations, output_map, terms)
        source = generate.single_file_source(functions.values(), SOURCE_FILE)
        self._names = {key: fn.name() for key, fn in functions.items()}
        self.library_path, self._functions = runtime.compile_and_load(
            source, list(self._names.values()), SOURCE_FILE, LIBRARY_FILE, cache_dir
        )
        self._log3 = pin.log3
        self._robot = robot
        nq, nv, n = robot.nq, robot.nv, output_map.size
        self._n = n
        self._rows = equations.rows
        self._npose = len(equations.pose_rows)
        self._pose = slice(0, 5, 2) if robot.is_planar else slice(0, 6)  # the pose rows, read as a view
        self._rot_rows = slice(n + 2, n + 3) if robot.is_planar else slice(n + 3, n + 6)
        self._rot_axes = slice(1, 2) if robot.is_planar else slice(0, 3)  # planar: the pitch
        self._lay = lay = _Small(nq, nv, n, nv - n - self._npose)
        self._small = np.zeros(lay.size)
        self._small_q, self._small_v = self._small[lay.q], self._small[lay.v]
        self._small_h_d, self._small_pos = self._small[lay.h_d], self._small[lay.pos]
        self._small_lin = self._small[lay.lin]
        self._contact_rot = np.eye(3)  # this tick's estimate of the contact frame's rotation
        sides = robot.foot_sides
        self._out = {s: (np.zeros(n), np.zeros(3), np.zeros((3, 3))) for s in sides}  # y, pos, R (C order)
        self._kept = {s: (np.zeros(n), np.zeros(3), np.zeros((3, 3))) for s in sides}
        self._scratch = (np.zeros(nv), np.zeros(n), np.zeros(n), np.zeros(3), np.zeros((3, 3)))
        self.y = self._out[sides[0]][0]
        self._residual_evals = {}
        self._keep_alive: list = []
        for s in sides:
            name = self._names[f"residual_{s}"]
            inputs = [*self._kept[s][:2], self._small]
            bound = runtime.bind_buffers({name: self._functions[name]}, inputs, [self._rows[s].F])
            self._keep_alive.append(bound[name][0])
            self._residual_evals[s] = bound[name][1]
        self._bindings = runtime.PerDataBindings(self._bind, MAX_BINDINGS)

    def _bind(self, data) -> tuple:
        """Bind the evaluations to ``data``'s arrays: ``(what to keep alive, the evaluator per
        (side, eps))``; ``eps``: into ``A_eps``, the other outputs into scratch buffers."""
        views = [*self._terms.views(data), self._small]
        evals, buffers = {}, []
        m, n = self._n + self._npose, self._n
        for s, rows in self._rows.items():
            name = self._names[f"evaluate_{s}"]
            fn = {name: self._functions[name]}
            for eps, outputs in (
                (False, [rows.A[:m], rows.F, rows.drift[:n], *self._out[s]]), (True, [rows.A_eps[:m], *self._scratch])
            ):  # fmt: skip
                bound = runtime.bind_buffers(fn, views, outputs)
                buffers.append(bound[name][0])
                evals[s, eps] = bound[name][1]
        return (views, buffers), evals

    def set_targets(self, stance: str, h_d: np.ndarray, fixed: dict) -> None:
        """As :meth:`PythonIKEvaluation.set_targets
        <amlip_qp.control.pbc.ik_evaluation.PythonIKEvaluation.set_targets>`."""
        self._small_h_d[...] = h_d
        self._small_pos[...] = fixed["contact_pos"]
        self._small_lin[...] = fixed["lin"]
        self._contact_rot = fixed["contact_rot"]

    def _orientation_rows(self, F: np.ndarray, rot: np.ndarray) -> np.ndarray:
        """Write ``F``'s orientation rows, ``log3(R R_est^T)`` as the reference forms them; return ``F``."""
        F[self._rot_rows] = self._log3(rot @ self._contact_rot.T)[self._rot_axes]
        return F

    def evaluate(self, kin: RobotKinematics, stance: str, q, heading_rad: float, v=None, eps: bool = False):
        """As :meth:`PythonIKEvaluation.evaluate
        <amlip_qp.control.pbc.ik_evaluation.PythonIKEvaluation.evaluate>`."""
        if v is None:
            kin.update_positions(q)
            self._small_v.fill(0.0)
        else:
            kin.update_kinematics(q, v)
            self._small_v[...] = v
        self._small_q[...] = q
        self._small[self._lay.heading] = heading_rad
        self._bindings.evaluators(kin.data)[stance, eps]()
        if eps:
            return None
        out = self._out[stance]
        self.y = out[0]
        return self._orientation_rows(self._rows[stance].F, out[2])

    def keep(self, stance: str) -> None:
        """Keep ``stance``'s last evaluation for :meth:`kept_residual`."""
        for kept, out in zip(self._kept[stance], self._out[stance]):
            kept[...] = out

    def kept_residual(self, stance: str, q) -> np.ndarray:
        """``F`` at the kept evaluation (its ``q``, given again) with the current targets."""
        self._small_q[...] = q
        self._residual_evals[stance]()
        return self._orientation_rows(self._rows[stance].F, self._kept[stance][2])

    def drift(self, kin: RobotKinematics, stance: str, heading_rad: float) -> np.ndarray:
        """``Adot v`` of the varying rows at the last :meth:`evaluate` with a ``v`` (the stance's
        buffer: the outputs' rows written by that evaluation, the contact frame's from Pinocchio)."""
        out = self._rows[stance].drift
        out[self._n :] = kin.frame_jdot_v6(self._robot.contact_frame_ids[stance])[self._pose]
        return out
