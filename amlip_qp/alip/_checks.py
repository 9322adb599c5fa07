"""Small input checks shared by the validated numpy API of :mod:`amlip_qp.alip`.

Each check raises :class:`amlip_qp.exceptions.InputError` with a message that
names the argument, shows the bad value and says what to pass instead.
"""

from __future__ import annotations

import math

import numpy as np

from amlip_qp.exceptions import InputError


def finite(name: str, value) -> None:
    """Raise InputError unless every entry of ``value`` is finite (no NaN, no inf)."""
    if isinstance(value, (float, int)):
        if math.isfinite(value):
            return
    else:
        try:
            arr = np.asarray(value, dtype=float)
        except (TypeError, ValueError):
            raise InputError(f"{name} must be a real number or array of them, got {value!r}") from None
        if np.all(np.isfinite(arr)):
            return
    raise InputError(f"{name} must be finite (no NaN or inf), got {value!r}; pass a finite value")


def positive(name: str, value, unit: str) -> None:
    """Raise InputError unless ``value`` is finite and > 0 (every entry, if an array)."""
    finite(name, value)
    if not np.all(np.asarray(value, dtype=float) > 0.0):
        raise InputError(f"{name} must be > 0 {unit}, got {value!r}; pass a strictly positive value")


def non_negative(name: str, value, unit: str) -> None:
    """Raise InputError unless ``value`` is finite and >= 0 (every entry, if an array)."""
    finite(name, value)
    if not np.all(np.asarray(value, dtype=float) >= 0.0):
        raise InputError(f"{name} must be >= 0 {unit}, got {value!r}; pass a non-negative value")


def vector(name: str, value, length: int) -> np.ndarray:
    """Return ``value`` as a finite float array of shape ``(length,)`` or raise InputError."""
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError) as exc:
        raise InputError(f"{name} must be a sequence of {length} numbers, got {value!r}") from exc
    if arr.shape != (length,):
        raise InputError(f"{name} must have shape ({length},), got shape {arr.shape}; pass {length} numbers")
    finite(name, arr)
    return arr


def side(name: str, value) -> str:
    """Return ``value`` if it is ``"left"`` or ``"right"``, else raise InputError."""
    if value not in ("left", "right"):
        raise InputError(f"{name} must be 'left' or 'right', got {value!r}")
    return value


def placed_foothold(foothold, x: float, y: float, heading_rad: float, s: float) -> tuple[float, float]:
    """``foothold(x, y, heading_rad, s)`` checked: two finite numbers (m), else :class:`InputError`."""
    if not callable(foothold):
        raise InputError(f"foothold must be a function (x_m, y_m, heading_rad, s) -> (x_m, y_m), got {foothold!r}")
    try:
        fx, fy = (float(v) for v in foothold(x, y, heading_rad, s))
    except (TypeError, ValueError) as exc:
        raise InputError(f"the foothold function must return two numbers (x_m, y_m): {exc}") from None
    if not math.isfinite(fx + fy):
        raise InputError(f"the foothold function returned a non-finite foothold ({fx!r}, {fy!r}) for ({x!r}, {y!r})")
    return fx, fy
