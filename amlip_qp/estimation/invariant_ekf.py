"""Contact-aided right-invariant EKF (Hartley, Ghaffari, Eustice & Grizzle, IJRR 2020).

R. Hartley, M. Ghaffari, R. M. Eustice, J. W. Grizzle, "Contact-aided
invariant extended Kalman filtering for robot state estimation", IJRR 39(4), 2020.

**State.** ``X`` in ``SE_{2+K}(3)`` with ``K = 2`` contact points: the IMU
orientation ``R`` (IMU to world), velocity ``v`` and position ``p`` of the IMU
(world axes), the contact points ``d_left``, ``d_right`` (world), plus the
gyro and accelerometer biases ``b_g``, ``b_a`` (IMU axes) beside the group
(the paper's "imperfect" IEKF with IMU biases). The error is right-invariant,
``eta = X_hat X^-1 ~ exp(xi)``, ordered
``xi = [xi_R, xi_v, xi_p, xi_dl, xi_dr, d b_g, d b_a]`` (21; ``d b = b_hat - b``).

**Contacts.** Both contact slots stay in the state at all times (a fixed
21-dimensional filter, no resizing in the 2 kHz loop). A slot is used only
while its foot is in contact; at touchdown it is re-initialised from the
leg kinematics, ``d = p + R y``, with the paper's augmentation of the
covariance (``P_dd = P_pp + R Sigma_fk R^T``, ``P_dx = P_px``), so whatever it
held in swing is forgotten. Feet in contact are assumed stationary up to a
white slip velocity (``contact_std``).

**A blade foot counts as a fixed contact only while it rests flat.** Cassie's
foot is a blade that lands on its heel and rolls onto the toe while already
loaded: on the closed-chain plant the contact site (the foot joint, above the
blade) moves by about 0.3 m/s forward and 0.25 m/s down for the first ~40 ms
of every stance. Taken as a fixed point, that motion biased the velocity
estimate by 0.04 m/s. So a foot whose switch reports contact is used only while
its blade (toe minus heel, from the leg kinematics) lies within
``max_blade_slope_rad`` of the ground by the estimated orientation: of the
horizontal on level ground and when blind, and of the ground's pitch along
the heading that the walking controller passes where it is given the terrain
(``ground_pitch_rad`` of :meth:`InvariantEKF.set_contacts`; on a 30 degree
slope a blade resting on the ground is 30 degrees from the horizontal, and
taken against the horizontal no stance counted). It touches down, for the
filter, when it lands flat. Feet without a blade (``blades_in_imu`` ``None``)
are used from the switch alone.

**Propagation** (IMU, control period ``dt``): ``R <- R Exp(w dt)``,
``p <- p + v dt + (R a + g) dt^2/2``, ``v <- v + (R a + g) dt`` with the
bias-corrected gyro ``w`` and specific force ``a``; the covariance with the
error's state transition ``Phi = exp(A dt)`` to first order, ``I + A dt``
(the neglected ``(A dt)^2 / 2`` is ``|A| dt / 2``, about 3e-3, of the kept
term at 2 kHz; the tests check ``Phi`` against finite differences of the
propagation), and ``Q_d = G Q G^T dt`` with isotropic densities (so
``R Sigma R^T = Sigma``).

**Correction** (each foot in contact): ``y = R^T (d - p)`` measured by the leg
kinematics; innovation ``z = R_hat y - (d_hat - p_hat) = H xi`` with the
constant ``H = [0 0 I -I 0 ...]`` (``xi`` is the estimate's error, so the
update removes its estimate ``K z``): ``X <- exp(-K z) X``, ``b <- b - K_b z``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from amlip_qp.exceptions import InputError

#: Gravity, world axes (z up), m/s^2.
GRAVITY_MPS2 = np.array([0.0, 0.0, -9.81])
#: Dimension of the error state.
DIM = 21
#: Slices of the error state.
R_, V_, P_, BG_, BA_ = slice(0, 3), slice(3, 6), slice(6, 9), slice(15, 18), slice(18, 21)
#: Slice of contact slot ``i`` (0: left, 1: right).
D_ = (slice(9, 12), slice(12, 15))


@dataclass(frozen=True)
class EkfNoise:
    """Noise and divergence settings (continuous-time densities, SI).

    The defaults are those of Hartley's published filter (``invariant-ekf``'s
    ROS configuration), for a VectorNav VN-100 class IMU on a walking robot:
    they cover vibration and impacts, far above the sensor's data-sheet noise.

    Attributes:
        gyro_std: Gyro white noise, rad/s/sqrt(Hz).
        accel_std: Accelerometer white noise, m/s^2/sqrt(Hz).
        gyro_bias_std: Gyro bias random walk, rad/s^2/sqrt(Hz).
        accel_bias_std: Accelerometer bias random walk, m/s^3/sqrt(Hz).
        contact_std: Slip velocity of a foot in contact, m/s/sqrt(Hz).
        kinematics_std: Leg-kinematics position noise, m (per axis).
        init_rotation_std_rad: Initial orientation uncertainty, rad.
        init_velocity_std_mps: Initial velocity uncertainty, m/s.
        init_position_std_m: Initial position uncertainty, m.
        init_gyro_bias_std_radps: Initial gyro bias uncertainty, rad/s.
        init_accel_bias_std_mps2: Initial accelerometer bias uncertainty, m/s^2.
        max_covariance_trace: Divergence when ``trace(P)`` exceeds this.
        max_speed_mps: Divergence when the estimated speed exceeds this, m/s.
        max_blade_slope_rad: A blade foot is a fixed contact only while its blade is this
            close to the horizontal, rad (1 degree: a blade of 0.16 m with its toe 3 mm up).
    """

    gyro_std: float = 0.01
    accel_std: float = 0.1
    gyro_bias_std: float = 1e-4
    accel_bias_std: float = 1e-3
    contact_std: float = 0.05
    kinematics_std: float = 0.01
    init_rotation_std_rad: float = 0.02
    init_velocity_std_mps: float = 0.1
    init_position_std_m: float = 0.01
    init_gyro_bias_std_radps: float = 0.01
    init_accel_bias_std_mps2: float = 0.1
    max_covariance_trace: float = 1e4
    max_speed_mps: float = 20.0
    max_blade_slope_rad: float = math.radians(1.0)

    def __post_init__(self):
        for name, value in self.__dict__.items():
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
                raise InputError(f"EkfNoise.{name} must be a positive finite number, got {value!r}")


def noise_from_table(table) -> EkfNoise:
    """:class:`EkfNoise` from a profile's ``[estimator]`` table (field name -> number); every other
    field keeps its default.

    Raises:
        InputError: An unknown key (naming the known ones) or a value :class:`EkfNoise` refuses.
    """
    known = tuple(EkfNoise.__dataclass_fields__)
    for key, value in table.items():
        if key not in known:
            raise InputError(f"[estimator]: unknown key {key!r} (known: {', '.join(known)})")
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise InputError(f"[estimator]: {key} must be a number, got {value!r}")
    return EkfNoise(**{k: float(v) for k, v in table.items()})


@dataclass(frozen=True)
class EkfState:
    """A copy of the filter state (see :class:`InvariantEKF` for the fields)."""

    R: np.ndarray
    v: np.ndarray
    p: np.ndarray
    d: np.ndarray
    bg: np.ndarray
    ba: np.ndarray
    P: np.ndarray


def skew(w) -> np.ndarray:
    """``[w]x``, the cross-product matrix of a 3-vector."""
    x, y, z = float(w[0]), float(w[1]), float(w[2])
    return np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])


def so3_exp(phi) -> tuple[np.ndarray, np.ndarray]:
    """``(Exp(phi), J_l(phi))``: the rotation of the rotation vector ``phi`` (rad) and its left Jacobian."""
    K = skew(phi)
    K2 = K @ K
    th2 = float(phi[0]) ** 2 + float(phi[1]) ** 2 + float(phi[2]) ** 2
    if th2 < 1e-10:
        a, b, c = 1.0 - th2 / 6.0, 0.5 - th2 / 24.0, 1.0 / 6.0 - th2 / 120.0
    else:
        th = math.sqrt(th2)
        s, co = math.sin(th), math.cos(th)
        a, b, c = s / th, (1.0 - co) / th2, (th - s) / (th2 * th)
    eye = np.eye(3)
    return eye + a * K + b * K2, eye + b * K + c * K2


def blade_is_flat(R, blade, max_slope_rad: float, ground_pitch_rad: float = 0.0) -> bool:
    """True when ``R @ blade`` (a blade in IMU axes, toe minus heel, in the world) lies within
    ``max_slope_rad`` of the ground: of the horizontal with ``ground_pitch_rad`` 0 (the same test, bit
    for bit), else of the elevation ``-ground_pitch_rad`` (the ground's pitch along the blade, rad,
    positive = descending ahead, as :class:`~amlip_qp.messages.TerrainPrediction`'s)."""
    b = np.asarray(R, dtype=float) @ np.asarray(blade, dtype=float)
    norm = math.sqrt(float(b @ b))
    if ground_pitch_rad == 0.0:
        return abs(float(b[2])) <= math.sin(max_slope_rad) * norm
    up = -float(ground_pitch_rad)
    return math.sin(up - max_slope_rad) * norm <= float(b[2]) <= math.sin(up + max_slope_rad) * norm


def measurement_matrix(in_contact: tuple[bool, bool]) -> np.ndarray:
    """``H`` of the contact measurements of the feet in contact (3 rows each, left first), shape (3k, 21)."""
    rows = []
    for i, c in enumerate(in_contact):
        if c:
            H = np.zeros((3, DIM))
            H[:, P_] = np.eye(3)
            H[:, D_[i]] = -np.eye(3)
            rows.append(H)
    return np.vstack(rows) if rows else np.zeros((0, DIM))


class InvariantEKF:
    """The filter state and its propagation and correction (see the module doc).

    Attributes:
        R: IMU orientation (IMU to world), shape (3, 3).
        v: IMU velocity, world, m/s.
        p: IMU position, world, m.
        d: Contact points (left, right), world, m, shape (2, 3).
        bg: Gyro bias, IMU axes, rad/s.
        ba: Accelerometer bias, IMU axes, m/s^2.
        P: Error covariance, shape (21, 21).
        in_contact: Which contact slots are in use (left, right).
    """

    def __init__(self, noise: EkfNoise | None = None):
        self.noise = noise or EkfNoise()
        n = self.noise
        self.R = np.eye(3)
        self.v = np.zeros(3)
        self.p = np.zeros(3)
        self.d = np.zeros((2, 3))
        self.bg = np.zeros(3)
        self.ba = np.zeros(3)
        self.P = np.eye(DIM)
        self.in_contact = (False, False)
        self._H = {c: measurement_matrix(c) for c in ((False, False), (True, False), (False, True), (True, True))}
        self._N = {c: n.kinematics_std**2 * np.eye(H.shape[0]) for c, H in self._H.items()}
        self._A = np.zeros((DIM, DIM))
        self._A[V_, R_] = skew(GRAVITY_MPS2)
        self._A[P_, V_] = np.eye(3)
        self._M = np.zeros((15, 3))  # [I; [v]x; [p]x; [d_l]x; [d_r]x]
        self._M[0:3] = np.eye(3)
        # Diagonal of the noise density without the gyro's state-dependent part.
        q = np.zeros(DIM)
        q[V_] = n.accel_std**2
        q[9:15] = n.contact_std**2
        q[BG_] = n.gyro_bias_std**2
        q[BA_] = n.accel_bias_std**2
        self._q_diag = np.diag(q)
        self._eye = np.eye(DIM)

    def state(self) -> EkfState:
        """A copy of the state."""
        return EkfState(
            self.R.copy(), self.v.copy(), self.p.copy(), self.d.copy(), self.bg.copy(), self.ba.copy(), self.P.copy()
        )

    # ------------------------------------------------------------------ set up
    def initialise(self, R, p, contacts_in_imu, v=None, bg=None, ba=None) -> None:
        """Start from orientation ``R``, IMU position ``p`` (m), both feet in contact at ``p + R y``.

        Args:
            R: IMU orientation, shape (3, 3).
            p: IMU position, world, m.
            contacts_in_imu: Contact points seen from the IMU (left, right), IMU axes, m, shape (2, 3).
            v: IMU velocity, world, m/s (default 0: at rest).
            bg, ba: Initial biases (default 0).
        """
        n = self.noise
        self.R = np.array(R, dtype=float)
        self.p = np.array(p, dtype=float)
        self.v = np.zeros(3) if v is None else np.array(v, dtype=float)
        self.bg = np.zeros(3) if bg is None else np.array(bg, dtype=float)
        self.ba = np.zeros(3) if ba is None else np.array(ba, dtype=float)
        y = np.asarray(contacts_in_imu, dtype=float)
        self.d = self.p + y @ self.R.T
        P = np.zeros((DIM, DIM))
        P[R_, R_] = n.init_rotation_std_rad**2 * np.eye(3)
        P[V_, V_] = n.init_velocity_std_mps**2 * np.eye(3)
        P[P_, P_] = n.init_position_std_m**2 * np.eye(3)
        P[BG_, BG_] = n.init_gyro_bias_std_radps**2 * np.eye(3)
        P[BA_, BA_] = n.init_accel_bias_std_mps2**2 * np.eye(3)
        self.P = P
        self.in_contact = (False, False)
        for i in range(2):
            self._augment(i, y[i])
        self.in_contact = (True, True)

    def _augment(self, i: int, y: np.ndarray) -> None:
        """(Re)start contact slot ``i`` at ``p + R y`` with the paper's covariance augmentation."""
        self.d[i] = self.p + self.R @ y
        P, s = self.P, D_[i]
        P[s, :] = P[P_, :]
        P[:, s] = P[:, P_]
        P[s, s] += self.noise.kinematics_std**2 * np.eye(3)

    # ------------------------------------------------------------- the models
    def error_dynamics(self) -> np.ndarray:
        """``A`` of the linearised right-invariant error dynamics ``xi' = A xi`` at the estimate, (21, 21)."""
        A, M, R = self._A, self._M, self.R
        M[3:6] = skew(self.v)
        M[6:9] = skew(self.p)
        M[9:12] = skew(self.d[0])
        M[12:15] = skew(self.d[1])
        A[0:15, BG_] = -(M @ R)
        A[V_, BA_] = -R
        return A

    def propagate(self, gyro_radps, accel_mps2, dt_s: float) -> None:
        """One IMU step of ``dt_s`` with the (biased) gyro and accelerometer readings, IMU axes."""
        A = self.error_dynamics()
        Phi = self._eye + A * dt_s
        M = self._M
        Q = self._q_diag.copy()
        Q[0:15, 0:15] += self.noise.gyro_std**2 * (M @ M.T)
        P = Phi @ self.P @ Phi.T + Q * dt_s
        self.P = 0.5 * (P + P.T)
        w = (np.asarray(gyro_radps, dtype=float) - self.bg) * dt_s
        acc = self.R @ (np.asarray(accel_mps2, dtype=float) - self.ba) + GRAVITY_MPS2
        self.p = self.p + self.v * dt_s + (0.5 * dt_s * dt_s) * acc
        self.v = self.v + acc * dt_s
        self.R = self.R @ so3_exp(w)[0]

    def set_contacts(
        self, in_contact: tuple[bool, bool], contacts_in_imu, blades_in_imu=None, ground_pitch_rad: float = 0.0
    ) -> None:
        """Declare which feet are in contact; a foot that just touched down restarts its slot.

        Args:
            in_contact: The contact switches (left, right).
            contacts_in_imu: The contact points seen from the IMU, IMU axes, m, shape (2, 3).
            blades_in_imu: Each blade foot's toe minus heel, IMU axes, m, shape (2, 3), or
                ``None`` (no blades). With blades, a foot counts as in contact only while its
                blade lies flat (:func:`blade_is_flat`).
            ground_pitch_rad: The ground's pitch along the blades, rad (positive = descending ahead;
                0: level ground), which "flat" is taken against.
        """
        c = [bool(in_contact[0]), bool(in_contact[1])]
        if blades_in_imu is not None:
            tol = self.noise.max_blade_slope_rad
            for i in range(2):
                c[i] = c[i] and blade_is_flat(self.R, blades_in_imu[i], tol, ground_pitch_rad)
        for i in range(2):
            if c[i] and not self.in_contact[i]:
                self._augment(i, np.asarray(contacts_in_imu[i], dtype=float))
        self.in_contact = (c[0], c[1])

    def innovation(self, contacts_in_imu) -> np.ndarray:
        """``z = R y - (d - p)`` of the feet in contact (left first), world axes, m, shape (3k,)."""
        y = np.asarray(contacts_in_imu, dtype=float)
        parts = [self.R @ y[i] - (self.d[i] - self.p) for i in range(2) if self.in_contact[i]]
        return np.concatenate(parts) if parts else np.zeros(0)

    def correct(self, contacts_in_imu) -> None:
        """Correct with the leg kinematics of the feet in contact (``y`` per side, IMU axes, m, shape (2, 3))."""
        c = self.in_contact
        if not (c[0] or c[1]):
            return
        H = self._H[c]
        z = self.innovation(contacts_in_imu)
        P = self.P
        PHt = P @ H.T
        S = H @ PHt + self._N[c]
        K = np.linalg.solve(S, PHt.T).T
        xi = -(K @ z)
        P = P - K @ (H @ P)
        self.P = 0.5 * (P + P.T)
        self.retract(xi)

    def retract(self, xi) -> None:
        """``X <- exp(xi[:15]) X``, ``b <- b + xi[15:]`` (the right-invariant update)."""
        dR, J = so3_exp(xi[R_])
        self.R = dR @ self.R
        self.v = dR @ self.v + J @ xi[V_]
        self.p = dR @ self.p + J @ xi[P_]
        self.d = self.d @ dR.T + np.stack([xi[D_[0]], xi[D_[1]]]) @ J.T
        self.bg = self.bg + xi[BG_]
        self.ba = self.ba + xi[BA_]

    def diverged(self) -> bool:
        """Non-finite state or covariance, ``trace(P)`` or speed beyond the :class:`EkfNoise` bounds."""
        tr = float(np.trace(self.P))
        total = tr + float(self.v.sum()) + float(self.p.sum()) + float(self.R.sum())
        if not math.isfinite(total):
            return True
        n = self.noise
        return tr > n.max_covariance_trace or float(self.v @ self.v) > n.max_speed_mps**2
