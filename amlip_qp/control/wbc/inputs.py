"""The per-tick inputs of the whole-body QP, gathered once for either build.

Everything a tick's problem depends on besides the robot and the
configuration is read from the kinematics and the target by ONE function,
:func:`gather_inputs`, into a :class:`TickInputs`. The Python build
(:meth:`WholeBodyQP.build <amlip_qp.control.wbc.builder.WholeBodyQP.build>`)
and the compiled one (:class:`~amlip_qp.control.wbc.compiled.CompiledBuild`)
both call it, so they cannot read different states. :class:`SymbolicInputs`
are the same inputs as CasADi symbols, for the generated build. (The
in-place build, :class:`~amlip_qp.control.wbc.compiled_in_place.InPlaceBuild`,
forms them from Pinocchio's arrays inside its generated code, and is tested
equal to the Python build.)

The inputs: the dynamics terms ``M`` (its upper triangle) and ``h - taup``; the force-point
Jacobians ``Jf`` (world-aligned, the layout's axes, stance foot then swing
foot); the stance points' Jacobians, positions and drifts ``Jdot v``; the
output task's least-squares terms ``(J, r)`` and the pelvis-yaw feedback's
shift of ``r``; the swing foot's force ramp ``w``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import casadi as ca
import numpy as np

from amlip_qp.alip import other_side
from amlip_qp.control.pelvis_yaw import PelvisYawFeedback

if TYPE_CHECKING:
    from amlip_qp.control.tracker import TrackingTarget
    from amlip_qp.control.wbc.config import QPConfig
    from amlip_qp.control.wbc.layout import VariableLayout
    from amlip_qp.control.wbc.tasks import OutputTask
    from amlip_qp.robots.kinematics import RobotKinematics
    from amlip_qp.robots.robot import Robot


def dm(a) -> ca.DM:
    """A CasADi constant of the numbers in ``a`` (float64)."""
    return ca.DM(np.asarray(a, dtype=float))


def swing_force_weight(config: QPConfig, target: TrackingTarget) -> float:
    """The force ramp ``w`` of the swing foot (0 in the air, 1 fully loaded):
    ``max(touchdown_blend * swing_contact_weight, 1 - phase / liftoff_phase)``, clipped to [0, 1]."""
    lift = config.liftoff_phase
    w_lift = max(0.0, 1.0 - target.phase / lift) if lift > 0 else 0.0
    w = max(config.touchdown_blend * float(target.swing_contact_weight), w_lift)
    if not math.isfinite(w):
        return 0.0
    return min(max(w, 0.0), 1.0)


def feedback_residual_shift(
    feedback: PelvisYawFeedback, kin: RobotKinematics, target: TrackingTarget, task: OutputTask
) -> float:
    """How much the pelvis-yaw feedback lowers the swing hip-yaw component of the
    output task's residual ``r = ... - K_d (yd_d - J v) - K_p (y_d - y)``:
    ``K_d ddh + K_p dh`` (rad/s^2) for the feedback's correction ``(dh, ddh)``."""
    dh, ddh = feedback.correction(kin, target)
    i = feedback.swing_index
    return task.gains.kd[i] * ddh + task.gains.kp[i] * dh


class TickInputs:
    """One tick's inputs (filled by :func:`gather_inputs`; SI units, world axes).

    Arrays marked "kin's" are the kinematics' own cached arrays or live views:
    valid until its next update, read-only.

    Attributes:
        stance: Stance side; ``swing`` the other.
        q: Configuration (kin's), (nq,).
        v: Velocity (kin's), (nv,).
        mass_upper: ``M(q)`` (kin's Pinocchio data), (nv, nv): only its upper
            triangle is filled (the CRBA's); the symmetric matrix is
            :meth:`RobotKinematics.mass_matrix`, whose mirroring the generated
            build does without.
        hp: ``h - taup``: nonlinear effects minus passive forces, N m / N, (nv,).
        Jf: Force-point Jacobians, the layout's axes of each point, stance
            foot's points then swing foot's, (2 * n_force, nv).
        point_jacobians: The stance points' translational Jacobians (kin's), 3 x nv each.
        point_positions: The stance points' positions (kin's views), m.
        point_drifts: The stance points' ``Jdot v`` (kin's), m/s^2.
        output_jacobian: The output task's ``J`` (n_out, nv).
        output_residual: The output task's ``r = Jdot v - ydd_des``, m/s^2 or rad/s^2.
        residual_shift: The pelvis-yaw feedback's shift of
            ``output_residual[feedback.swing_index]`` (subtracted), 0 without feedback.
        swing_force_weight: The swing foot's force ramp ``w`` in [0, 1].
        feedback: The :class:`PelvisYawFeedback`, or ``None``.
    """

    def __init__(self, robot: Robot, layout: VariableLayout, config: QPConfig, output_task: OutputTask, names):
        self.robot = robot
        self.layout = layout
        self.config = config
        self.output_task = output_task
        self.feedback = PelvisYawFeedback.for_outputs(tuple(names), config.hip_yaw_feedback)
        d, k = layout.point_dim, layout.n_points
        self.Jf = np.zeros((2 * layout.n_force, robot.nv))
        #: Per side, its force frames and the views of their rows of ``Jf`` as the stance (first) and as the swing foot.
        self._points = {
            side: (
                tuple(robot.force_frame_ids[side]),
                tuple(self.Jf[d * p : d * (p + 1)] for p in range(k)),
                tuple(self.Jf[d * (k + p) : d * (k + p + 1)] for p in range(k)),
            )
            for side in robot.foot_sides
        }
        self.stance, self.swing = "left", "right"
        self.q: np.ndarray = robot.q_stand
        self.v: np.ndarray = np.zeros(robot.nv)
        self.mass_upper: np.ndarray = np.zeros((robot.nv, robot.nv))
        self.hp = np.zeros(robot.nv)
        self.point_jacobians: list[np.ndarray] = []
        self.point_positions: list[np.ndarray] = []
        self.point_drifts: list[np.ndarray] = []
        self.output_jacobian = np.zeros((output_task.size, robot.nv))
        self.output_residual = np.zeros(output_task.size)
        self.residual_shift = 0.0
        self.swing_force_weight = 0.0


def gather_inputs(kin: RobotKinematics, target: TrackingTarget, inputs: TickInputs) -> TickInputs:
    """Fill ``inputs`` for the state in ``kin`` (updated this tick) and the references in ``target``.

    Raises:
        InputError: The kinematics has no dynamics (``update_positions`` only) or the stance is not a side.
    """
    stance = target.stance
    swing = other_side(stance)
    inputs.stance, inputs.swing = stance, swing
    inputs.q, inputs.v = kin.state()
    kin.require_dynamics()
    np.subtract(kin.data.nle, kin.passive_forces(), out=inputs.hp)  # h - taup
    inputs.mass_upper = kin.data.M
    # Force-point Jacobians on the layout's axes: the stance foot's rows, then the swing foot's.
    axes = inputs.layout.axes_index
    jac = kin.frame_jacobian
    fids, st_rows, _ = inputs._points[stance]
    jacs = [jac(f) for f in fids]
    for J, row in zip(jacs, st_rows):
        row[...] = J[axes]
    sw_fids, _, sw_rows = inputs._points[swing]
    for f, row in zip(sw_fids, sw_rows):
        row[...] = jac(f)[axes]
    inputs.point_jacobians = jacs
    inputs.point_positions = [kin.frame_translation_view(f) for f in fids]
    inputs.point_drifts = [kin.frame_jdot_v(f) for f in fids]
    task = inputs.output_task
    inputs.output_jacobian, inputs.output_residual = task.least_squares(kin, target)
    fb = inputs.feedback
    inputs.residual_shift = 0.0 if fb is None else feedback_residual_shift(fb, kin, target, task)
    inputs.swing_force_weight = swing_force_weight(inputs.config, target)
    return inputs


def packed_layout(nq: int, layout: VariableLayout, n_outputs: int) -> dict:
    """Slices of the generated build's packed small input: ``q``, ``v``,
    ``contact`` (two or four points: the stance points' positions, m, then their
    drifts, m/s^2; one point: its drift on the layout's axes), ``r`` (output
    task residual, pelvis-yaw shift applied), ``w`` (swing force ramp); and its ``size``."""
    n_con = 6 * layout.n_points if layout.n_points > 1 else layout.point_dim
    return consecutive_slices({"q": nq, "v": layout.nv, "contact": n_con, "r": n_outputs, "w": 1})


def consecutive_slices(sizes: dict[str, int]) -> dict[str, Any]:
    """Per name, the slice of a packed vector holding ``sizes`` one after the other; and its ``size``."""
    out: dict[str, Any] = {}
    at = 0
    for name, size in sizes.items():
        out[name] = slice(at, at + size)
        at += size
    out["size"] = at
    return out


class PackedInput:
    """The generated build's packed small input :attr:`array` (slices :attr:`slices`
    of :func:`packed_layout`), with views of its parts made once (a tick's copies
    then cost no slicing).

    Args:
        nq: Configuration size.
        layout: The QP's :class:`~amlip_qp.control.wbc.layout.VariableLayout`.
        n_outputs: Number of outputs of the output task.
    """

    def __init__(self, nq: int, layout: VariableLayout, n_outputs: int):
        self.slices = small = packed_layout(nq, layout, n_outputs)
        self.array = u = np.zeros(small["size"])
        self._q, self._v, self._r = u[small["q"]], u[small["v"]], u[small["r"]]
        self._w = small["w"].start
        c = small["contact"].start
        if layout.n_points > 1:
            # the stance points' positions, then their drifts
            k = 2 * layout.n_points
            self._contact: tuple[np.ndarray, ...] = tuple(u[c + 3 * i : c + 3 * (i + 1)] for i in range(k))
        else:
            self._contact = (u[small["contact"]],)
        self._axes = layout.axes_index

    def pack(self, inputs: TickInputs) -> None:
        """Write ``inputs`` into :attr:`array`."""
        self._q[...] = inputs.q
        self._v[...] = inputs.v
        contact = self._contact
        if len(contact) == 4:
            (p0, p1), (d0, d1) = inputs.point_positions, inputs.point_drifts
            contact[0][...] = p0
            contact[1][...] = p1
            contact[2][...] = d0
            contact[3][...] = d1
        elif len(contact) > 1:
            for dst, src in zip(contact, (*inputs.point_positions, *inputs.point_drifts)):
                dst[...] = src
        else:
            contact[0][...] = inputs.point_drifts[0][self._axes]
        rr = self._r
        rr[...] = inputs.output_residual
        if inputs.feedback is not None:
            rr[inputs.feedback.swing_index] -= inputs.residual_shift
        self.array[self._w] = inputs.swing_force_weight


@dataclass
class SymbolicInputs:
    """:class:`TickInputs` as CasADi symbols, for one stance (the generated build).

    The function's arguments are ``M_upper`` (``M``'s upper triangle is read),
    ``hp``, ``JfT`` (``Jf`` transposed), ``JoT`` (the output Jacobian
    transposed) and ``packed`` (:func:`packed_layout`).
    """

    stance: str
    arguments: tuple[ca.MX, ...]
    argument_names: tuple[str, ...]
    mass_matrix: ca.MX
    hp: ca.MX
    JfT: ca.MX
    JoT: ca.MX
    q: ca.MX
    v: ca.MX
    contact: ca.MX
    output_residual: ca.MX
    swing_force_weight: ca.MX

    @property
    def swing(self) -> str:
        """The swing side."""
        return other_side(self.stance)

    @classmethod
    def create(cls, stance: str, nq: int, layout: VariableLayout, n_outputs: int) -> SymbolicInputs:
        """The symbols of ``stance``'s function."""
        nv, nf = layout.nv, layout.n_force
        small = packed_layout(nq, layout, n_outputs)
        Mu = ca.MX.sym("M_upper", nv, nv)
        hp = ca.MX.sym("hp", nv)
        JfT = ca.MX.sym("JfT", nv, 2 * nf)
        JoT = ca.MX.sym("JoT", nv, n_outputs)
        u = ca.MX.sym("u", small["size"])
        M = ca.triu(Mu) + ca.triu(Mu, False).T
        return cls(
            stance, (Mu, hp, JfT, JoT, u), ("M_upper", "hp", "JfT", "JoT", "packed"), M, hp, JfT, JoT,
            u[small["q"]], u[small["v"]], u[small["contact"]], u[small["r"]], u[small["w"]],
        )  # fmt: skip
