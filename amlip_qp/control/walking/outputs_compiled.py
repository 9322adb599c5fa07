"""The output map ``h_0(q)`` with its Jacobian and drift, as generated C.

:class:`~amlip_qp.robots.outputs.OutputMap` is the readable reference (a
scalar chain rule in Python). :class:`CompiledOutputMap` evaluates the same
outputs with C code that CasADi generates from the same definitions, and has
the same ``evaluate(kin, stance, heading_rad)`` interface, so it plugs into
:attr:`RobotKinematics.output_map <amlip_qp.robots.kinematics.RobotKinematics.output_map>`.

Python gathers the primitive quantities from Pinocchio (base rotation,
angular Jacobian and drift, the CoM, the contact points and, if the outputs
read them, the swing foot's toe and heel and its contact frame's rotation:
positions, Jacobians, drifts). The generated code
applies the chain rule symbolically: with ``x`` the primitives (the base
rotation's entries, the points), ``y = f(x)``, ``J_y = df/dx J_x`` and
``Jdot_v_y = df/dx Jdot_v_x + xdot^T (d2f/dx2) xdot``, where a rotation
column ``r_j`` has ``J = -[r_j]x J_w`` and drift ``alpha x r_j + w x (w x r_j)``.
The joint outputs are joint coordinates and stay in Python.

The source depends only on the robot's outputs, whether its root is planar,
and ``nv``: it is compiled once into the codegen cache (see
:mod:`amlip_qp.codegen.runtime`).

It lives in the walking loop: it needs CasADi and the codegen runtime, which
``robots`` may not import. A kinematics object gets it when it is made
(:func:`make_kinematics`, what the walking controller makes by default); every
tracker then reads it through ``kin.outputs``.
"""

from __future__ import annotations

import os
import warnings
from typing import TYPE_CHECKING

import numpy as np

from amlip_qp.codegen import generate, runtime
from amlip_qp.codegen.output_map import FUNCTION_NAME, output_map_function
from amlip_qp.exceptions import CodegenError, CompilerUnavailableError, InputError
from amlip_qp.robots.kinematics import RobotKinematics
from amlip_qp.robots.outputs import OutputMap

if TYPE_CHECKING:  # pragma: no cover - typing only
    from amlip_qp.robots.robot import Robot

SOURCE_FILE = "amlip_outputs.c"
LIBRARY_FILE = "libamlip_outputs.so"
#: The output maps of :func:`make_kinematics`: generated C or Python.
OUTPUT_BACKENDS = ("c", "python")


def generate_source(output_map: OutputMap) -> bytes:
    """The C source of ``output_map``'s outputs (:class:`~amlip_qp.robots.outputs.OutputMap`)."""
    fn, _ = output_map_function(output_map.primitives, output_map.planar, output_map.robot.nv)
    return generate.single_file_source([fn], SOURCE_FILE)


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
        nv = robot.nv
        source = generate_source(ref)
        self.library_path, functions = runtime.compile_and_load(
            source, [FUNCTION_NAME], SOURCE_FILE, LIBRARY_FILE, cache_dir
        )
        fn = functions[FUNCTION_NAME]
        n = len(self.names)
        self._JT = np.zeros((fn.nnz_in(0) // nv, nv))
        self._p = np.zeros(fn.nnz_in(1))
        self._y, self._J, self._jdv = np.zeros(n), np.zeros((n, nv)), np.zeros(n)
        self._buffer, self._eval = fn.buffer()
        # Stub limits: casadi's FunctionBuffer.set_arg/set_res stubs demand a size (the binding takes
        # it from the buffer); numpy's stubs declare ndarray a Buffer only for Python >= 3.12.
        for i, arr in enumerate((self._JT, self._p)):
            self._buffer.set_arg(i, memoryview(arr.reshape(-1)))  # type: ignore[call-arg, arg-type]
        for i, arr in enumerate((self._y, self._J, self._jdv)):
            if fn.nnz_out(i) != arr.size:
                raise CodegenError(f"{self.library_path}: {FUNCTION_NAME} output {i} has the wrong size")
            self._buffer.set_res(i, memoryview(arr.reshape(-1)))  # type: ignore[call-arg, arg-type]
        self._base = robot.base_frame_id
        # Per stance side: the points and rotating frames of the packed input (OutputInputs' order),
        # and the joint outputs' q and v indices.
        sides = robot.foot_sides
        self._points = {stance: ref.points(stance) for stance in sides}
        self._rotating = {stance: ref.rotating_frames(stance) for stance in sides}
        self._joints = {stance: ref.joint_indices(stance) for stance in sides}
        # the joint outputs' Jacobian entries (row, v index), per stance (a few: set one by one)
        self._joint_entries = {stance: tuple(zip(ref.joint_rows, self._joints[stance][1])) for stance in sides}
        # Views of the inputs each primitive is copied into (``view[...] = x`` is the cheapest copy).
        JT, p = self._JT, self._p
        self._in_base = (JT[0:3], JT[3:6], p[0:9].reshape(3, 3), p[9:12], p[12:15], p[15:18])
        n_points, n_rot = len(self._points[sides[0]]), len(self._rotating[sides[0]])
        self._in_points = tuple((JT[6 + 3 * i : 9 + 3 * i], p[18 + 6 * i : 21 + 6 * i], p[21 + 6 * i : 24 + 6 * i])
                                for i in range(n_points))  # fmt: skip
        at, row = 18 + 6 * n_points, 6 + 3 * n_points
        self._in_rotating = tuple((JT[row + 3 * i : row + 3 + 3 * i], p[at + 12 * i : at + 9 + 12 * i].reshape(3, 3),
                                   p[at + 9 + 12 * i : at + 12 + 12 * i]) for i in range(n_rot))  # fmt: skip
        self._at = at + 12 * n_rot  # the joint angles, then the heading
        self._in_v = p[p.size - nv :]

    @property
    def size(self) -> int:
        """Number of outputs."""
        return len(self.names)

    def evaluate(self, kin: RobotKinematics, stance: str, heading_rad: float = 0.0):
        """Same contract as :meth:`OutputMap.evaluate <amlip_qp.robots.outputs.OutputMap.evaluate>`."""
        self._ref.checked_swing(stance, heading_rad)
        q, v = kin.state()
        jac, acc = kin.frame_jacobian6, kin.frame_jdot_v6
        base = self._base
        Jw, Jc, R, alpha, com, com_drift = self._in_base
        Jw[...] = jac(base)[3:]
        Jc[...] = kin.com_jacobian()
        R[...] = kin.frame_rotation_view(base)  # row-major into the packed input
        alpha[...] = acc(base)[3:]
        com[...] = kin.com_view
        com_drift[...] = kin.com_jdot_v()
        for fid, (J_in, pos_in, drift_in) in zip(self._points[stance], self._in_points):
            J_in[...] = jac(fid)[:3]
            pos_in[...] = kin.frame_translation_view(fid)
            drift_in[...] = acc(fid)[:3]
        for fid, (J_in, R_in, alpha_in) in zip(self._rotating[stance], self._in_rotating):
            J_in[...] = jac(fid)[3:]
            R_in[...] = kin.frame_rotation_view(fid)
            alpha_in[...] = acc(fid)[3:]
        p, at = self._p, self._at
        q_idx = self._joints[stance][0]
        for k, qi in enumerate(q_idx):
            p[at + k] = q[qi]
        p[at + len(q_idx)] = heading_rad
        self._in_v[...] = v
        self._eval()
        J = self._J.copy()
        for entry in self._joint_entries[stance]:
            J[entry] = 1.0
        return self._y.copy(), J, self._jdv.copy()


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
