"""The whole-body QP's per-tick assembly as generated, compiled C.

:meth:`WholeBodyQP.build <amlip_qp.control.wbc.builder.WholeBodyQP.build>`
is the readable reference: about 75 numpy calls per tick, each cheap, whose
Python overhead made the assembly the largest part of the controller tick
(more than the solve). :class:`CompiledBuild` writes the same problem with
one call of C code that CasADi generates from the same constraint and cost
objects (their :meth:`symbolic` methods):

- Python gathers the inputs with the same function as the reference
  (:func:`~amlip_qp.control.wbc.inputs.gather_inputs`: Pinocchio's terms,
  the output task's ``(J, r)`` with the pelvis-yaw feedback, the swing force
  ramp ``w``) and packs them;
- the generated function (one per stance side, the stance's constants
  baked in) forms everything else straight into the problem's arrays: the
  row map ``R [M | -Jf^T]`` (dynamics equalities, torque map, rigid-spring
  forces), every constraint block and the cost rows ``E, e`` and ``g``;
  ``H = H0 + E^T E`` stays one numpy product.

The C source depends on the robot and the :class:`QPConfig` (its constants
are baked in). It is compiled once into the codegen cache (see
:mod:`amlip_qp.codegen.runtime`: the same compiler, flags and cache folder,
keyed by the source's hash) and called through ``Function.buffer()`` with
inputs and outputs bound once to preallocated arrays, so a call costs about
a microsecond plus the arithmetic. The results equal the Python build to
rounding (tested to 1e-12 relative). Measured times: docs/TUNING.md.
"""

from __future__ import annotations

import os
from typing import TYPE_CHECKING

import casadi as ca
import numpy as np

from amlip_qp.codegen import generate, runtime
from amlip_qp.codegen.runtime import bind_buffers
from amlip_qp.control.wbc.inputs import PackedInput, SymbolicInputs, dm, gather_inputs
from amlip_qp.exceptions import InputError

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


def generate_source(builder: WholeBodyQP) -> tuple[bytes, dict[str, ca.Function]]:
    """The C source of both stances' assembly functions for ``builder``, and the functions."""
    # Expanded to scalar (SX) code: sparsity and constants folded, ~5000
    # operations per stance; E^T E stays with numpy (docs/TUNING.md).
    functions = {side: assembly_function(builder, side).expand() for side in builder.robot.foot_sides}
    return generate.single_file_source(functions.values(), SOURCE_FILE), functions


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
        fn = symbolic[B.robot.foot_sides[0]]
        L, P, inp = B.layout, B.problem, B.inputs
        self._packed = PackedInput(B.robot.nq, L, B.output_task.size)
        # Inputs: M (its upper triangle is read), the builder's hp and Jf, J^T of the outputs, the packed rest.
        self._Mu = np.zeros((L.nv, L.nv), order="F")
        self._JoT = np.zeros((B.output_task.size, L.nv))
        self._E = np.zeros((fn.size_out(fn.index_out("ET"))[1], L.n))
        self._EtE = np.zeros((L.n, L.n))
        n_tau = fn.size_out(fn.index_out("TT"))[1]  # the leading inequality rows with a varying C
        outputs = {
            "ET": self._E, "g": P.g, "AT": P.A, "b": P.b, "TT": P.C[:n_tau], "l_tau": P.l[:n_tau],
            "u_in": P.u, "lb": P.lb, "ub": P.ub, "RDT": B.dynamics.RD, "Rhp": B.dynamics.Rhp,
        }  # fmt: skip
        self._outputs = outputs  # keeps the bound arrays alive
        names = {side: f"{FUNCTION_STEM}_{side}" for side in B.robot.foot_sides}
        self.library_path, functions = runtime.compile_and_load(
            source, list(names.values()), SOURCE_FILE, LIBRARY_FILE, cache_dir
        )
        inputs = [self._Mu, inp.hp, inp.Jf, self._JoT, self._packed.array]
        bound = bind_buffers(functions, inputs, list(outputs.values()))
        self._buffers = {side: bound[name][0] for side, name in names.items()}
        self._eval = {side: bound[name][1] for side, name in names.items()}

    def build(self, kin: RobotKinematics, target: TrackingTarget) -> QPProblem:
        """Fill the builder's problem for ``kin`` and ``target``; return it.
        Same contract as :meth:`WholeBodyQP.build`."""
        B = self.builder
        inp = gather_inputs(kin, target, B.inputs)
        self._Mu[...] = inp.mass_upper
        self._JoT[...] = inp.output_jacobian
        self._packed.pack(inp)
        self._eval[inp.stance]()
        E = self._E
        np.add(B.constant_cost.H0, np.matmul(E.T, E, out=self._EtE), out=B.problem.H)
        B.dynamics.filled_for(inp.stance)
        return B.problem
