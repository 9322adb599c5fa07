"""The whole-body QP's per-tick assembly as generated C that reads Pinocchio's arrays in place.

The QP tracker's default assembly with a C compiler, the same
problem as :class:`~amlip_qp.control.wbc.compiled.CompiledBuild` and the
Python build to rounding, with less Python a tick:

- :class:`~amlip_qp.control.wbc.compiled.CompiledBuild` gathers the tick's
  inputs in Python (:func:`~amlip_qp.control.wbc.inputs.gather_inputs`: a
  dozen Pinocchio getters, a new array each, the output map ``h_0`` with
  its own generated C, the output task's residual and the pelvis-yaw
  feedback with numpy) and copies them into its generated assembly;
- :class:`InPlaceBuild` binds its generated function's inputs once to
  Pinocchio's own storage (:class:`~amlip_qp.codegen.frame_terms.FrameTerms`:
  the joint Jacobians ``data.J``, the joints' rotations, velocities and
  accelerations, the frames' positions, the CoM terms, ``M``, ``h``; every
  update overwrites them in place) plus one small packed array per tick
  (``q``, ``v``, the references, the heading, the swing force ramp ``w``).
  The function (one per stance side) forms the frames' Jacobians (bit for
  bit Pinocchio's) and drifts (to rounding), the output map
  (:func:`~amlip_qp.codegen.output_map.output_map_on_terms`), the output
  task's residual with the pelvis-yaw feedback
  (:meth:`~amlip_qp.control.pelvis_yaw.PelvisYawFeedback.symbolic_correction`),
  the passive forces (:mod:`~amlip_qp.control.passive_symbolic`) and,
  through :func:`~amlip_qp.control.wbc.compiled.assembly_function`, the whole
  problem; ``H = H0 + E^T E`` stays one numpy product. It keeps ``h_0``'s
  ``(y, J, Jdot v)`` of the tick (:attr:`InPlaceBuild.outputs`), which the
  QP tracker returns in its result, so the controller need not evaluate the
  output map again. It only reads the kinematics object.

``QPTracker(in_place_assembly=False)`` gives
:class:`~amlip_qp.control.wbc.compiled.CompiledBuild` instead. A kinematics
whose output map is not the robot's standard ``h_0`` (a drop-in,
:func:`~amlip_qp.robots.outputs.computes_standard_outputs`) is built by the
Python build instead.
The C source depends on the robot and the :class:`QPConfig`; it is compiled
once into the codegen cache (about 5 s for Cassie).
"""

from __future__ import annotations

import math
import os
from typing import TYPE_CHECKING

import casadi as ca
import numpy as np

from amlip_qp.alip import other_side
from amlip_qp.codegen import generate, runtime
from amlip_qp.codegen.frame_terms import FrameTerms
from amlip_qp.codegen.output_map import output_map_on_terms
from amlip_qp.codegen.runtime import bind_buffers
from amlip_qp.control.passive_symbolic import passive_forces_expression
from amlip_qp.control.wbc.compiled import assembly_function
from amlip_qp.control.wbc.constraints import FrictionPyramid
from amlip_qp.control.wbc.inputs import consecutive_slices, dm, swing_force_weight
from amlip_qp.exceptions import InputError
from amlip_qp.qp.problem import QPProblem
from amlip_qp.robots.outputs import OutputMap, computes_standard_outputs

if TYPE_CHECKING:
    from amlip_qp.control.tracker import TrackingTarget
    from amlip_qp.control.wbc.builder import WholeBodyQP
    from amlip_qp.robots.kinematics import RobotKinematics

#: Name stem of the generated functions (``<stem>_left``, ``<stem>_right``), other than the default
#: build's, so both libraries can be loaded in one process without a clash of symbols.
FUNCTION_STEM = "wbqp_in_place"
#: File names inside the cache folder.
SOURCE_FILE = "amlip_wbqp_in_place.c"
LIBRARY_FILE = "libamlip_wbqp_in_place.so"
#: The functions' name stem with the airborne problem's outputs (another library, other symbols).
AIRBORNE_FUNCTION_STEM = "wbqp_in_place_airborne"
#: The assembly outputs the airborne problem repeats, as its leading blocks, in this order (not
#: ``ET``: the airborne Hessian is the leading block of the full ``E'E``, :meth:`InPlaceBuild.build`).
AIRBORNE_OUTPUTS = ("g", "AT", "b", "TT", "l_tau", "u_in", "lb", "ub")


def small_layout(nq: int, nv: int, n_outputs: int) -> dict:
    """Slices of the tick function's small packed input: ``q``, ``v``, ``h_d``,
    ``dh_d``, ``ddh_d`` (the output references), ``heading`` (rad), ``w`` (the
    swing force ramp); and its ``size``."""
    sizes = {"q": nq, "v": nv, "h_d": n_outputs, "dh_d": n_outputs, "ddh_d": n_outputs, "heading": 1, "w": 1}
    return consecutive_slices(sizes)


def frame_terms(builder: WholeBodyQP) -> FrameTerms:
    """The Pinocchio terms the tick functions read: the base, the contact points and the force points."""
    robot = builder.robot
    outputs = OutputMap(robot)
    frames = [robot.base_frame_id]
    for side in robot.foot_sides:
        frames += [robot.contact_frame_ids[side], *robot.force_frame_ids[side]]
    # a four-point foot's sole line (the swing foot's pitch output); a two-point foot's are its force points
    frames += [f for side in robot.foot_sides for f in robot.sole_line_frame_ids.get(side, ()) if f not in frames]
    rotating = [f for side in robot.foot_sides for f in outputs.rotating_frames(side)]
    return FrameTerms(robot.pin_model, frames, [robot.base_frame_id, *rotating])


def tick_function(
    builder: WholeBodyQP, stance: str, terms: FrameTerms, airborne: tuple[int, int] | None = None
) -> ca.Function:
    """The CasADi function of ``stance``'s whole tick (see the module doc): the
    inputs ``M_upper`` and ``nle`` (Pinocchio's ``M``, read above the diagonal,
    and ``h``), the :attr:`FrameTerms.symbols` and ``small``
    (:func:`small_layout`); the outputs of :func:`assembly_function`, then ``y``,
    ``JyT`` and ``jdv`` of the output map. With ``airborne = (n, n_in)`` (the
    variables and inequality rows before the swing foot's), then the airborne
    problem's varying blocks, each the same entries as the full problem's
    (:data:`AIRBORNE_OUTPUTS`): the same values written twice, not computed twice."""
    B, L, robot = builder, builder.layout, builder.robot
    nv, nq, task = L.nv, robot.nq, B.output_task
    n_out = task.size
    swing = other_side(stance)
    outputs = OutputMap(robot)
    Mu, nle = ca.MX.sym("M_upper", nv, nv), ca.MX.sym("nle", nv)
    sl = small_layout(nq, nv, n_out)
    u = ca.MX.sym("small", sl["size"])
    q, v, h_d, dh_d, ddh_d = (u[sl[k]] for k in ("q", "v", "h_d", "dh_d", "ddh_d"))
    heading, w = u[sl["heading"]], u[sl["w"]]
    T = terms
    base = robot.base_frame_id
    J_base, R = T.jacobian(base), T.rotation(base)
    y, JyT, jdv = output_map_on_terms(outputs, T, stance, q, v, heading)
    # The output task's residual r = Jdot v - ydd_d - K_d (yd_d - J v) - K_p (y_d - y), the feedback's shift applied.
    kp, kd = dm(task.gains.kp), dm(task.gains.kd)
    r = jdv - ddh_d - kd * (dh_d - ca.mtimes(JyT.T, v)) - kp * (h_d - y)
    fb = B.inputs.feedback
    if fb is not None:
        dh, ddh = fb.symbolic_correction(R, ca.mtimes(J_base[5, :], v), heading, h_d, dh_d)
        i = fb.swing_index
        shift = ca.MX.zeros(n_out)
        shift[i] = task.gains.kd[i] * ddh + task.gains.kp[i] * dh
        r = r - shift
    # The assembly's inputs: Jf (the layout's axes; stance points, then swing points) and the packed rest.
    axes = L.axes_index if isinstance(L.axes_index, slice) else [int(a) for a in L.axes_index]
    jf = [T.jacobian(f)[axes, :] for side in (stance, swing) for f in robot.force_frame_ids[side]]
    points = robot.force_frame_ids[stance]
    if L.n_points > 1:
        contact = ca.vertcat(*[T.position(f) for f in points], *[T.drift(f)[0:3] for f in points])
    else:
        contact = T.drift(points[0])[axes]
    core = assembly_function(B, stance)
    hp = nle - passive_forces_expression(robot, q, v)  # h - taup
    parts = core(Mu, hp, ca.vertcat(*jf).T, JyT, ca.vertcat(q, v, contact, r, w))
    names = [core.name_out(i) for i in range(core.n_out())]
    args = [Mu, nle, *(s for _, s in T.symbols), u]
    arg_names = ["M_upper", "nle", *(n for n, _ in T.symbols), "small"]
    outs, out_names = [*parts, ca.densify(y), ca.densify(JyT), ca.densify(jdv)], [*names, "y", "JyT", "jdv"]
    stem = FUNCTION_STEM
    if airborne is not None:
        n, n_in = airborne
        part = dict(zip(names, parts))
        # column-major outputs: a leading block of variables is a leading block of rows of ET, AT, TT
        blocks = {"g": part["g"][:n], "AT": part["AT"][:n, :], "b": part["b"],
                  "TT": part["TT"][:n, :], "l_tau": part["l_tau"], "u_in": part["u_in"][:n_in],
                  "lb": part["lb"][:n], "ub": part["ub"][:n]}  # fmt: skip
        outs += [blocks[k] for k in AIRBORNE_OUTPUTS]
        out_names += [f"{k}_airborne" for k in AIRBORNE_OUTPUTS]
        stem = AIRBORNE_FUNCTION_STEM
    return ca.Function(f"{stem}_{stance}", args, outs, arg_names, out_names)


def generate_in_place_source(
    builder: WholeBodyQP, terms: FrameTerms | None = None, airborne: tuple[int, int] | None = None
) -> tuple[bytes, dict[str, ca.Function]]:
    """The C source of both stances' tick functions for ``builder`` (reading ``terms``, default
    :func:`frame_terms`; with the ``airborne`` problem's outputs, :func:`tick_function`), and the functions."""
    # Expanded to scalar (SX) code: sparsity and constants folded; E^T E stays with numpy (docs/TUNING.md).
    terms = frame_terms(builder) if terms is None else terms
    functions = {side: tick_function(builder, side, terms, airborne).expand() for side in builder.robot.foot_sides}
    return generate.single_file_source(functions.values(), SOURCE_FILE), functions


def airborne_dims(builder: WholeBodyQP) -> tuple[int, int] | None:
    """``(n, n_in)``: the variables and inequality rows before the swing foot's, when the swing
    foot's force variables and friction rows trail the problem (the layout and the constraint
    order put them last; then the problem of an airborne swing foot is a leading block); else ``None``."""
    L, friction = builder.layout, builder.constraint("friction")
    if not isinstance(friction, FrictionPyramid):
        return None
    if L.sl_f_sw.stop != L.n or friction.swing_rows.stop != builder.problem.n_in:
        return None
    return L.sl_f_sw.start, friction.swing_rows.start


class InPlaceBuild:
    """The compiled assembly of one :class:`WholeBodyQP` (see the module doc).

    Args:
        builder: The :class:`~amlip_qp.control.wbc.builder.WholeBodyQP`
            whose problem arrays it fills (with its inputs and dynamics buffers).
        cache_dir: Overrides the codegen cache folder.
        airborne: Also fill :attr:`airborne_problem`, and return it from :meth:`build` while the
            swing foot's force ramp is 0 (ignored when the layout has no such leading block,
            :func:`airborne_dims`).

    Attributes:
        airborne_problem: The problem without the airborne swing foot's forces and friction rows
            (its own contiguous buffers, :meth:`QPProblem.allocate
            <amlip_qp.qp.problem.QPProblem.allocate>`), entry for entry the leading block of the
            builder's problem; ``None`` without ``airborne``. It has the same optimum as the full
            problem while the swing foot's forces are fixed at zero and its rows free.
        outputs: The output map ``h_0``'s ``(y, J, Jdot_v)`` that the last :meth:`build`
            computed (new arrays each build; shapes (n_outputs,), (n_outputs, nv),
            (n_outputs,)), for its target's stance and heading; ``None`` before a build, and
            after one that did not compute them (a drop-in output map, an error).

    Raises:
        CompilerUnavailableError: No C compiler.
        CodegenError: The compiler rejected the source or the library does not load.
    """

    def __init__(self, builder: WholeBodyQP, cache_dir: str | os.PathLike | None = None, airborne: bool = False):
        self.builder = B = builder
        runtime.require_compiler()  # before the generation, which takes seconds
        self._terms = frame_terms(builder)
        dims = airborne_dims(builder) if airborne else None
        source, symbolic = generate_in_place_source(builder, self._terms, dims)
        fn = symbolic[B.robot.foot_sides[0]]
        L, P, n_out = B.layout, B.problem, B.output_task.size
        self._slices = sl = small_layout(B.robot.nq, L.nv, n_out)
        self._small = u = np.zeros(sl["size"])
        # its parts, views made once (per build, slicing would cost more than the small copies)
        self._small_parts = tuple(u[sl[k]] for k in ("q", "v", "h_d", "dh_d", "ddh_d"))
        self._i_heading, self._i_w = sl["heading"].start, sl["w"].start
        self._standard_map_type: type | None = None  # the output map class last found standard
        self._E = np.zeros((fn.size_out(fn.index_out("ET"))[1], L.n))
        self._EtE = np.zeros((L.n, L.n))
        self._y, self._J, self._jdv = np.zeros(n_out), np.zeros((n_out, L.nv)), np.zeros(n_out)
        n_tau = fn.size_out(fn.index_out("TT"))[1]  # the leading inequality rows with a varying C
        self._outputs = [
            self._E, P.g, P.A, P.b, P.C[:n_tau], P.l[:n_tau], P.u, P.lb, P.ub, B.dynamics.RD, B.dynamics.Rhp,
            self._y, self._J, self._jdv,
        ]  # fmt: skip
        self.airborne_problem: QPProblem | None = None
        if dims is not None:
            self._add_airborne_outputs(dims, n_tau)
        stem = FUNCTION_STEM if dims is None else AIRBORNE_FUNCTION_STEM
        self._names = {side: f"{stem}_{side}" for side in B.robot.foot_sides}
        self.library_path, self._functions = runtime.compile_and_load(
            source, list(self._names.values()), SOURCE_FILE, LIBRARY_FILE, cache_dir
        )
        self._data = None  # the Pinocchio data the functions read (bound on the first build with it)
        self._views: list = []  # keeps the bound views alive
        self._eval: dict = {}
        self.outputs: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None

    def _add_airborne_outputs(self, dims: tuple[int, int], n_tau: int) -> None:
        """Allocate :attr:`airborne_problem` and bind its varying blocks to the functions' airborne outputs."""
        n, n_in = dims
        P = self.builder.problem
        self.airborne_problem = Pa = QPProblem.allocate(
            n, P.n_eq, n_in,
            variables={k: s for k, s in P.variables.items() if s.stop <= n},
            eq_rows=list(P.eq_rows),
            in_rows=[(k, slice(s.start, min(s.stop, n_in))) for k, s in P.in_rows if s.start < n_in],
        )  # fmt: skip
        self._n_tau = n_tau
        # The airborne Hessian is the full product's leading block: numpy forms E'E with BLAS's syrk,
        # whose blocking follows the size, so a product of the leading columns alone can differ from
        # that block in the last bits (it does with OpenBLAS on some processors).
        self._EtE_lead = self._EtE[:n, :n]
        # the constant Hessian's block, contiguous (the builder makes H0 once)
        self._H0_air = np.ascontiguousarray(self.builder.constant_cost.H0[:n, :n])
        self._outputs += [Pa.g, Pa.A, Pa.b, Pa.C[:n_tau], Pa.l[:n_tau], Pa.u, Pa.lb, Pa.ub]
        self.copy_constant_rows()

    def copy_constant_rows(self) -> None:
        """Copy the full problem's constant inequality rows (those after the torque rows: the
        stance friction pyramid) into :attr:`airborne_problem`; call it after changing them
        (the tracker turns the pyramid to the stance ground). Nothing without ``airborne``."""
        Pa = self.airborne_problem
        if Pa is None:
            return
        P, k, n, n_in = self.builder.problem, self._n_tau, Pa.n, Pa.n_in
        np.copyto(Pa.C[k:], P.C[k:n_in, :n])
        np.copyto(Pa.l[k:], P.l[k:n_in])

    def full_problem(self) -> QPProblem:
        """The builder's full problem of the last build: after an airborne build, its Hessian
        (which that build leaves) is completed first. For recording; not on the control path."""
        B = self.builder
        E = self._E
        np.add(B.constant_cost.H0, np.dot(E.T, E, out=self._EtE), out=B.problem.H)
        return B.problem

    def _bind_data(self, kin: RobotKinematics) -> None:
        """Bind the functions' inputs to ``kin``'s Pinocchio arrays (see the module doc)."""
        data = kin.data
        self._views = [data.M, data.nle, *self._terms.views(data), self._small]
        bound = bind_buffers(self._functions, self._views, self._outputs)
        self._eval = {side: bound[name][1] for side, name in self._names.items()}
        self._buffers = [bound[name][0] for name in self._names.values()]  # the evaluators need them alive
        self._data = data

    def build(self, kin: RobotKinematics, target: TrackingTarget) -> QPProblem:
        """Fill the builder's problem for ``kin`` and ``target``; return it.
        Same contract as :meth:`WholeBodyQP.build`."""
        B = self.builder
        self.outputs = None
        map_type = type(kin.output_map)
        if map_type is not self._standard_map_type:
            if not computes_standard_outputs(kin.output_map):
                return B.build(kin, target)  # a drop-in output map: only the Python build reads it
            self._standard_map_type = map_type
        kin.require_dynamics()
        stance = target.stance
        if stance not in self._names:
            raise InputError(f"target.stance must be one of {tuple(self._names)}, got {stance!r}")
        if kin.data is not self._data:
            self._bind_data(kin)
        u = self._small
        u_q, u_v, u_h_d, u_dh_d, u_ddh_d = self._small_parts
        q, v = kin.state()
        u_q[:] = q
        u_v[:] = v
        u_h_d[:] = target.h_d
        u_dh_d[:] = target.dh_d
        u_ddh_d[:] = target.ddh_d
        heading = float(target.heading_rad)
        if not math.isfinite(heading):
            raise InputError(f"target.heading_rad must be finite, got {target.heading_rad!r}")
        u[self._i_heading] = heading
        B.inputs.swing_force_weight = w = swing_force_weight(B.config, target)  # the tracker reads it
        u[self._i_w] = w
        self._eval[stance]()
        B.dynamics.filled_for(stance)
        self.outputs = (self._y.copy(), self._J.copy(), self._jdv.copy())
        Pa = self.airborne_problem
        if w == 0.0 and Pa is not None:
            E = self._E
            np.dot(E.T, E, out=self._EtE)
            np.add(self._H0_air, self._EtE_lead, out=Pa.H)
            return Pa
        E = self._E
        # np.dot: the same bits as np.matmul (the same BLAS call), with less overhead
        np.add(B.constant_cost.H0, np.dot(E.T, E, out=self._EtE), out=B.problem.H)
        return B.problem
