"""One tick of the contact-aided invariant EKF as generated C.

:class:`~amlip_qp.estimation.invariant_ekf.InvariantEKF` is the readable
reference (numpy). A numpy tick costs a few hundred microseconds, several
times the 2 kHz budget (the goal: at most 15 % of the QP tracker's
tick), so :class:`CompiledEkf` runs the same tick (propagation, contact
re-initialisation at touchdown, correction, and the base pose and twist the
controller needs) as one C function that CasADi generates from the same
equations, written here a second time on CasADi symbols (the tests compare
the two to 1e-10), with the leg kinematics of the contact points (the
revolute chains of the controller's Pinocchio model, from its joint
placements) in the same function, so one call does the whole tick. The noise
settings, the IMU position and the leg geometry are baked into the source; it
is compiled once per setting into the codegen cache
(:func:`amlip_qp.codegen.runtime.compile_and_load`).

The contact flags enter as numbers 0/1: a foot out of contact gets a zero
measurement row and a unit variance (so its gain is exactly zero), and a
touchdown re-initialises its slot through a selection matrix, so the code has
no branches but the small-angle one of ``Exp``.
"""

from __future__ import annotations

import os

import casadi as ca
import numpy as np

from amlip_qp.codegen import generate, runtime
from amlip_qp.estimation.invariant_ekf import DIM, GRAVITY_MPS2, EkfNoise, EkfState
from amlip_qp.estimation.leg_kinematics import LegKinematics
from amlip_qp.exceptions import CodegenError

FUNCTION_NAME = "ekf_tick"
SOURCE_FILE = "amlip_ekf.c"
LIBRARY_FILE = "libamlip_ekf.so"
#: Size of the packed filter state: R (9, row-major), v, p, d_left, d_right, b_g, b_a (3 each), P (441).
N_STATE = 27 + DIM * DIM
#: Size of the packed tick input before the joint angles: gyro, accel (of the previous tick), dt,
#: contact switches now (2), contacts the previous tick used (2), gyro now, the ground's pitch along
#: the blades (rad, :func:`~amlip_qp.estimation.invariant_ekf.blade_is_flat`); then ``q[7:]``.
N_INPUT_HEAD = 3 + 3 + 1 + 2 + 2 + 3 + 1
#: Index of the ground's pitch in the packed tick input.
GROUND_PITCH_INDEX = 14
#: The joint types the generated leg kinematics knows: Pinocchio short name -> rotation axis.
_REVOLUTE_AXES = {"JointModelRX": (1.0, 0.0, 0.0), "JointModelRY": (0.0, 1.0, 0.0), "JointModelRZ": (0.0, 0.0, 1.0)}


def _skew(w):
    return ca.vertcat(ca.horzcat(0, -w[2], w[1]), ca.horzcat(w[2], 0, -w[0]), ca.horzcat(-w[1], w[0], 0))


def _so3_exp(phi):
    K = _skew(phi)
    K2 = ca.mtimes(K, K)
    th2 = phi[0] ** 2 + phi[1] ** 2 + phi[2] ** 2
    th = ca.sqrt(th2)
    s, co = ca.sin(th), ca.cos(th)
    small = th2 < 1e-10
    a = ca.if_else(small, 1.0 - th2 / 6.0, s / th)
    b = ca.if_else(small, 0.5 - th2 / 24.0, (1.0 - co) / th2)
    c = ca.if_else(small, 1.0 / 6.0 - th2 / 120.0, (th - s) / (th2 * th))
    eye = ca.SX.eye(3)
    return eye + a * K + b * K2, eye + b * K + c * K2


def _quat_xyzw(R):
    """Shepperd's method with ``w >= 0``, as :func:`~amlip_qp.estimation.rotations.rot_to_quat_xyzw`."""
    r00, r01, r02 = R[0, 0], R[0, 1], R[0, 2]
    r10, r11, r12 = R[1, 0], R[1, 1], R[1, 2]
    r20, r21, r22 = R[2, 0], R[2, 1], R[2, 2]
    tr = r00 + r11 + r22
    s0 = 2.0 * ca.sqrt(tr + 1.0)
    q0 = ca.vertcat((r21 - r12) / s0, (r02 - r20) / s0, (r10 - r01) / s0, 0.25 * s0)
    s1 = 2.0 * ca.sqrt(1.0 + r00 - r11 - r22)
    q1 = ca.vertcat(0.25 * s1, (r01 + r10) / s1, (r02 + r20) / s1, (r21 - r12) / s1)
    s2 = 2.0 * ca.sqrt(1.0 + r11 - r00 - r22)
    q2 = ca.vertcat((r01 + r10) / s2, 0.25 * s2, (r12 + r21) / s2, (r02 - r20) / s2)
    s3 = 2.0 * ca.sqrt(1.0 + r22 - r00 - r11)
    q3 = ca.vertcat((r02 + r20) / s3, (r12 + r21) / s3, 0.25 * s3, (r10 - r01) / s3)
    q = ca.if_else(tr > 0, q0, ca.if_else(ca.logic_and(r00 > r11, r00 > r22), q1, ca.if_else(r11 > r22, q2, q3)))
    return ca.if_else(q[3] < 0, -q, q)


def _rotation(axis, angle):
    """Rotation by ``angle`` about a constant unit ``axis`` (Rodrigues), as SX."""
    K = ca.DM([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return ca.SX.eye(3) + ca.sin(angle) * K + (1 - ca.cos(angle)) * ca.mtimes(K, K)


def _contacts_in_imu(legs: LegKinematics, q_joints):
    """:meth:`LegKinematics.contacts_in_imu <amlip_qp.estimation.leg_kinematics.LegKinematics.contacts_in_imu>`
    and :meth:`~amlip_qp.estimation.leg_kinematics.LegKinematics.blades_in_imu` on symbols (the blades
    ``None`` without blade feet): the joint chains from the base (at the identity) to the contact frames.

    Raises:
        CodegenError: A joint on a chain is not a revolute joint about x, y or z.
    """
    model = legs.model
    placements: dict[int, tuple] = {}

    def joint(j: int):
        if j not in placements:
            Mj = model.jointPlacements[j]
            R_pl, p_pl = ca.DM(Mj.rotation), ca.DM(Mj.translation)
            if j == 1 or model.parents[j] == 0:  # the free-flyer base, at the identity
                placements[j] = (ca.SX(R_pl), ca.SX(p_pl))
            else:
                kind = model.joints[j].shortname()
                if kind not in _REVOLUTE_AXES:
                    raise CodegenError(f"the compiled EKF's leg kinematics has no {kind} (joint {model.names[j]!r})")
                R_par, p_par = joint(model.parents[j])
                angle = q_joints[model.idx_qs[j] - 7]
                placements[j] = (
                    ca.mtimes([R_par, R_pl, _rotation(_REVOLUTE_AXES[kind], angle)]),
                    p_par + ca.mtimes(R_par, p_pl),
                )
        return placements[j]

    def position(fid: int):
        frame = model.frames[fid]
        R_j, p_j = joint(frame.parentJoint)
        return p_j + ca.mtimes(R_j, ca.DM(frame.placement.translation))

    out = [position(fid) - ca.DM(legs.imu_pos_in_base_m) for fid in legs.frame_ids]
    if legs.blade_frame_ids is None:
        return out, None
    return out, [position(toe) - position(heel) for toe, heel in legs.blade_frame_ids]


def _sym(P):
    """The symmetric matrix made of the upper triangle of ``P`` (the lower entries are never computed)."""
    out = ca.SX(DIM, DIM)
    for i in range(DIM):
        for j in range(i, DIM):
            out[i, j] = P[i, j]
            out[j, i] = P[i, j]
    return out


def _function(noise: EkfNoise, legs: LegKinematics) -> ca.Function:
    n = noise
    x = ca.SX.sym("state", N_STATE)
    u = ca.SX.sym("input", N_INPUT_HEAD + legs.model.nq - 7)
    R = ca.reshape(x[0:9], 3, 3).T
    v, p = x[9:12], x[12:15]
    d = [x[15:18], x[18:21]]
    bg, ba = x[21:24], x[24:27]
    P = _sym(ca.reshape(x[27:], DIM, DIM).T)  # only the upper triangle is read
    gyro, accel, dt = u[0:3], u[3:6], u[6]
    c_now, c_before = [u[7], u[8]], [u[9], u[10]]
    gyro_now = u[11:14]
    ground_pitch = u[GROUND_PITCH_INDEX]
    y, blades = _contacts_in_imu(legs, u[N_INPUT_HEAD:])
    r_imu = ca.DM(legs.imu_pos_in_base_m)
    g = ca.DM(GRAVITY_MPS2)
    I3 = ca.SX.eye(3)

    # --- propagation (InvariantEKF.error_dynamics / propagate)
    M = ca.vertcat(I3, _skew(v), _skew(p), _skew(d[0]), _skew(d[1]))
    A = ca.SX(DIM, DIM)
    A[3:6, 0:3] = _skew(g)
    A[6:9, 3:6] = I3
    A[0:15, 15:18] = -ca.mtimes(M, R)
    A[3:6, 18:21] = -R
    Phi = ca.SX.eye(DIM) + A * dt
    q_diag = np.zeros(DIM)
    q_diag[3:6] = n.accel_std**2
    q_diag[9:15] = n.contact_std**2
    q_diag[15:18] = n.gyro_bias_std**2
    q_diag[18:21] = n.accel_bias_std**2
    Q = ca.SX(ca.DM(np.diag(q_diag)))
    Q[0:15, 0:15] += n.gyro_std**2 * ca.mtimes(M, M.T)
    P = _sym(ca.mtimes([Phi, P, Phi.T]) + Q * dt)
    w = (gyro - bg) * dt
    acc = ca.mtimes(R, accel - ba) + g
    p = p + v * dt + (0.5 * dt * dt) * acc
    v = v + acc * dt
    R = ca.mtimes(R, _so3_exp(w)[0])

    # --- a blade foot counts as in contact only while flat (InvariantEKF.set_contacts / blade_is_flat)
    if blades is not None:
        tol = float(n.max_blade_slope_rad)
        sin_tol = float(np.sin(tol))
        up = -ground_pitch
        for i in range(2):
            blade_w = ca.mtimes(R, blades[i])
            norm = ca.sqrt(ca.dot(blade_w, blade_w))
            level = ca.fabs(blade_w[2]) <= sin_tol * norm
            sloped = ca.logic_and(ca.sin(up - tol) * norm <= blade_w[2], blade_w[2] <= ca.sin(up + tol) * norm)
            flat = ca.if_else(ground_pitch == 0, level, sloped)
            c_now[i] = ca.if_else(flat, c_now[i], 0.0)

    # --- touchdown: restart the slot at p + R y with the covariance augmentation (InvariantEKF._augment)
    for i in range(2):
        aug = c_now[i] * (1 - c_before[i]) > 0.5
        s = range(9 + 3 * i, 12 + 3 * i)
        src = {k: 6 + (k - s[0]) if k in s else k for k in range(DIM)}  # row/column k takes src[k]
        Pa = ca.SX(P)
        for a in range(DIM):
            for b in range(a, DIM):
                if a in s or b in s:
                    extra = n.kinematics_std**2 if (a == b) else 0.0
                    Pa[a, b] = ca.if_else(aug, P[src[a], src[b]] + extra, P[a, b])
                    Pa[b, a] = Pa[a, b]
        P = Pa
        d[i] = ca.if_else(aug, p + ca.mtimes(R, y[i]), d[i])

    # --- correction (InvariantEKF.correct): the six scalar rows one after the other, which is the
    # batch update exactly (the noise is diagonal and H constant); a foot out of contact has a zero row
    # and unit variance, so a zero gain.
    xi = ca.SX.zeros(DIM)
    for i in range(2):
        c = c_now[i]
        z = c * (ca.mtimes(R, y[i]) - (d[i] - p))
        var = c * n.kinematics_std**2 + (1 - c)
        for axis in range(3):
            jp, jd = 6 + axis, 9 + 3 * i + axis
            Ph = c * (P[:, jp] - P[:, jd])  # P h^T
            s_ = c * (Ph[jp] - Ph[jd]) + var
            k = Ph / s_
            xi = xi + k * (z[axis] - c * (xi[jp] - xi[jd]))
            P = _sym(P - ca.mtimes(k, Ph.T))
    xi = -xi
    dR, J = _so3_exp(xi[0:3])
    R = ca.mtimes(dR, R)
    v = ca.mtimes(dR, v) + ca.mtimes(J, xi[3:6])
    p = ca.mtimes(dR, p) + ca.mtimes(J, xi[6:9])
    d = [ca.mtimes(dR, d[i]) + ca.mtimes(J, xi[9 + 3 * i : 12 + 3 * i]) for i in range(2)]
    bg = bg + xi[15:18]
    ba = ba + xi[18:21]

    # --- the base pose and twist (EkfBaseEstimator), and the divergence signals
    w_b = gyro_now - bg
    base_q = ca.vertcat(p - ca.mtimes(R, r_imu), _quat_xyzw(R))
    base_v = ca.vertcat(ca.mtimes(R.T, v) - ca.cross(w_b, r_imu), w_b)
    state = ca.vertcat(ca.reshape(R.T, 9, 1), v, p, d[0], d[1], bg, ba, ca.reshape(P.T, DIM * DIM, 1))
    checks = ca.vertcat(ca.trace(P), ca.dot(v, v))
    used = ca.vertcat(c_now[0], c_now[1])
    return ca.Function(
        FUNCTION_NAME, [x, u],
        [ca.densify(state), ca.densify(ca.vertcat(base_q, base_v)), ca.densify(checks), ca.densify(used)],
        ["state", "input"], ["state_next", "base", "checks", "contacts"],
    )  # fmt: skip


def generate_source(noise: EkfNoise, legs: LegKinematics) -> bytes:
    """The C source of one EKF tick for these settings and this robot's leg kinematics."""
    fn = _function(noise, legs)
    return generate.single_file_source([fn], SOURCE_FILE)


class CompiledEkf:
    """The generated-C EKF tick on packed buffers (see the module doc).

    Raises:
        CompilerUnavailableError: No C compiler.
        CodegenError: The compiler rejected the source or the library does not load.
    """

    def __init__(self, noise: EkfNoise, legs: LegKinematics, cache_dir: str | os.PathLike | None = None):
        source = generate_source(noise, legs)
        self.library_path, functions = runtime.compile_and_load(
            source, [FUNCTION_NAME], SOURCE_FILE, LIBRARY_FILE, cache_dir
        )
        fn = functions[FUNCTION_NAME]
        #: The packed filter state (input of the tick).
        self.state = np.zeros(N_STATE)
        #: The packed tick input.
        self.input = np.zeros(N_INPUT_HEAD + legs.model.nq - 7)
        #: The joint angles ``q[7:]`` (a view into :attr:`input`).
        self.q_joints = self.input[N_INPUT_HEAD:]
        self._next = np.zeros(N_STATE)
        #: The base ``q[:7]`` and ``v[:6]`` after the last tick.
        self.base = np.zeros(13)
        #: ``trace(P)`` and ``|v|^2`` after the last tick.
        self.checks = np.zeros(2)
        #: The contacts the last tick used (0/1, left and right; a blade foot counts once flat).
        self.contacts = np.zeros(2)
        self._buffer, self._eval = fn.buffer()
        for i, arr in enumerate((self.state, self.input)):
            self._buffer.set_arg(i, memoryview(arr))  # type: ignore[call-arg, arg-type]
        for i, arr in enumerate((self._next, self.base, self.checks, self.contacts)):
            if fn.nnz_out(i) != arr.size:
                raise CodegenError(f"{self.library_path}: {FUNCTION_NAME} output {i} has the wrong size")
            self._buffer.set_res(i, memoryview(arr))  # type: ignore[call-arg, arg-type]

    def load(self, st: EkfState) -> None:
        """Set the packed state from ``st``."""
        x = self.state
        x[0:9] = st.R.reshape(-1)
        x[9:12], x[12:15] = st.v, st.p
        x[15:21] = st.d.reshape(-1)
        x[21:24], x[24:27] = st.bg, st.ba
        x[27:] = st.P.reshape(-1)

    def unpack(self) -> EkfState:
        """A copy of the state (the covariance made symmetric from its upper triangle)."""
        x = self.state.copy()
        P = x[27:].reshape(DIM, DIM)
        P = np.triu(P) + np.triu(P, 1).T
        return EkfState(x[0:9].reshape(3, 3), x[9:12], x[12:15], x[15:21].reshape(2, 3), x[21:24], x[24:27], P)

    def tick(self) -> None:
        """Run one tick on :attr:`input`; :attr:`state` becomes the new state."""
        self._eval()
        self.state[:] = self._next
