"""The harness's per-tick state read and control write as generated C, on MuJoCo's arrays in place.

:meth:`Plant.array_reader <amlip_qp.sim.world.plant.Plant.array_reader>` (on
:class:`~amlip_qp.robots.state_reader.StateReader`) is the readable reference:
MuJoCo ``(qpos, qvel)`` -> the controller's Pinocchio ``(q, v)``, plus the base's
row for the log. :class:`CompiledStateRead` gives the same numbers bit for bit
(tested on walking states): CasADi generates C from the same operations in the
same order (the quaternion normalized, its rotation's entries, then ``R^T`` times
the free joint's linear velocity, each sum left to right; no fused
multiply-adds: :data:`~amlip_qp.codegen.runtime.CFLAGS`). Its inputs are bound
once to ``data.qpos`` and ``data.qvel`` (``Function.buffer()``: MuJoCo keeps the
arrays across steps), so a read is one call and three copies, against a dozen
Python-level operations. It also sums ``qpos`` and ``qvel``, the harness's
finiteness check.

:class:`CompiledCtrlWrite` is :meth:`Plant.ctrl_writer
<amlip_qp.sim.world.plant.Plant.ctrl_writer>` (``tau / gear`` clipped to the control
range, into ``data.ctrl``) in one call: C99's ``fmax``/``fmin`` give NumPy's
``maximum``/``minimum`` on numbers; where ``tau / gear`` is not finite (a
torque the controller never outputs, or a zero gear) the NumPy writer writes
instead, which keeps its NaN.

The sources depend only on the plant's sizes and the
:class:`~amlip_qp.robots.state_reader.FreeJointPlan`; they are compiled once
into the codegen cache (:mod:`amlip_qp.codegen.runtime`).
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable

import casadi as ca
import mujoco
import numpy as np

from amlip_qp.codegen import generate, runtime
from amlip_qp.exceptions import CodegenError, InputError
from amlip_qp.robots.state import ZERO_QUATERNION_NORM, rotation_entries
from amlip_qp.robots.state_reader import FreeJointPlan

SOURCE_FILE = "amlip_state_read.c"
LIBRARY_FILE = "libamlip_state_read.so"
FUNCTION_NAME = "amlip_state_read"
WRITE_SOURCE_FILE = "amlip_ctrl_write.c"
WRITE_LIBRARY_FILE = "libamlip_ctrl_write.so"
WRITE_FUNCTION_NAME = "amlip_ctrl_write"

#: ``((q, v, root), total)``: the state as :meth:`StateReader.arrays
#: <amlip_qp.robots.state_reader.StateReader.arrays>` returns it (``None`` when
#: the reference must read it: a non-finite entry or a zero quaternion), and
#: ``sum(qpos) + sum(qvel)``.
ReadResult = tuple[tuple[np.ndarray, np.ndarray, list[float]] | None, float]


def read_function(plan: FreeJointPlan, nq: int, nv: int) -> ca.Function:
    """``(qpos[nq], qvel[nv]) -> (q, v, root[13], checks[2])``: the read of ``plan`` as a CasADi Function.

    ``checks`` is ``(sum(qpos) + sum(qvel), |quaternion|)``. The operations are those of
    the reference (``amlip_qp/robots/state_reader.py``), in its order.
    """
    qpos_sx, qvel_sx = ca.SX.sym("qpos", nq), ca.SX.sym("qvel", nv)
    qpos = [qpos_sx[i] for i in range(nq)]
    qvel = [qvel_sx[i] for i in range(nv)]
    q = [qpos[i] for i in plan.gather_q]
    v = [qvel[i] for i in plan.gather_v]
    iw, ix, iy, iz = plan.quat_wxyz
    w, x, y, z = qpos[iw], qpos[ix], qpos[iy], qpos[iz]
    norm = ca.sqrt(w * w + x * x + y * y + z * z)
    x, y, z, w = x / norm, y / norm, z / norm, w / norm
    q[plan.pq : plan.pq + 4] = [x, y, z, w]
    n = ca.sqrt(w * w + x * x + y * y + z * z)
    # The one rotation formula, on symbols. u / 1.0 is u: the reference's shortcut (no division
    # at a norm of 1.0) gives the same numbers.
    entries = rotation_entries(w / n, x / n, y / n, z / n)  # type: ignore[arg-type]
    r00, r01, r02, r10, r11, r12, r20, r21, r22 = entries
    l0, l1, l2 = (qvel[i] for i in plan.lin_xyz)
    lin = [r00 * l0 + r10 * l1 + r20 * l2, r01 * l0 + r11 * l1 + r21 * l2, r02 * l0 + r12 * l1 + r22 * l2]
    v[plan.pv : plan.pv + 3] = lin
    root = [qpos[i] for i in plan.root_pos] + [x, y, z, w] + lin + [qvel[i] for i in plan.root_ang]
    checks = [ca.sum1(qpos_sx) + ca.sum1(qvel_sx), norm]
    return ca.Function(
        FUNCTION_NAME,
        [qpos_sx, qvel_sx],
        [ca.vertcat(*q), ca.vertcat(*v), ca.vertcat(*root), ca.vertcat(*checks)],
        ["qpos", "qvel"],
        ["q", "v", "root", "checks"],
    )


def generate_source(plan: FreeJointPlan, nq: int, nv: int) -> bytes:
    """The C source of :func:`read_function`."""
    return generate.single_file_source([read_function(plan, nq, nv)], SOURCE_FILE)


class CompiledStateRead:
    """The generated-C read of one plant's ``data`` (module doc); ``reader()`` -> :data:`ReadResult`.

    Args:
        plan: The plant's :class:`~amlip_qp.robots.state_reader.FreeJointPlan`.
        data: The plant's ``MjData``, whose ``qpos`` and ``qvel`` it reads in place.
        cache_dir: Overrides :func:`~amlip_qp.codegen.runtime.cache_root`.

    Raises:
        CompilerUnavailableError: No C compiler.
        CodegenError: The compiler rejected the source or the library does not load.
        InputError: ``data``'s arrays are not contiguous float64 arrays.
    """

    def __init__(self, plan: FreeJointPlan, data: mujoco.MjData, cache_dir: str | os.PathLike | None = None):
        nq, nv = data.qpos.size, data.qvel.size
        self.library_path, functions = runtime.compile_and_load(
            generate_source(plan, nq, nv), [FUNCTION_NAME], SOURCE_FILE, LIBRARY_FILE, cache_dir
        )
        fn = functions[FUNCTION_NAME]
        self._q, self._v = np.zeros(len(plan.gather_q)), np.zeros(len(plan.gather_v))
        self._root, self._checks = np.zeros(13), np.zeros(2)
        self._data = data  # keeps the arrays bound below alive
        self._buffer, self._eval = fn.buffer()
        # Stub limits: casadi's FunctionBuffer.set_arg/set_res stubs demand a size (the binding takes
        # it from the buffer); numpy's stubs declare ndarray a Buffer only for Python >= 3.12.
        for i, arr in enumerate((data.qpos, data.qvel)):
            if fn.nnz_in(i) != arr.size or not arr.flags.c_contiguous or arr.dtype != np.float64:
                raise InputError(
                    f"{FUNCTION_NAME}: data's qpos and qvel must be contiguous float64 arrays of the plan's plant"
                )
            self._buffer.set_arg(i, memoryview(arr))  # type: ignore[call-arg]
        for i, arr in enumerate((self._q, self._v, self._root, self._checks)):
            if fn.nnz_out(i) != arr.size:
                raise CodegenError(f"{self.library_path}: {FUNCTION_NAME} output {i} has the wrong size")
            self._buffer.set_res(i, memoryview(arr))  # type: ignore[call-arg, arg-type]

    def reader(self) -> Callable[[], ReadResult]:
        """``f()``: the state now, as :data:`ReadResult` (``q`` and ``v`` new arrays)."""
        evaluate, q, v, root, checks, isfinite = self._eval, self._q, self._v, self._root, self._checks, math.isfinite
        zero = ZERO_QUATERNION_NORM

        def read(_keep: CompiledStateRead = self) -> ReadResult:  # _keep: the buffer outlives its evaluation
            evaluate()
            total, norm = checks.tolist()
            if not isfinite(total) or norm < zero:
                return None, total
            return (q.copy(), v.copy(), root.tolist()), total

        return read


def write_function(nu: int) -> ca.Function:
    """``(tau[nu], gear[nu], lo[nu], hi[nu]) -> (ctrl[nu], sum(tau / gear))``: ``min(max(tau / gear, lo), hi)``
    and the sum before the clip (not finite: a NaN the clip would hide)."""
    tau, gear, lo, hi = (ca.SX.sym(name, nu) for name in ("tau", "gear", "lo", "hi"))
    ratio = tau / gear
    ctrl = ca.fmin(ca.fmax(ratio, lo), hi)
    return ca.Function(
        WRITE_FUNCTION_NAME, [tau, gear, lo, hi], [ctrl, ca.sum1(ratio)], ["tau", "gear", "lo", "hi"], ["ctrl", "total"]
    )


class CompiledCtrlWrite:
    """The generated-C control write into ``ctrl`` (module doc); ``writer()`` -> ``f(tau_Nm)``.

    Args:
        ctrl: The plant's controls the controller's actuators drive (``data.ctrl`` or its leading
            slice; contiguous float64), written in place.
        gear, lo, hi: Per actuator: the gear and the control range (copied).
        fallback: ``f(tau_Nm)`` writing with NumPy, for a torque that is not finite.
        cache_dir: Overrides :func:`~amlip_qp.codegen.runtime.cache_root`.

    Raises:
        CompilerUnavailableError: No C compiler.
        CodegenError: The compiler rejected the source or the library does not load.
        InputError: ``ctrl`` is not a contiguous float64 array.
    """

    def __init__(
        self,
        ctrl: np.ndarray,
        gear: np.ndarray,
        lo: np.ndarray,
        hi: np.ndarray,
        fallback: Callable[[np.ndarray], None],
        cache_dir: str | os.PathLike | None = None,
    ):
        nu = ctrl.size
        self.library_path, functions = runtime.compile_and_load(
            generate.single_file_source([write_function(nu)], WRITE_SOURCE_FILE),
            [WRITE_FUNCTION_NAME],
            WRITE_SOURCE_FILE,
            WRITE_LIBRARY_FILE,
            cache_dir,
        )
        fn = functions[WRITE_FUNCTION_NAME]
        if not ctrl.flags.c_contiguous or ctrl.dtype != np.float64:
            raise InputError(f"{WRITE_FUNCTION_NAME}: the controls must be a contiguous float64 array")
        self._tau = np.zeros(nu)
        self._constants = tuple(np.array(a, dtype=float).reshape(-1) for a in (gear, lo, hi))
        self._total = np.zeros(1)
        self._ctrl, self._fallback = ctrl, fallback
        self._buffer, self._eval = fn.buffer()
        for i, arr in enumerate((self._tau, *self._constants)):
            if fn.nnz_in(i) != arr.size:
                raise CodegenError(f"{self.library_path}: {WRITE_FUNCTION_NAME} input {i} has the wrong size")
            self._buffer.set_arg(i, memoryview(arr))  # type: ignore[call-arg, arg-type]
        self._buffer.set_res(0, memoryview(ctrl))  # type: ignore[call-arg, arg-type]
        self._buffer.set_res(1, memoryview(self._total))  # type: ignore[call-arg, arg-type]

    def writer(self) -> Callable[[np.ndarray], None]:
        """``f(tau_Nm)``: write the controls of the joint torques ``tau_Nm`` (N m, controller order)."""
        evaluate, tau, total, fallback, isfinite = self._eval, self._tau, self._total, self._fallback, math.isfinite

        def write(tau_Nm: np.ndarray, _keep: CompiledCtrlWrite = self) -> None:  # _keep: see CompiledStateRead
            tau[:] = tau_Nm
            evaluate()
            if not isfinite(total.item()):
                fallback(tau_Nm)  # NaN stays NaN, as NumPy's clip (C's fmax drops it)

        return write
