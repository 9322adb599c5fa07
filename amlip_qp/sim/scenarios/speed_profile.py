"""A forward-speed command over time: piecewise linear between knots, held before the first and after the last."""

from __future__ import annotations

from bisect import bisect_right
from dataclasses import dataclass, field

import numpy as np

from amlip_qp.exceptions import InputError


@dataclass(frozen=True)
class SpeedProfile:
    """Piecewise-linear forward speed over time, held constant after the last knot.

    Attributes:
        times_s: Knot times, s (strictly increasing, first >= 0).
        speeds_mps: Speeds at the knots, m/s.
    """

    times_s: tuple[float, ...]
    speeds_mps: tuple[float, ...]
    #: The knots as tuples of floats, made once in ``__post_init__`` (``__call__`` runs every control tick).
    _knots: tuple[tuple[float, ...], tuple[float, ...]] = field(init=False, repr=False, compare=False)

    def __post_init__(self):
        t = np.asarray(self.times_s, dtype=float)
        v = np.asarray(self.speeds_mps, dtype=float)
        if t.size == 0 or t.shape != v.shape:
            raise InputError("a speed profile needs as many times as speeds, at least one knot")
        if not (np.all(np.isfinite(t)) and np.all(np.isfinite(v))):
            raise InputError("speed profile times and speeds must be finite numbers")
        if t[0] < 0 or np.any(np.diff(t) <= 0):
            raise InputError(f"speed profile times must start at >= 0 s and increase strictly, got {t.tolist()}")
        object.__setattr__(self, "_knots", (tuple(t.tolist()), tuple(v.tolist())))

    @classmethod
    def parse(cls, text: str) -> SpeedProfile:
        """Parse ``"t0:v0,t1:v1,..."`` (s:m/s), e.g. ``"0:0,5:2.1"``."""
        try:
            pairs = [item.split(":") for item in text.split(",") if item.strip()]
            times = tuple(float(a) for a, _ in pairs)
            speeds = tuple(float(b) for _, b in pairs)
        except ValueError:
            raise InputError(f"speed profile must look like '0:0,5:2.1' (time_s:speed_mps,...), got {text!r}") from None
        return cls(times, speeds)

    @classmethod
    def constant(cls, speed_mps: float) -> SpeedProfile:
        """A constant speed."""
        return cls((0.0,), (float(speed_mps),))

    def __call__(self, t_s: float) -> float:
        """Speed at time ``t_s``, m/s: ``np.interp(t_s, times_s, speeds_mps)`` bit for bit (tested).

        In plain Python (it runs every control tick): NumPy's search and its arithmetic,
        ``slope * (t - t_j) + v_j``, in the same order.
        """
        times, speeds = self._knots
        if t_s >= times[-1]:  # held after the last knot (and at it)
            return speeds[-1]
        if t_s < times[0] or len(times) == 1:
            return speeds[0]
        if t_s != t_s:  # NaN
            return t_s
        j = bisect_right(times, t_s) - 1
        t_j, v_j = times[j], speeds[j]
        if t_j == t_s:
            return v_j
        slope = (speeds[j + 1] - v_j) / (times[j + 1] - t_j)
        v = slope * (t_s - t_j) + v_j
        if v != v:  # NaN one way (overflow): np.interp tries the other
            v = slope * (t_s - times[j + 1]) + speeds[j + 1]
            if v != v and v_j == speeds[j + 1]:
                v = v_j
        return v

    @property
    def final_mps(self) -> float:
        """The speed held after the last knot, m/s."""
        return float(self.speeds_mps[-1])
