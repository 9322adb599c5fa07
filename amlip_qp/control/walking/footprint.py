"""Terrain-aware foothold selection: the swing foot's footprint on one tread.

On stairs the ALIP placement law knows nothing of edges: a target a few
centimetres short of a riser puts the toe against it (the foot lands on the
edge or stubs its toe when it lifts off again), one just past an edge hangs
the heel over it. :class:`FootholdSelector` moves such a target along the
heading to the nearest spot where the whole footprint (toe to heel plus a
margin) lies between two height discontinuities of the terrain's height
function; the planner places the foot there and its next step corrects the
ALIP state for the moved foothold (the deadbeat law starts from the measured
state).

Edges are found by sampling the height function along the heading at
:data:`SAMPLE_STEP_M` spacing, on a world grid of that spacing (the samples
are cached, so a target that moves a little from tick to tick reuses them):
an edge is a jump of more than :data:`EDGE_RISE_M` between two neighbours, a
grade of about 63 degrees. Slopes (below 30 degrees) and waves have none, so
there the selector returns the target unchanged (the same floats). Where the
raw target's nearest two candidates are about equally near, the one chosen at
the last tick wins by :data:`HYSTERESIS_M`: the target does not flicker between
two treads.

Used by the terrain-aware ground mode only
(:class:`~amlip_qp.control.walking.ground.GroundPredictor`); the flat and blind
modes never run it.
"""

from __future__ import annotations

import math
from collections.abc import Callable

from amlip_qp.exceptions import InputError

#: Spacing of the height samples along the heading (and of their world grid), m.
SAMPLE_STEP_M = 0.01
#: A height jump between neighbouring samples larger than this is an edge, m.
EDGE_RISE_M = 0.02
#: How far ahead of and behind the raw target the selector looks for a spot, m.
SEARCH_M = 0.3
#: Clearance from a riser that rises beside the footprint (ahead of the toe or
#: behind the heel), m: landing error and the swing's toe path. Where the ground
#: drops beside the footprint the blade only has to stay on the tread.
EDGE_MARGIN_M = 0.03
#: The candidate chosen at the last tick wins unless another is nearer by this much, m.
HYSTERESIS_M = 0.05
#: A stretch of ground within this of the last foothold is that foothold's, m.
SAME_SPOT_M = 0.01
#: From this phase of the swing on, the foothold stays on the stretch of ground chosen before.
LOCK_PHASE = 0.5
#: Samples kept before the cache is cleared.
MAX_CACHED = 20000


class FootholdSelector:
    """Moves a swing target so that the footprint lies on one tread (module doc).

    Args:
        height_fn: world ``(x, y)`` m -> ground height m (finite; the caller replaces holes).
        front_m, back_m: the footprint from the contact point along the heading, m (>= 0; the robot's
            own: :func:`~amlip_qp.robots.foot_extent.foot_extent_m`; 0 and 0: a point foot).
        margin_m: clearance from a rising edge (a riser wall) to the footprint, m (>= 0).
    """

    def __init__(
        self,
        height_fn: Callable[[float, float], float],
        front_m: float = 0.0,
        back_m: float = 0.0,
        margin_m: float = EDGE_MARGIN_M,
    ):
        if not callable(height_fn):
            raise InputError(f"height_fn must be callable (x_m, y_m) -> z_m, got {height_fn!r}")
        for name, v in (("front_m", front_m), ("back_m", back_m), ("margin_m", margin_m)):
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not (math.isfinite(v) and v >= 0.0):
                raise InputError(f"{name} must be a finite length >= 0 m, got {v!r}")
        self.height_fn = height_fn
        self.front_m = float(front_m)
        self.back_m = float(back_m)
        self.margin_m = float(margin_m)
        self._cache: dict[tuple[int, int], float] = {}
        self._last: tuple[float, float] | None = None

    def reset(self) -> None:
        """Forget the samples and the last choice (a new run: the same choices as a new selector's)."""
        self._cache.clear()
        self._last = None

    def new_step(self) -> None:
        """A touchdown: the next target is chosen afresh (no hysteresis towards the last step's)."""
        self._last = None
        if len(self._cache) > MAX_CACHED:
            self._cache.clear()

    def _sample(self, ix: int, iy: int) -> float:
        key = (ix, iy)
        z = self._cache.get(key)
        if z is None:
            z = float(self.height_fn((ix + 0.5) * SAMPLE_STEP_M, (iy + 0.5) * SAMPLE_STEP_M))
            self._cache[key] = z
        return z

    def edges(self, x_m: float, y_m: float, heading_rad: float, lo_m: float, hi_m: float) -> list[tuple[float, float]]:
        """Edges along the heading through ``(x_m, y_m)`` between offsets ``lo_m`` and ``hi_m`` (m):
        ``(offset m, rise m)`` each, the rise positive where the ground steps up along the heading."""
        c, s = math.cos(heading_rad), math.sin(heading_rad)
        step = SAMPLE_STEP_M
        ts: list[float] = []
        zs: list[float] = []
        for k in range(math.floor(lo_m / step), math.ceil(hi_m / step) + 1):
            # grid points half a step off the round coordinates, where boxes of terrain meet
            ix, iy = math.floor((x_m + k * step * c) / step), math.floor((y_m + k * step * s) / step)
            ts.append(((ix + 0.5) * step - x_m) * c + ((iy + 0.5) * step - y_m) * s)
            zs.append(self._sample(ix, iy))
        for k in range(1, len(zs) - 1):  # a notch or spike one sample wide is a glitch of the ray, not ground
            a, b = zs[k - 1], zs[k + 1]
            if not min(a, b) - EDGE_RISE_M <= zs[k] <= max(a, b) + EDGE_RISE_M:
                zs[k] = a
        out: list[tuple[float, float]] = []
        for k in range(1, len(zs)):
            if abs(zs[k] - zs[k - 1]) > EDGE_RISE_M:
                out.append((0.5 * (ts[k] + ts[k - 1]), zs[k] - zs[k - 1]))
        return out

    def zones(self, edges: list[tuple[float, float]]) -> list[tuple[float, float]]:
        """Where the footprint clears ``edges`` (``(offset m, rise m)``, in order): ``(lo, hi)`` offsets, m."""
        out: list[tuple[float, float]] = []
        lo = -math.inf
        for e, rise in edges:
            hi = e - self.front_m - (self.margin_m if rise > 0.0 else 0.0)
            if lo <= hi:
                out.append((lo, hi))
            lo = max(lo, e + self.back_m + (0.0 if rise > 0.0 else self.margin_m))
        out.append((lo, math.inf))
        return out

    @property
    def reach_m(self) -> float:
        """How far ahead of and behind a point the selector reads the terrain for it, m."""
        return SEARCH_M + self.front_m + self.back_m + self.margin_m

    def region(self, x_m: float, y_m: float, heading_rad: float) -> tuple[float, float]:
        """The stretch of ground along the heading (offsets ``(lo, hi)`` from ``(x_m, y_m)``, m) where the
        footprint fits nearest to that point: the one holding it, else the nearest; its ends are within the
        search reach (``SEARCH_M`` plus the footprint), ``+-`` that reach where no edge is nearer."""
        reach = self.reach_m
        zones = self.zones(self.edges(x_m, y_m, heading_rad, -reach, reach))
        lo, hi = min(zones, key=lambda z: z[0] if z[0] > 0.0 else (-z[1] if z[1] < 0.0 else 0.0))
        return max(lo, -reach), min(hi, reach)

    def place(self, x_m: float, y_m: float, heading_rad: float, phase: float = 0.0) -> tuple[float, float]:
        """The foothold for the raw target ``(x_m, y_m)`` (world, m) of a step along ``heading_rad`` (rad) at
        ``phase`` of the swing: the raw target moved along the heading into the nearest stretch of ground where
        the footprint fits (module doc); the same floats back where it fits already. From :data:`LOCK_PHASE` on,
        the stretch of the last tick's foothold is kept.
        """
        reach = SEARCH_M + self.front_m + self.back_m + self.margin_m
        zones = self.zones(self.edges(x_m, y_m, heading_rad, -reach, reach))
        c, s = math.cos(heading_rad), math.sin(heading_rad)
        last = self._last
        u_last = math.nan if last is None else c * (last[0] - x_m) + s * (last[1] - y_m)
        best, best_cost = (0.0, 0.0), math.inf
        for lo, hi in zones:
            gap = lo if lo > 0.0 else (-hi if hi < 0.0 else 0.0)
            mine = lo - SAME_SPOT_M <= u_last <= hi + SAME_SPOT_M
            cost = gap
            if mine:
                cost = -math.inf if phase >= LOCK_PHASE else gap - HYSTERESIS_M
            if cost < best_cost:
                best, best_cost = (lo, hi), cost
        lo, hi = best
        if lo <= 0.0 <= hi:
            self._last = (x_m, y_m)
            return x_m, y_m
        u = lo if lo > 0.0 else hi
        self._last = (x_m + u * c, y_m + u * s)
        return self._last
