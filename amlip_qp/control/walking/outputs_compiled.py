"""The output map ``h_0(q)`` with its Jacobian and drift, as generated C reading Pinocchio in place.

:class:`~amlip_qp.robots.outputs.OutputMap` is the readable reference (a
scalar chain rule in Python). :class:`CompiledOutputMap` evaluates the same
outputs with C code that CasADi generates from the same definitions, and has
the same ``evaluate(kin, stance, heading_rad)`` interface, so it plugs into
:attr:`RobotKinematics.output_map <amlip_qp.robots.kinematics.RobotKinematics.output_map>`.

The generated function (one per stance side) reads Pinocchio's own storage of
the kinematics it is given, bound once per Pinocchio data
(:class:`~amlip_qp.codegen.frame_terms.FrameTerms`: the joint Jacobians, the
joints' rotations, velocities and drift accelerations, the frames' positions
and rotations, the CoM terms; every update overwrites them in place), plus
one small array a call (``q``, ``v``, the heading). It forms the frames'
Jacobians and drifts as Pinocchio's getters do, then the outputs by the chain
rule (:func:`~amlip_qp.codegen.output_map.output_map_on_terms`): with ``x``
the primitives (the base rotation's columns, the points), ``y = f(x)``,
``J_y = df/dx J_x`` and ``Jdot_v_y = df/dx Jdot_v_x + xdot^T (d2f/dx2) xdot``,
where a rotation column ``r_j`` has ``J = -[r_j]x J_w`` and drift
``alpha x r_j + w x (w x r_j)``. A call is one C call and three copies: no
Python gathers Pinocchio's quantities.

The source depends only on the robot's model and outputs: it is compiled once
into the codegen cache (see :mod:`amlip_qp.codegen.runtime`).

It lives in the walking loop: it needs CasADi and the codegen runtime, which
``robots`` may not import. A kinematics object gets it when it is made
(:func:`make_kinematics`, what the walking controller makes by default); every
tracker then reads it through ``kin.outputs``.
"""

from __future__ import annotations

import os
import warnings
from typing import TYPE_CHECKING

import casadi as ca
import numpy as np

from amlip_qp.codegen import generate, runtime
from amlip_qp.codegen.frame_terms import FrameTerms, output_frame_terms
from amlip_qp.codegen.output_map import output_map_on_terms
from amlip_qp.exceptions import CompilerUnavailableError, InputError
from amlip_qp.robots.kinematics import RobotKinematics
from amlip_qp.robots.outputs import OutputMap

if TYPE_CHECKING:  # pragma: no cover - typing only
    from amlip_qp.robots.robot import Robot

SOURCE_FILE = "amlip_outputs.c"
LIBRARY_FILE = "libamlip_outputs.so"
#: Name stem of the generated functions, ``<stem>_left`` and ``<stem>_right``.
FUNCTION_STEM = "output_map_in_place"
#: The output maps of :func:`make_kinematics`: generated C or Python.
OUTPUT_BACKENDS = ("c", "python")
#: Pinocchio data objects a map keeps bound at once (the controller's and its IK's kinematics).
MAX_BINDINGS = 8


def output_functions(output_map: OutputMap, terms: FrameTerms) -> dict[str, ca.Function]:
    """Per stance side, the function of :attr:`FrameTerms.symbols` and ``small = (q, v, heading)``
    giving ``y``, ``JyT`` and ``jdv`` (expanded to scalar code)."""
    robot = output_map.robot
    nq, nv = robot.nq, robot.nv
    functions = {}
    for side in robot.foot_sides:
        u = ca.MX.sym("small", nq + nv + 1)
        y, JyT, jdv = output_map_on_terms(output_map, terms, side, u[:nq], u[nq : nq + nv], u[nq + nv])
        fn = ca.Function(
            f"{FUNCTION_STEM}_{side}", [*(s for _, s in terms.symbols), u],
            [ca.densify(y), ca.densify(JyT), ca.densify(jdv)],
            [*(n for n, _ in terms.symbols), "small"], ["y", "JyT", "jdv"],
        )  # fmt: skip
        functions[side] = fn.expand()
    return functions


def generate_source(output_map: OutputMap) -> bytes:
    """The C source of ``output_map``'s outputs (:class:`~amlip_qp.robots.outputs.OutputMap`)."""
    functions = output_functions(output_map, output_frame_terms(output_map))
    return generate.single_file_source(functions.values(), SOURCE_FILE)


class CompiledOutputMap:
    """Drop-in compiled :class:`~amlip_qp.robots.outputs.OutputMap` (see the module doc).

    Raises:
        CompilerUnavailableError: No C compiler.
        CodegenError: The compiler rejected the source or the library does not load.
    """

    #: The robot's standard ``h_0``, as
    #: :attr:`OutputMap.standard_outputs <amlip_qp.robots.outputs.OutputMap.standard_outputs>`.
    standard_outputs = True

    def __init__(self, robot: Robot, cache_dir: str | os.PathLike | None = None):
        ref = OutputMap(robot)
        self.robot = robot
        self.names = ref.names
        self._ref = ref
        runtime.require_compiler()  # before the generation, which takes a second
        self._terms = terms = output_frame_terms(ref)
        functions = output_functions(ref, terms)
        source = generate.single_file_source(functions.values(), SOURCE_FILE)
        self._names = {side: fn.name() for side, fn in functions.items()}
        self.library_path, self._functions = runtime.compile_and_load(
            source, list(self._names.values()), SOURCE_FILE, LIBRARY_FILE, cache_dir
        )
        n, nq, nv = len(self.names), robot.nq, robot.nv
        self._small = np.zeros(nq + nv + 1)
        self._small_q, self._small_v = self._small[:nq], self._small[nq : nq + nv]
        self._i_heading = nq + nv
        self._y, self._J, self._jdv = np.zeros(n), np.zeros((n, nv)), np.zeros(n)
        self._bindings = runtime.PerDataBindings(self._bind, MAX_BINDINGS)

    @property
    def size(self) -> int:
        """Number of outputs."""
        return len(self.names)

    def _bind(self, data) -> tuple:
        """Bind the functions to ``data``'s arrays: ``(what to keep alive, the evaluator per side)``."""
        views = [*self._terms.views(data), self._small]
        bound = runtime.bind_buffers(self._functions, views, [self._y, self._J, self._jdv])
        return (views, [b[0] for b in bound.values()]), {side: bound[name][1] for side, name in self._names.items()}

    def evaluate(self, kin: RobotKinematics, stance: str, heading_rad: float = 0.0):
        """Same contract as :meth:`OutputMap.evaluate <amlip_qp.robots.outputs.OutputMap.evaluate>`."""
        self._ref.checked_swing(stance, heading_rad)
        q, v = kin.state()
        evals = self._bindings.evaluators(kin.data)
        self._small_q[...] = q
        self._small_v[...] = v
        self._small[self._i_heading] = heading_rad
        evals[stance]()
        # after a position update Pinocchio's velocity terms are stale: the drift is zero, as v is
        jdv = np.zeros(self._jdv.size) if kin.positions_only else self._jdv.copy()
        return self._y.copy(), self._J.copy(), jdv


def make_kinematics(
    robot: Robot, output_backend: str = "c", cache_dir: str | os.PathLike | None = None, stacklevel: int = 2
) -> RobotKinematics:
    """A :class:`~amlip_qp.robots.kinematics.RobotKinematics` for the walking controller and its
    tracker, its output map chosen here once.

    Args:
        robot: The robot.
        output_backend: ``"c"`` (the walking controller's default): the generated-C
            :class:`CompiledOutputMap` (the same outputs to rounding, about half the time);
            without a C compiler the Python map with a
            :class:`~amlip_qp.codegen.runtime.CodegenFallbackWarning`. ``"python"``:
            :class:`~amlip_qp.robots.outputs.OutputMap`.
        cache_dir: Overrides the codegen cache folder.
        stacklevel: The fallback warning's, as :func:`warnings.warn`'s (2: the caller of this function).

    Raises:
        InputError: An unknown ``output_backend``.
        CodegenError: The compiler rejected the source or the library does not load.
    """
    if output_backend not in OUTPUT_BACKENDS:
        raise InputError(f"output_backend must be 'c' or 'python', got {output_backend!r}")
    if output_backend == "python":
        return RobotKinematics(robot)
    try:
        output_map = CompiledOutputMap(robot, cache_dir)
    except CompilerUnavailableError as exc:
        warnings.warn(
            f"no compiled output map ({exc}); using the Python OutputMap (same outputs, slower)",
            runtime.CodegenFallbackWarning,
            stacklevel=stacklevel,
        )
        return RobotKinematics(robot)
    return RobotKinematics(robot, output_map)
