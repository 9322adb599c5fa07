"""A blind estimate of the local ground from the last footholds (pure numpy).

Without terrain perception the only ground a walking robot knows is where its
feet touched down. :class:`FootholdPlane` keeps the last ``capacity``
footholds (world ``x, y, z`` of the stance contact at each touchdown, m) and
fits the local ground plane ``z = a + g_u u + g_w w`` by least squares in the
heading frame (``u`` along the heading, ``w`` to its left). From the plane it
gives the ground's pitch and roll along the heading and its rise to a target
point, from which the walking controller's ground predictor
(:mod:`amlip_qp.control.walking.ground`, blind mode) makes the planner's
:class:`~amlip_qp.messages.TerrainPrediction` (docs/ALIP_SLOPES.md):

    plane = FootholdPlane()
    plane.add(stance_contact_world_m, heading_rad)   # at every touchdown
    ground = plane.plane(heading_rad)
    dz_m = ground.rise_m(*(target_xy_world_m - stance_contact_world_m[:2]), heading_rad)

Guards against nonsense:

- fewer than two footholds give flat ground, two give the pitch along the
  heading only, and footholds that do not spread by at least
  ``min_spread_m`` along a direction, give no slope along it (flat: a robot
  walking in place learns no pitch, a robot walking straight with its feet in
  one line learns no roll);
- the slope is capped at ``max_slope_rad`` (the gradient is scaled down);
- a heading change larger than ``reset_turn_rad`` since the oldest kept
  foothold forgets all but the newest (the old footholds describe ground
  behind a corner).

Conventions (those of :class:`~amlip_qp.messages.TerrainPrediction`):
pitch is the ground's rotation about the heading frame's y axis, positive =
descending ahead (an uphill slope of ``a`` has pitch ``-a``); roll is its
rotation about the heading's x axis, positive = rising to the left.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass

import numpy as np

from amlip_qp.alip import _checks as C
from amlip_qp.exceptions import InputError


@dataclass(frozen=True)
class GroundPlane:
    """The fitted ground in a heading frame.

    Attributes:
        grade_along: ``dz/du``, the ground's rise per metre along the heading (m/m).
        grade_left: ``dz/dw``, its rise per metre to the left of the heading (m/m).
        pitch_rad: ``-atan(grade_along)`` (positive = descending ahead).
        roll_rad: ``atan(grade_left)`` (positive = rising to the left).
        n_footholds: how many footholds the fit used.
    """

    grade_along: float
    grade_left: float
    pitch_rad: float
    roll_rad: float
    n_footholds: int

    def rise_m(self, dx_m: float, dy_m: float, heading_rad: float) -> float:
        """The plane's rise (m) over the world horizontal offset ``(dx_m, dy_m)`` (m), with the
        grades taken in the heading frame ``heading_rad`` (rad; the one the plane was fitted in)."""
        c, s = math.cos(heading_rad), math.sin(heading_rad)
        return self.grade_along * (c * dx_m + s * dy_m) + self.grade_left * (-s * dx_m + c * dy_m)


def _wrap(angle_rad: float) -> float:
    """An angle in (-pi, pi], rad."""
    return math.atan2(math.sin(angle_rad), math.cos(angle_rad))


class FootholdPlane:
    """The last footholds and the ground plane they span (module doc).

    Args:
        capacity: how many footholds to keep (>= 2).
        max_slope_rad: largest slope the estimate reports, rad (0 < max < pi/2).
        reset_turn_rad: a heading change (rad, > 0) since the oldest kept foothold
            that forgets all but the newest.
        min_spread_m: smallest spread (m, > 0) of the footholds along a direction
            (their largest minus smallest coordinate) to fit a slope along it.
    """

    def __init__(
        self,
        capacity: int = 4,
        max_slope_rad: float = math.radians(30.0),
        reset_turn_rad: float = math.radians(45.0),
        min_spread_m: float = 0.05,
    ):
        if isinstance(capacity, bool) or not isinstance(capacity, int) or capacity < 2:
            raise InputError(f"capacity must be an integer >= 2 (footholds to keep), got {capacity!r}")
        C.positive("max_slope_rad", max_slope_rad, "rad")
        if not max_slope_rad < 0.5 * math.pi:
            raise InputError(f"max_slope_rad must be < pi/2 rad, got {max_slope_rad!r}")
        C.positive("reset_turn_rad", reset_turn_rad, "rad")
        C.positive("min_spread_m", min_spread_m, "m")
        self.capacity = capacity
        self.max_slope_rad = float(max_slope_rad)
        self.reset_turn_rad = float(reset_turn_rad)
        self.min_spread_m = float(min_spread_m)
        self._points: deque[np.ndarray] = deque(maxlen=capacity)
        self._headings: deque[float] = deque(maxlen=capacity)

    def reset(self) -> None:
        """Forget every foothold (a new walk)."""
        self._points.clear()
        self._headings.clear()

    @property
    def footholds_world_m(self) -> np.ndarray:
        """The kept footholds, oldest first, world xyz, m: shape ``(n, 3)`` (a copy)."""
        return np.array(self._points).reshape(-1, 3)

    def add(self, foothold_world_m, heading_rad: float) -> None:
        """Record a touchdown: the new stance contact (world xyz, m) and the step's heading (rad)."""
        p = C.vector("foothold_world_m", foothold_world_m, 3)
        C.finite("heading_rad", heading_rad)
        if self._headings and abs(_wrap(heading_rad - self._headings[0])) > self.reset_turn_rad:
            self.reset()
        self._points.append(p)
        self._headings.append(float(heading_rad))

    def plane(self, heading_rad: float) -> GroundPlane:
        """Fit the ground plane to the kept footholds, in the heading frame ``heading_rad`` (rad)."""
        C.finite("heading_rad", heading_rad)
        n = len(self._points)
        if n < 2:
            return GroundPlane(0.0, 0.0, 0.0, 0.0, n)
        P = np.array(self._points)
        c, s = math.cos(heading_rad), math.sin(heading_rad)
        d = P - P[-1]
        u = c * d[:, 0] + s * d[:, 1]
        w = -s * d[:, 0] + c * d[:, 1]
        cols = [np.ones(n)]
        # Two footholds fit the pitch along the heading only (three unknowns need three points).
        use = [np.ptp(u) >= self.min_spread_m, n >= 3 and np.ptp(w) >= self.min_spread_m]
        cols += [x for x, ok in zip((u, w), use) if ok]
        grades = [0.0, 0.0]
        if len(cols) > 1:
            sol = np.linalg.lstsq(np.column_stack(cols), d[:, 2], rcond=None)[0]
            fitted = iter(sol[1:].tolist())
            grades = [next(fitted) if ok else 0.0 for ok in use]
        ga, gl = grades
        norm = math.hypot(ga, gl)
        cap = math.tan(self.max_slope_rad)
        if norm > cap:
            ga, gl = ga * cap / norm, gl * cap / norm
        return GroundPlane(ga, gl, -math.atan(ga), math.atan(gl), n)
