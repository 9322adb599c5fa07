"""The whole-body QP's per-tick assembly as generated, compiled C.

:meth:`WholeBodyQP.build <amlip_qp.control.wbc.builder.WholeBodyQP.build>`
is the readable reference: Python gathers the tick's inputs
(:func:`~amlip_qp.control.wbc.inputs.gather_inputs`: a dozen Pinocchio
calls for the frames' Jacobians and drifts, the output map ``h_0`` with its
Jacobian and drift, the output task's residual with the pelvis-yaw feedback)
and about 75 numpy calls form the problem; each is cheap, but their Python
overhead was most of the controller tick. :class:`CompiledBuild` writes the
same problem with one call of C code that CasADi generates from the same
definitions:

- its inputs are Pinocchio's own arrays, bound once in place
  (:class:`~amlip_qp.control.wbc.frame_terms.FrameTerms`: the joint
  Jacobians ``data.J``, the joints' rotations, velocities and accelerations,
  the frames' positions, the CoM terms, ``M``), plus ``h - taup`` and one
  small packed array per tick (``q``, ``v``, the references, the heading and
  the swing force ramp ``w``);
- the generated function (one per stance side, the stance's constants baked
  in) forms the frames' Jacobians and drifts, the output map
  (:func:`~amlip_qp.codegen.output_map.output_map_function`), the output
  task's residual with the pelvis-yaw feedback
  (:meth:`~amlip_qp.control.pelvis_yaw.PelvisYawFeedback.symbolic_correction`)
  and everything else straight into the problem's arrays: the row map
  ``R [M | -Jf^T]`` (dynamics equalities, torque map, rigid-spring forces),
  every constraint block and the cost rows ``E, e`` and ``g``
  (:func:`assembly_function`, from the constraint and cost objects'
  :meth:`symbolic` methods); ``H = H0 + E^T E`` stays one numpy product;
- the outputs ``(y, J, Jdot v)`` it computed on the way are stored in the
  kinematics' output cache (:meth:`RobotKinematics.store_outputs
  <amlip_qp.robots.kinematics.RobotKinematics.store_outputs>`), so the
  controller's ``kin.outputs`` of the same tick costs nothing.

A kinematics whose output map is not the robot's standard ``h_0`` (a drop-in
without ``standard_outputs``) is built by the Python build instead.

The C source depends on the robot and the :class:`QPConfig` (its constants
are baked in). It is compiled once into the codegen cache (see
:mod:`amlip_qp.codegen.runtime`: the same compiler, flags and cache folder,
keyed by the source's hash) and called through ``Function.buffer()`` with
inputs and outputs bound to the arrays, so a call costs about a microsecond
plus the arithmetic. The results equal the Python build to rounding (tested
to 1e-12 relative). Measured times: docs/TUNING.md.
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path
from typing import TYPE_CHECKING

import casadi as ca
import numpy as np

from amlip_qp.alip import other_side
from amlip_qp.codegen import generate, runtime
from amlip_qp.codegen.output_map import output_map_function
from amlip_qp.control.wbc.frame_terms import FrameTerms
from amlip_qp.control.wbc.inputs import SymbolicInputs, dm, swing_force_weight
from amlip_qp.control.wbc.passive_symbolic import passive_forces_expression
from amlip_qp.exceptions import CodegenError, InputError
from amlip_qp.robots.outputs import OutputMap

if TYPE_CHECKING:
    from amlip_qp.control.tracker import TrackingTarget
    from amlip_qp.control.wbc.builder import WholeBodyQP
    from amlip_qp.qp.problem import QPProblem
    from amlip_qp.robots.kinematics import RobotKinematics

#: Name stem of the generated functions (``<stem>_left``, ``<stem>_right``).
FUNCTION_STEM = "wbqp_build"
#: File names inside the cache folder.
SOURCE_FILE = "amlip_wbqp.c"
LIBRARY_FILE = "libamlip_wbqp.so"


def _varying_rows(builder: WholeBodyQP, kind: str, key: str, parts: dict) -> ca.MX | None:
    """The stacked expressions ``key`` of the ``kind`` constraints; those that
    have one must be the leading rows (the output binds to a prefix of the array)."""
    got, prefix = [], True
    for c in builder.constraints:
        if c.kind != kind or not c.size:
            continue
        expr = parts[c.name].get(key)
        if expr is None:
            prefix = False
        elif not prefix:
            raise InputError(f"compiled QP assembly: varying {key} rows of {c.name!r} follow constant ones")
        else:
            got.append(expr)
    return ca.vertcat(*got) if got else None


def assembly_function(builder: WholeBodyQP, stance: str) -> ca.Function:
    """The CasADi function of ``stance``'s assembly (see the module doc)."""
    B, L = builder, builder.layout
    nv, n = L.nv, L.n
    sym = SymbolicInputs.create(stance, builder.robot.nq, L, B.output_task.size)
    dyn = B.dynamics.symbolic(sym)
    parts = {c.name: c.symbolic(sym, dyn) for c in B.constraints}
    A, b = _varying_rows(B, "eq", "A", parts), _varying_rows(B, "eq", "b", parts)
    C, l_in, u_in = (_varying_rows(B, "in", key, parts) for key in ("C", "l", "u"))
    if A is None or A.shape != (B.problem.n_eq, n) or C is None or u_in is None or u_in.shape[0] != B.problem.n_in:
        raise InputError("compiled QP assembly: the constraints must give every equality row and every upper bound")
    boxes = [parts[c.name] for c in B.constraints if c.kind == "box"]
    lb, ub = boxes[0]["lb"], boxes[0]["ub"]
    for box in boxes[1:]:
        lb, ub = lb + box["lb"], ub + box["ub"]
    E_rows, e_rows = [], []
    for cost in B.costs:
        for E_part, e_part in cost.symbolic(sym, dyn):
            E_rows.append(E_part)
            e_rows.append(e_part)
    E, e = ca.vertcat(*E_rows), ca.vertcat(*e_rows)
    cc = B.constant_cost
    g_tasks = ca.mtimes(dm(cc.Kq), sym.q) + ca.mtimes(dm(cc.Kv), sym.v) + dm(cc.k0)
    g = ca.vertcat(g_tasks, ca.MX(n - nv, 1)) + ca.mtimes(E.T, e)
    outputs = {
        "ET": E.T, "g": g, "AT": A.T, "b": b,
        "TT": C.T, "l_tau": l_in, "u_in": u_in, "lb": lb, "ub": ub, "RDT": dyn.RD.T, "Rhp": dyn.Rhp,
    }  # fmt: skip
    return ca.Function(
        f"{FUNCTION_STEM}_{stance}",
        list(sym.arguments),
        [ca.densify(x) for x in outputs.values()],
        list(sym.argument_names),
        list(outputs),
    )


def small_layout(nq: int, nv: int, n_outputs: int) -> dict:
    """Slices of the tick function's small packed input: ``q``, ``v``, ``h_d``,
    ``dh_d``, ``ddh_d`` (the output references), ``heading`` (rad), ``w`` (the
    swing force ramp); and its ``size``."""
    sizes = {"q": nq, "v": nv, "h_d": n_outputs, "dh_d": n_outputs, "ddh_d": n_outputs, "heading": 1, "w": 1}
    out: dict = {}
    at = 0
    for name, size in sizes.items():
        out[name] = slice(at, at + size)
        at += size
    out["size"] = at
    return out


def frame_terms(builder: WholeBodyQP) -> FrameTerms:
    """The Pinocchio terms the tick functions read: the base, the contact points and the force points."""
    robot = builder.robot
    frames = [robot.base_frame_id]
    for side in robot.foot_sides:
        frames += [robot.contact_frame_ids[side], *robot.force_frame_ids[side]]
    return FrameTerms(robot.pin_model, frames, [robot.base_frame_id])


def tick_function(builder: WholeBodyQP, stance: str, terms: FrameTerms) -> ca.Function:
    """The CasADi function of ``stance``'s whole tick (see the module doc): the
    inputs ``M_upper`` and ``nle`` (Pinocchio's ``M``, read above the diagonal,
    and ``h``), the :attr:`FrameTerms.symbols` and ``small``
    (:func:`small_layout`); the outputs of :func:`assembly_function`, then ``y``,
    ``JyT`` and ``jdv`` of the output map."""
    B, L, robot = builder, builder.layout, builder.robot
    nv, nq, task = L.nv, robot.nq, B.output_task
    n_out = task.size
    swing = other_side(stance)
    outputs = OutputMap(robot)
    cassie = outputs.layout == "cassie"
    Mu, nle = ca.MX.sym("M_upper", nv, nv), ca.MX.sym("nle", nv)
    sl = small_layout(nq, nv, n_out)
    u = ca.MX.sym("small", sl["size"])
    q, v, h_d, dh_d, ddh_d = (u[sl[k]] for k in ("q", "v", "h_d", "dh_d", "ddh_d"))
    heading, w = u[sl["heading"]], u[sl["w"]]
    T = terms
    base = robot.base_frame_id
    # The output map (codegen.output_map's packed order), with the hip-yaw rows' ones.
    J_base = T.jacobian(base)
    frames = [robot.contact_frame_ids[stance], robot.contact_frame_ids[swing]]
    frames += list(robot.force_frame_ids[swing]) if cassie else []
    JT = ca.horzcat(J_base[3:6, :].T, T.Jcom.T, *[T.jacobian(f)[0:3, :].T for f in frames])
    yaw = [q[outputs.yaw_q_idx[stance]], q[outputs.yaw_q_idx[swing]]] if cassie else [0.0, 0.0]
    R = T.rotation(base)
    packed = ca.vertcat(
        ca.reshape(R.T, 9, 1), T.drift(base)[3:6], T.com, T.acom,
        *[ca.vertcat(T.position(f), T.drift(f)[0:3]) for f in frames], *yaw, heading, v,
    )  # fmt: skip
    y, JyT, jdv = output_map_function(outputs.layout, nv)[0](JT, packed)
    if cassie:
        rows, cols = [outputs.yaw_v_idx[stance], outputs.yaw_v_idx[swing]], [2, 3]
        JyT = JyT + ca.DM(ca.Sparsity.triplet(nv, n_out, rows, cols), 1.0)  # structural zeros there
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
    if L.n_points == 2:
        contact = ca.vertcat(*[T.position(f) for f in points], *[T.drift(f)[0:3] for f in points])
    else:
        contact = T.drift(points[0])[axes]
    core = assembly_function(B, stance)
    hp = nle - passive_forces_expression(robot, q, v)  # h - taup
    parts = core(Mu, hp, ca.vertcat(*jf).T, JyT, ca.vertcat(q, v, contact, r, w))
    names = [core.name_out(i) for i in range(core.n_out())]
    args = [Mu, nle, *(s for _, s in T.symbols), u]
    arg_names = ["M_upper", "nle", *(n for n, _ in T.symbols), "small"]
    return ca.Function(
        f"{FUNCTION_STEM}_{stance}", args, [*parts, ca.densify(y), ca.densify(JyT), ca.densify(jdv)],
        arg_names, [*names, "y", "JyT", "jdv"],
    )  # fmt: skip


def generate_source(builder: WholeBodyQP) -> tuple[bytes, dict[str, ca.Function]]:
    """The C source of both stances' tick functions for ``builder``, and the functions."""
    # Expanded to scalar (SX) code: sparsity and constants folded; E^T E stays with numpy (docs/TUNING.md).
    terms = frame_terms(builder)
    functions = {side: tick_function(builder, side, terms).expand() for side in builder.robot.foot_sides}
    options = dict(generate.CODEGEN_OPTIONS, with_header=False)
    cg = ca.CodeGenerator(SOURCE_FILE, options)
    for fn in functions.values():
        cg.add(fn)
    with tempfile.TemporaryDirectory(prefix="amlip_qp_wbqp_") as tmp:
        cg.generate(tmp + os.sep)
        source = (Path(tmp) / SOURCE_FILE).read_bytes()
    return generate.banner().encode("ascii") + source, functions


def _bind(functions: dict[str, ca.Function], inputs: list, outputs: list) -> dict[str, tuple]:
    """Bind each function's inputs and outputs to the arrays (contiguous; a
    C-order (a, b) array is the column-major (b, a) matrix).

    Returns:
        Per name, its ``(buffer, evaluate)`` pair.

    Raises:
        CodegenError: A size differs or an array is not contiguous.
    """
    bound = {}
    # Stub limit: casadi's FunctionBuffer.set_arg/set_res stubs demand a size (the binding takes it from the buffer).
    for name, fn in functions.items():
        buf, ev = fn.buffer()
        for kind, arrays, nnz, setter in (
            ("input", inputs, fn.nnz_in, buf.set_arg), ("output", outputs, fn.nnz_out, buf.set_res)
        ):  # fmt: skip
            for i, arr in enumerate(arrays):
                if nnz(i) != arr.size or arr.dtype != np.float64:
                    raise CodegenError(f"{name} {kind} {i} has the wrong size or type")
                if not (arr.flags.c_contiguous or arr.flags.f_contiguous):
                    raise CodegenError(f"{name} {kind} {i} is not contiguous")
                setter(i, memoryview(arr.reshape(-1, order="A")))  # type: ignore[call-arg]
        bound[name] = (buf, ev)
    return bound


class CompiledBuild:
    """The compiled assembly of one :class:`WholeBodyQP` (see the module doc).

    Args:
        builder: The :class:`~amlip_qp.control.wbc.builder.WholeBodyQP`
            whose problem arrays it fills (with its inputs and dynamics buffers).
        cache_dir: Overrides the codegen cache folder.

    Raises:
        CompilerUnavailableError: No C compiler.
        CodegenError: The compiler rejected the source or the library does not load.
    """

    def __init__(self, builder: WholeBodyQP, cache_dir: str | os.PathLike | None = None):
        self.builder = B = builder
        runtime.require_compiler()  # before the generation, which takes seconds
        source, symbolic = generate_source(builder)
        self._terms = frame_terms(builder)
        fn = symbolic[B.robot.foot_sides[0]]
        L, P, n_out = B.layout, B.problem, B.output_task.size
        self._slices = small_layout(B.robot.nq, L.nv, n_out)
        self._small = np.zeros(self._slices["size"])
        self._E = np.zeros((fn.size_out(fn.index_out("ET"))[1], L.n))
        self._EtE = np.zeros((L.n, L.n))
        self._y, self._J, self._jdv = np.zeros(n_out), np.zeros((n_out, L.nv)), np.zeros(n_out)
        n_tau = fn.size_out(fn.index_out("TT"))[1]  # the leading inequality rows with a varying C
        self._outputs = [
            self._E, P.g, P.A, P.b, P.C[:n_tau], P.l[:n_tau], P.u, P.lb, P.ub, B.dynamics.RD, B.dynamics.Rhp,
            self._y, self._J, self._jdv,
        ]  # fmt: skip
        self._names = {side: f"{FUNCTION_STEM}_{side}" for side in B.robot.foot_sides}
        self.library_path, self._functions = runtime.compile_and_load(
            source, list(self._names.values()), SOURCE_FILE, LIBRARY_FILE, cache_dir
        )
        self._data = None  # the Pinocchio data the functions read (bound on the first build with it)
        self._views: list = []  # keeps the bound views alive
        self._eval: dict = {}

    def _bind_data(self, kin: RobotKinematics) -> None:
        """Bind the functions' inputs to ``kin``'s Pinocchio arrays (see the module doc)."""
        data = kin.data
        self._views = [data.M, data.nle, *self._terms.views(data), self._small]
        bound = _bind(self._functions, self._views, self._outputs)
        self._eval = {side: bound[name][1] for side, name in self._names.items()}
        self._buffers = [bound[name][0] for name in self._names.values()]  # the evaluators need them alive
        self._data = data

    def build(self, kin: RobotKinematics, target: TrackingTarget) -> QPProblem:
        """Fill the builder's problem for ``kin`` and ``target``; return it.
        Same contract as :meth:`WholeBodyQP.build`."""
        B = self.builder
        if not getattr(kin.output_map, "standard_outputs", False):
            return B.build(kin, target)  # a drop-in output map: only the Python build reads it
        kin.require_dynamics()
        stance = target.stance
        if stance not in self._names:
            raise InputError(f"target.stance must be one of {tuple(self._names)}, got {stance!r}")
        if kin.data is not self._data:
            self._bind_data(kin)
        sl, u = self._slices, self._small
        q, v = kin.state()
        u[sl["q"]] = q
        u[sl["v"]] = v
        u[sl["h_d"]] = target.h_d
        u[sl["dh_d"]] = target.dh_d
        u[sl["ddh_d"]] = target.ddh_d
        heading = float(target.heading_rad)
        u[sl["heading"]] = heading
        B.inputs.swing_force_weight = w = swing_force_weight(B.config, target)  # the tracker reads it
        u[sl["w"]] = w
        self._eval[stance]()
        E = self._E
        np.add(B.constant_cost.H0, np.matmul(E.T, E, out=self._EtE), out=B.problem.H)
        B.dynamics.filled_for(stance)
        kin.store_outputs(stance, heading, (self._y.copy(), self._J.copy(), self._jdv.copy()))
        return B.problem
