"""Scalar Kalman filters on the angular momentum about the stance contact
(paper section "Filter for Angular Momentum").

One filter per plane, run at the control rate ``dT``::

    predict:  L_y(k+1) = L_y(k) + m g p_st,x(k) dT  + w,   w ~ N(0, q dT)
              L_x(k+1) = L_x(k) - m g p_st,y(k) dT  + w
    correct:  z(k) = L(k) + v,                            v ~ N(0, r)

with ``z`` the momentum measured from the full-model state.

Noise parameters:

- ``process_var_rate`` ``q``: white-noise intensity of the model error in
  ``dL/dt``, in (kg m^2/s)^2 per second; the per-tick process variance is
  ``q * dT``, so the tuning does not depend on the control rate. It covers what
  the zero-ankle-torque LIP model leaves out (ankle torque, leg swing, springs).
  Default 4.0, i.e. a 2 N m/sqrt(Hz) torque disturbance.
- ``measurement_var`` ``r``: variance of the measured ``L``, (kg m^2/s)^2.
  Default 0.25, i.e. a 0.5 kg m^2/s standard deviation.

Both defaults are starting points for a 30 kg biped; tune them for a robot.

At touchdown the contact point changes, so the filtered ``L`` must be moved
to the new contact: call ``reset`` with the transferred value (see
:func:`amlip_qp.alip.lip.transfer_3d`) or with the first measurement.

The filters work on plain Python floats and allocate nothing per call: they
are meant for a 2 kHz loop.
"""

from __future__ import annotations

import math

from amlip_qp.alip import _checks as C
from amlip_qp.alip.formulas import GRAVITY_MPS2
from amlip_qp.exceptions import InputError


def _finite(x) -> bool:
    """Whether ``x`` is one finite real number (False for NaN, inf, bools, strings, arrays)."""
    try:
        return not isinstance(x, bool) and math.isfinite(x)
    except TypeError:
        return False


#: Default process-noise intensity q, (kg m^2/s)^2 / s.
DEFAULT_PROCESS_VAR_RATE = 4.0
#: Default measurement-noise variance r, (kg m^2/s)^2.
DEFAULT_MEASUREMENT_VAR = 0.25


class MomentumFilter1D:
    """Scalar Kalman filter on one component of ``L`` about the stance contact.

    Args:
        mass_kg: total mass, kg.
        sign: ``+1.0`` for the sagittal component ``L_y`` driven by ``p_st,x``
            (``dL_y/dt = m g p_x``), ``-1.0`` for the lateral ``L_x`` driven by
            ``p_st,y`` (``dL_x/dt = -m g p_y``).
        g_mps2: gravity magnitude, m/s^2.
        process_var_rate: ``q``, (kg m^2/s)^2 / s (module doc).
        measurement_var: ``r``, (kg m^2/s)^2 (module doc).
        L0_Nms: initial estimate, kg m^2/s.
        var0: initial estimate variance, (kg m^2/s)^2.
    """

    __slots__ = ("_mg", "_q", "_r", "L", "P")

    def __init__(
        self,
        mass_kg: float,
        sign: float = 1.0,
        g_mps2: float = GRAVITY_MPS2,
        process_var_rate: float = DEFAULT_PROCESS_VAR_RATE,
        measurement_var: float = DEFAULT_MEASUREMENT_VAR,
        L0_Nms: float = 0.0,
        var0: float = 1.0,
    ):
        C.positive("mass_kg", mass_kg, "kg")
        C.positive("g_mps2", g_mps2, "m/s^2")
        if sign not in (1.0, -1.0):
            raise InputError(f"sign must be +1.0 (sagittal L_y) or -1.0 (lateral L_x), got {sign!r}")
        C.positive("process_var_rate", process_var_rate, "(kg m^2/s)^2/s")
        C.positive("measurement_var", measurement_var, "(kg m^2/s)^2")
        C.finite("L0_Nms", L0_Nms)
        C.non_negative("var0", var0, "(kg m^2/s)^2")
        self._mg = float(sign) * float(mass_kg) * float(g_mps2)
        self._q = float(process_var_rate)
        self._r = float(measurement_var)
        #: Current estimate of L, kg m^2/s.
        self.L = float(L0_Nms)
        #: Current estimate variance, (kg m^2/s)^2.
        self.P = float(var0)

    @property
    def process_var_rate(self) -> float:
        """Process noise rate ``q`` of ``L``, (kg m^2/s)^2 per s."""
        return self._q

    @property
    def measurement_var(self) -> float:
        """Measurement noise variance ``r`` of ``L``, (kg m^2/s)^2."""
        return self._r

    def reset(self, L_Nms: float, var: float | None = None) -> None:
        """Set the estimate to ``L_Nms`` (kg m^2/s), and its variance to ``var`` if given.

        Call at touchdown with the momentum about the new contact.
        """
        if not _finite(L_Nms) or (var is not None and not (_finite(var) and var >= 0.0)):
            raise InputError(f"reset needs a finite L_Nms and a finite var >= 0, got L_Nms={L_Nms!r}, var={var!r}")
        self.L = float(L_Nms)
        if var is not None:
            self.P = float(var)

    def predict(self, p_m: float, dT_s: float) -> float:
        """Propagate over ``dT_s`` seconds with the CoM offset ``p_m`` (m) from the
        stance contact along the driving axis; returns the predicted L (kg m^2/s)."""
        if not (_finite(p_m) and _finite(dT_s) and dT_s > 0.0):
            raise InputError(f"predict needs a finite p_m and a finite dT_s > 0 s, got p_m={p_m!r}, dT_s={dT_s!r}")
        self.L += self._mg * p_m * dT_s
        self.P += self._q * dT_s
        return self.L

    def correct(self, L_meas_Nms: float) -> float:
        """Fuse a measurement ``L_meas_Nms`` (kg m^2/s); returns the filtered L (kg m^2/s)."""
        if not _finite(L_meas_Nms):
            raise InputError(f"L_meas_Nms must be finite, got {L_meas_Nms!r}; skip correct() for a missing measurement")
        k = self.P / (self.P + self._r)
        self.L += k * (L_meas_Nms - self.L)
        self.P *= 1.0 - k
        return self.L

    def step(self, p_m: float, L_meas_Nms: float, dT_s: float) -> float:
        """One control tick: :meth:`predict` with ``p_m`` over ``dT_s``, then :meth:`correct`.

        Returns the filtered L (kg m^2/s). The arithmetic is that of the two
        methods, inlined (the 2 kHz hot path); bad inputs go through them for
        their exact errors and state changes.
        """
        if not (_finite(p_m) and _finite(dT_s) and _finite(L_meas_Nms) and dT_s > 0.0):
            self.predict(p_m, dT_s)
            return self.correct(L_meas_Nms)
        return self._advance(p_m, L_meas_Nms, dT_s)

    def _advance(self, p_m: float, L_meas_Nms: float, dT_s: float) -> float:
        """:meth:`step`'s arithmetic on checked inputs (finite, ``dT_s > 0``)."""
        L = self.L + self._mg * p_m * dT_s
        P = self.P + self._q * dT_s
        k = P / (P + self._r)
        L += k * (L_meas_Nms - L)
        self.L = L
        self.P = P * (1.0 - k)
        return L


class AngularMomentumFilter:
    """The two per-plane filters: ``L_y`` driven by ``p_st,x`` and ``L_x`` driven by ``p_st,y``.

    Args as :class:`MomentumFilter1D` (without ``sign``); ``L0_Nms`` is the
    initial ``(L_x, L_y)`` in world axes, kg m^2/s.
    """

    __slots__ = ("x", "y")

    def __init__(
        self,
        mass_kg: float,
        g_mps2: float = GRAVITY_MPS2,
        process_var_rate: float = DEFAULT_PROCESS_VAR_RATE,
        measurement_var: float = DEFAULT_MEASUREMENT_VAR,
        L0_Nms: tuple[float, float] = (0.0, 0.0),
        var0: float = 1.0,
    ):
        #: Filter on L_x (lateral plane).
        L0_vec_Nms = C.vector("L0_Nms", L0_Nms, 2)
        self.x = MomentumFilter1D(mass_kg, -1.0, g_mps2, process_var_rate, measurement_var, L0_vec_Nms[0], var0)
        #: Filter on L_y (sagittal plane).
        self.y = MomentumFilter1D(mass_kg, 1.0, g_mps2, process_var_rate, measurement_var, L0_vec_Nms[1], var0)

    def reset(self, L_x_Nms: float, L_y_Nms: float, var: float | None = None) -> None:
        """Set both estimates (kg m^2/s, world axes), e.g. to the momentum about a new contact."""
        self.x.reset(L_x_Nms, var)
        self.y.reset(L_y_Nms, var)

    def step(self, p_st_x_m: float, p_st_y_m: float, L_x_meas_Nms: float, L_y_meas_Nms: float, dT_s: float):
        """One control tick on both planes; returns the filtered ``(L_x, L_y)`` (kg m^2/s, world axes).

        ``p_st_x_m``, ``p_st_y_m``: CoM minus stance contact (m, world axes);
        ``L_*_meas_Nms``: measured momentum about the stance contact; ``dT_s``: tick (s).
        """
        # The per-tick path: five Python floats with a finite sum are five finite numbers (NaN and inf propagate).
        if (
            type(p_st_x_m) is float and type(p_st_y_m) is float and type(L_x_meas_Nms) is float
            and type(L_y_meas_Nms) is float and type(dT_s) is float and dT_s > 0.0
            and math.isfinite(p_st_x_m + p_st_y_m + L_x_meas_Nms + L_y_meas_Nms + dT_s)
        ):  # fmt: skip
            return self.x._advance(p_st_y_m, L_x_meas_Nms, dT_s), self.y._advance(p_st_x_m, L_y_meas_Nms, dT_s)
        args = (p_st_x_m, p_st_y_m, L_x_meas_Nms, L_y_meas_Nms, dT_s)
        if not (all(_finite(a) for a in args) and dT_s > 0.0):
            # Check both planes before stepping either (no half-updated state).
            raise InputError(
                "AngularMomentumFilter.step: p_st_m and L_meas_Nms must be finite numbers and dT_s > 0 s, got "
                f"p_st=({p_st_x_m!r}, {p_st_y_m!r}), L_meas=({L_x_meas_Nms!r}, {L_y_meas_Nms!r}), dT_s={dT_s!r}"
            )
        return self.x.step(p_st_y_m, L_x_meas_Nms, dT_s), self.y.step(p_st_x_m, L_y_meas_Nms, dT_s)

    @property
    def L_Nms(self) -> tuple[float, float]:
        """Current filtered ``(L_x, L_y)``, kg m^2/s, world axes."""
        return self.x.L, self.y.L
