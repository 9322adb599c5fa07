"""Pinocchio kinematics and dynamics of a model at the last update, for any Pinocchio model.

Usage: :class:`~amlip_qp.robots.kinematics.RobotKinematics` (this class with
the robot's contacts, root body, passive forces and output map) is what the
controllers create, one per controller; call :meth:`ModelKinematics.update`
once per control tick with the Pinocchio state ``(q, v)``; it runs
Pinocchio's passes once (``computeAllTerms``: kinematics, joint Jacobians,
CoM and its Jacobian, CRBA, nonlinear effects, centroidal momentum, and the
joint accelerations at zero ``vdot``, which give the drift terms; then the
frame placements and the CoM acceleration). The getters afterwards only read
and combine cached results: Jacobians and drifts are fetched from Pinocchio
once per update, and frame placements, the CoM and the momentum are read
through views into Pinocchio's data made once (a fresh Pinocchio accessor
costs about a microsecond per item, a control tick needs dozens).

:meth:`ModelKinematics.update_positions` is a lighter update for iterative
kinematics (the IK): positions, Jacobians and the CoM at ``q`` with ``v = 0``;
drifts and momenta are then zero and the dynamics getters raise.
:meth:`ModelKinematics.update_kinematics` is the kinematics of :meth:`ModelKinematics.update`
at ``(q, v)`` (positions, Jacobians, drifts, the CoM terms) without the dynamics.

All vectors are in world axes and SI units. Jacobians are world-aligned
(Pinocchio's ``LOCAL_WORLD_ALIGNED``) and map Pinocchio's ``v``; a
"``jdot_v``" is the classical-acceleration drift ``Jdot v`` (the acceleration
with ``vdot = 0``), so ``xddot = J vdot + jdot_v``.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from amlip_qp.exceptions import InputError

if TYPE_CHECKING:
    import pinocchio as pin


class ModelKinematics:
    """Pinocchio kinematics/dynamics of one model at the last ``update(q, v)``.

    A subclass with per-update caches of its own extends :meth:`_invalidate`
    (called by both updates) and may call :meth:`_ready` (the getters' test
    that an update ran).

    Attributes:
        model: The Pinocchio model.
        data: This object's own Pinocchio data.
        q: The configuration of the last update (copy), shape (nq,).
        v: The velocity of the last update (copy), shape (nv,).
    """

    def __init__(self, model: pin.Model):
        """Create the Pinocchio data of ``model``; call :meth:`update` before any getter."""
        import pinocchio as pin

        self._pin = pin
        self.model = model
        self.data = self.model.createData()
        self._q_shape = (self.model.nq,)
        self._v_shape = (self.model.nv,)
        self._lwa = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
        self._com_acc_level = pin.KinematicLevel.ACCELERATION
        # computeAllTerms' total mass (its sum of the bodies' masses, in its order; q-independent),
        # the divisor of its CoM Jacobian (update_kinematics forms that Jacobian the same way).
        scratch = model.createData()
        pin.computeAllTerms(model, scratch, pin.neutral(model), np.zeros(model.nv))
        self._cat_mass = float(scratch.mass[0])
        self.q: np.ndarray | None = None
        self.v: np.ndarray | None = None
        # Per-update caches (cleared by _invalidate), filled on first use.
        self._jac: dict[int, np.ndarray] = {}
        self._acc: dict[int, np.ndarray] = {}
        self._jac3: dict[int, np.ndarray] = {}  # translational rows of _jac (views)
        self._acc3: dict[int, np.ndarray] = {}  # linear part of _acc (views)
        self._bind_views()
        self._M: np.ndarray | None = None
        #: True after :meth:`update_positions` (no dynamics, zero velocity).
        self.positions_only = False
        self._dynamics = False  # True after update(q, v) only
        self._zero_a = np.zeros(self.model.nv)  # the zero vdot of update_kinematics' drift pass
        # Shared zero drifts of update_positions(): read-only, as callers get views.
        self._zero3 = np.zeros(3)
        self._zero6 = np.zeros(6)
        self._zero3.flags.writeable = False
        self._zero6.flags.writeable = False

    # ------------------------------------------------------------------ update
    def update(self, q, v) -> None:
        """Run Pinocchio's passes at the state ``(q, v)`` (Pinocchio convention).

        Raises:
            InputError: Wrong shapes or NaN/inf.
        """
        pin = self._pin
        q = np.array(q, dtype=float)  # own copies: the caller may reuse its arrays
        v = np.array(v, dtype=float)
        if q.shape != self._q_shape or v.shape != self._v_shape:
            raise InputError(f"q, v must have shapes ({self.model.nq},), ({self.model.nv},); got {q.shape}, {v.shape}")
        # One cheap test per tick: a finite sum implies finite entries (NaN and
        # inf propagate); only if it fails (NaN, inf or overflow) check exactly.
        if not math.isfinite(sum(q.tolist()) + sum(v.tolist())) and not (np.isfinite(q).all() and np.isfinite(v).all()):
            raise InputError("q or v contains NaN or inf")
        self.q, self.v = q, v
        m, d = self.model, self.data
        if d is not self._views_data:
            self._bind_views()
        # computeAllTerms' forward pass also leaves data.a at the joint
        # accelerations for vdot = 0 (bitwise the same as a separate
        # forwardKinematics(q, v, 0)); the frame drifts and acom use them.
        pin.computeAllTerms(m, d, q, v)
        pin.updateFramePlacements(m, d)
        pin.centerOfMass(m, d, self._com_acc_level, False)
        self._invalidate(False)
        self._dynamics = True

    def update_kinematics(self, q, v) -> None:
        """Kinematics-only update at the state ``(q, v)``: no dynamics.

        Runs the joint placements and Jacobians with the CoM Jacobian, the joint
        velocities and their accelerations at zero ``vdot`` (the drifts), the
        frame placements and the CoM's position, velocity and drift: every
        frame and CoM getter and :meth:`outputs` with its drift read as after
        :meth:`update`, to the last bit (the CoM Jacobian as ``computeAllTerms``
        forms it: the linear rows of the centroidal map over the total mass, not
        ``jacobianCenterOfMass``'s sum, which differs by about 1e-16). The dynamics (CRBA, the
        nonlinear effects, the centroidal momentum) are not computed:
        ``mass_matrix``, ``nonlinear_effects``, the momenta and
        ``centroidal_momentum_matrix`` raise :class:`~amlip_qp.exceptions.InputError`
        until the next :meth:`update`. For iterative kinematics that needs the
        drifts (the IK's last iterate); ``q`` and ``v`` are not checked (a hot
        path): pass finite arrays of shapes (nq,), (nv,).
        """
        pin = self._pin
        m, d = self.model, self.data
        if d is not self._views_data:
            self._bind_views()
        self.q = q = np.array(q, dtype=float)
        self.v = v = np.array(v, dtype=float)
        # The centroidal map's pass computes the joint placements and Jacobians (data.J) and the
        # composite inertias' map Ag as computeAllTerms does (the same bits); computeAllTerms' CoM
        # Jacobian is its linear rows over the total mass. forwardKinematics then adds the velocities
        # and the drift accelerations (the same placements).
        pin.computeCentroidalMap(m, d, q)
        np.divide(self._ag_linear, self._cat_mass, out=self._jcom_view)
        pin.forwardKinematics(m, d, q, v, self._zero_a)
        pin.updateFramePlacements(m, d)
        pin.centerOfMass(m, d, self._com_acc_level, False)
        self._invalidate(False)

    def update_positions(self, q) -> None:
        """Light update at the configuration ``q`` only, with ``v = 0``.

        Runs the joint placements and Jacobians, the frame placements, the CoM
        and its Jacobian: enough for the frame/contact/CoM positions and
        Jacobians, the base rotation and :meth:`outputs` ``(y, J)``. No
        velocity pass: ``v`` is set to zero, so every velocity-dependent term is
        zero and returned as such (``com_velocity``, the ``*jdot_v`` drifts,
        the momenta; the third item of :meth:`outputs` is zeros). The dynamics
        (``mass_matrix``, ``nonlinear_effects``, ``centroidal_momentum_matrix``)
        are not computed and raise :class:`~amlip_qp.exceptions.InputError`
        until the next :meth:`update`. ``q`` is not checked (hot path of the IK):
        pass a finite configuration of shape (nq,).
        """
        pin = self._pin
        m, d = self.model, self.data
        if d is not self._views_data:
            self._bind_views()
        self.q = np.array(q, dtype=float)
        if self.v is None or self.v.shape != (m.nv,) or not self.positions_only:
            self.v = np.zeros(m.nv)
        # One pass: the CoM Jacobian computes the joint placements and the joint
        # Jacobians (data.J) too (a separate computeJointJacobians gave the same bits).
        pin.jacobianCenterOfMass(m, d, self.q, False)  # also com[0]
        pin.updateFramePlacements(m, d)
        self._invalidate(True)

    def _bind_views(self) -> None:
        """Make the live views into :attr:`data` used by the getters.

        eigenpy maps Pinocchio's C++ storage into numpy without copying, and
        every update overwrites that storage in place, so a view taken once
        always shows the last update. Reading a view costs ~0.1 µs where a
        fresh accessor (``data.oMf[i].translation``, ``data.com[0]``) costs
        1-2 µs. The views do not keep the data alive: ``_views_data`` does,
        and the updates re-bind if :attr:`data` was replaced. The public views
        (:meth:`frame_translation_view`, :meth:`frame_rotation_view`,
        :attr:`com_view`) serve the output maps and the QP assembly, which
        copy them (or convert them to floats) right away and never keep them.
        """
        d = self.data
        self._views_data = d
        #: Read-only live view of the CoM position (m); copy it at once, never keep or write it.
        self.com_view = d.com[0]
        self._jcom_view = d.Jcom
        self._ag_linear = d.Ag[:3]
        self._vcom_view = d.vcom[0]
        self._acom_view = d.acom[0]
        self._hg_view = d.hg.vector  # (m v_c, L_c)
        self._translation_views: dict[int, np.ndarray] = {}
        self._rotation_views: dict[int, np.ndarray] = {}

    def _invalidate(self, positions_only: bool) -> None:
        """Drop the per-update caches (both update kinds); a subclass with caches of its own extends it."""
        self._jac.clear()
        self._acc.clear()
        self._jac3.clear()
        self._acc3.clear()
        self._M = None
        self.positions_only = positions_only
        self._dynamics = False

    def _ready(self) -> None:
        if self.q is None or self.v is None:  # state()'s test, without its call (a dozen getters a tick)
            self.state()

    def state(self) -> tuple[np.ndarray, np.ndarray]:
        """``(q, v)`` of the last update: :attr:`q`, :attr:`v` themselves (read-only); InputError before any."""
        q, v = self.q, self.v
        if q is None or v is None:
            raise InputError(f"{type(self).__name__}: call update(q, v) first")
        return q, v

    def require_dynamics(self) -> None:
        """Raise :class:`InputError` unless the last update was a full ``update(q, v)``."""
        self._ready()
        if not self._dynamics:
            raise InputError(
                f"{type(self).__name__}: dynamics not computed by update_positions() or update_kinematics();"
                " call update(q, v)"
            )

    # ------------------------------------------------------------- frames
    def frame_position(self, frame_id: int) -> np.ndarray:
        """World position (m) of a Pinocchio frame, shape (3,)."""
        self._ready()
        return self.frame_translation_view(frame_id).copy()

    def frame_translation_view(self, frame_id: int) -> np.ndarray:
        """Read-only live view of ``data.oMf[frame_id].translation``, m (see :meth:`_bind_views`).

        For hot loops that copy the numbers at once; never keep or write it.
        """
        view = self._translation_views.get(frame_id)
        if view is None:
            view = self._translation_views[frame_id] = self.data.oMf[frame_id].translation
        return view

    def frame_rotation(self, frame_id: int) -> np.ndarray:
        """World rotation matrix of a Pinocchio frame, shape (3, 3)."""
        self._ready()
        return self.frame_rotation_view(frame_id).copy()

    def frame_rotation_view(self, frame_id: int) -> np.ndarray:
        """Read-only live view of ``data.oMf[frame_id].rotation`` (see :meth:`_bind_views`).

        For hot loops that copy the numbers at once; never keep or write it.
        """
        view = self._rotation_views.get(frame_id)
        if view is None:
            view = self._rotation_views[frame_id] = self.data.oMf[frame_id].rotation
        return view

    def frame_jacobian6(self, frame_id: int) -> np.ndarray:
        """World-aligned 6 x nv Jacobian (linear rows first, then angular) of a frame.

        Cached until the next update (treat as read-only).
        """
        jac = self._jac.get(frame_id)
        if jac is None:
            self._ready()
            jac = self._pin.getFrameJacobian(self.model, self.data, frame_id, self._lwa)
            self._jac[frame_id] = jac
        return jac

    def frame_jdot_v6(self, frame_id: int) -> np.ndarray:
        """World-aligned classical acceleration drift of a frame (linear, angular), shape (6,).

        Cached until the next update (treat as read-only).
        """
        acc = self._acc.get(frame_id)
        if acc is None:
            self._ready()
            if self.positions_only:
                return self._zero6
            a = self._pin.getFrameClassicalAcceleration(self.model, self.data, frame_id, self._lwa)
            # (linear, angular); the view keeps this fresh Motion object (not Pinocchio's data) alive.
            acc = self._acc[frame_id] = a.vector
        return acc

    def frame_jacobian(self, frame_id: int) -> np.ndarray:
        """World-aligned translational Jacobian (3 x nv) of a frame's origin.

        Cached until the next update (treat as read-only).
        """
        jac = self._jac3.get(frame_id)
        if jac is None:
            jac = self._jac3[frame_id] = self.frame_jacobian6(frame_id)[:3]
        return jac

    def frame_jdot_v(self, frame_id: int) -> np.ndarray:
        """``Jdot v`` (m/s^2) of a frame's origin, world axes, shape (3,).

        Cached until the next update (treat as read-only).
        """
        acc = self._acc3.get(frame_id)
        if acc is None:
            acc = self._acc3[frame_id] = self.frame_jdot_v6(frame_id)[:3]
        return acc

    # ------------------------------------------------------- centre of mass
    @property
    def mass_kg(self) -> float:
        """Total mass (kg): Pinocchio's sum of the bodies' masses, taken once (it does not depend on
        ``q``; every update's ``data.mass[0]`` has the same bits, tests/test_robots_model_kinematics.py)."""
        return self._cat_mass

    def com(self) -> np.ndarray:
        """Centre of mass ``c`` (m), shape (3,)."""
        self._ready()
        return self.com_view.copy()

    def com_velocity(self) -> np.ndarray:
        """CoM velocity ``v_c`` (m/s), shape (3,)."""
        self._ready()
        if self.positions_only:
            return self._zero3.copy()
        return self._vcom_view.copy()

    def com_jacobian(self) -> np.ndarray:
        """CoM Jacobian (3 x nv)."""
        self._ready()
        return self.data.Jcom

    def com_jdot_v(self) -> np.ndarray:
        """CoM acceleration drift ``Jcom_dot v`` (m/s^2), shape (3,)."""
        self._ready()
        if self.positions_only:
            return self._zero3.copy()
        return self._acom_view.copy()

    # ------------------------------------------------------------ momentum
    def centroidal_momentum(self) -> tuple[np.ndarray, np.ndarray]:
        """``(m v_c, L_c)``: linear momentum (kg m/s) and angular momentum about the CoM (kg m^2/s), world axes."""
        self.require_dynamics()
        hg = self._hg_view
        return hg[:3].copy(), hg[3:].copy()

    def angular_momentum_about(self, point) -> np.ndarray:
        """Angular momentum ``L = L_c + (c - r) x m v_c`` (kg m^2/s) about a world point ``r`` (m)."""
        self.require_dynamics()
        l0, l1, l2, a0, a1, a2 = self._hg_view.tolist()
        r = np.asarray(point, dtype=float)
        if r.shape != (3,):
            raise InputError(f"point must be a finite 3-vector, got {r!r}")
        r0, r1, r2 = r.tolist()
        if not (math.isfinite(r0) and math.isfinite(r1) and math.isfinite(r2)):
            raise InputError(f"point must be a finite 3-vector, got {r!r}")
        c0, c1, c2 = self.com_view.tolist()
        p0, p1, p2 = c0 - r0, c1 - r1, c2 - r2
        # p x (m v_c), written out on floats: numpy's cross costs ~20 µs on 3-vectors.
        return np.array(
            [
                a0 + p1 * l2 - p2 * l1,
                a1 + p2 * l0 - p0 * l2,
                a2 + p0 * l1 - p1 * l0,
            ]
        )

    def centroidal_momentum_matrix(self) -> np.ndarray:
        """Centroidal momentum matrix ``A_g`` (6 x nv): ``(m v_c, L_c) = A_g v``."""
        self.require_dynamics()
        return self.data.Ag

    # ------------------------------------------------------------ dynamics
    def mass_matrix(self) -> np.ndarray:
        """Joint-space inertia matrix ``M(q)`` (nv x nv, symmetric, armature included).

        Cached until the next :meth:`update` (treat as read-only).
        """
        self.require_dynamics()
        if self._M is None:
            # CRBA fills the upper triangle; Pinocchio's Python computeAllTerms mirrors it into the lower
            # one (tests/test_robots_model_kinematics.py checks M == M^T bit for bit): a copy is enough.
            self._M = self.data.M.copy()
        return self._M

    def nonlinear_effects(self) -> np.ndarray:
        """``h = C(q, v) v + g(q)`` (N m / N), shape (nv,)."""
        self.require_dynamics()
        return self.data.nle.copy()
