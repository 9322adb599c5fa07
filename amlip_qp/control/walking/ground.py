"""The ground the walking controller plans each step for: flat, blind (felt footholds) or terrain-aware.

The planner takes the ground as a :class:`~amlip_qp.messages.TerrainPrediction`
(heights relative to the stance contact, pitches along the heading;
docs/ALIP_SLOPES.md). A :class:`GroundPredictor` makes one every tick, in one of
the modes of :data:`GROUND_MODES`:

- ``"flat"``: none (the planner's flat-ground numbers, bit for bit: the
  controller of flat ground, unchanged);
- ``"blind"``: no terrain perception, as on the Wave Field: the ground is
  felt only where the feet touched down. A plane through the last footholds
  (:class:`~amlip_qp.alip.footholds.FootholdPlane`, fitted at each touchdown)
  gives the height of the next contact and the ground pitch;
- ``"aware"``: the controller is handed a height function of the terrain,
  world ``(x, y)`` m -> ground ``z`` m (in simulation, ray casts into the
  plant's scene; the controller never sees the simulator), read at the swing
  target (height, and pitch: the gentler of the grades half a blade behind and
  ahead along the heading, so that a stair's edge reads as its tread) and under
  the stance contact. The planner's swing target is moved off the terrain's
  edges, so that the foot's footprint lies on one tread
  (:class:`~amlip_qp.control.walking.footprint.FootholdSelector`, the hook
  :meth:`GroundPredictor.foothold`), and a step over an edge gets its rise (up
  or down) as extra swing clearance (:meth:`GroundPredictor.fit`). On smooth
  ground (slopes, waves) both change nothing.

In both terrain modes the height where the swing foot lifted off is the
previous stance contact's, as measured (blind) or read (aware). The
predictions are clipped to what the references accept (:data:`MAX_DZ_M`,
:data:`MAX_PITCH_RAD`): a step or a glitch of the estimate must not stop
the walk with an error.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import replace

import numpy as np

from amlip_qp.alip.footholds import FootholdPlane, GroundPlane
from amlip_qp.control.walking.footprint import EDGE_RISE_M, FootholdSelector
from amlip_qp.exceptions import InputError
from amlip_qp.messages import Command, TerrainPrediction

#: The ground modes of :class:`GroundPredictor` (module doc).
GROUND_MODES: tuple[str, ...] = ("flat", "blind", "aware")

#: Largest height difference a prediction may have (either sign), m: about a
#: third of Cassie's CoM height, so that the swing path stays below the CoM.
MAX_DZ_M = 0.25
#: Largest ground pitch a prediction may have (either sign), rad (30 degrees).
MAX_PITCH_RAD = math.radians(30.0)
#: How far behind and ahead of a point (m, along the heading) an ``"aware"``
#: prediction reads the ground's grades for its pitch (about half a foot blade).
PITCH_HALF_BASE_M = 0.05

#: The swing foot's apex stays at least this far below the CoM, m, when
#: :func:`fit_clearance` lowers a clearance that would lift it too high.
APEX_MARGIN_M = 0.05

#: The MPC's foothold regions (:meth:`GroundPredictor.regions`) are made for headings within this of a
#: world axis, rad (a box of world axes along a stretch of the heading).
REGION_MAX_ANGLE_RAD = math.radians(30.0)
#: A region's half size across the heading (unbounded), m.
REGION_OPEN_M = 1000.0
#: Regions kept for reuse (a foothold on a stretch found before gets its region without sampling the terrain).
MAX_CACHED_REGIONS = 16
#: A region with an end where no edge is within the search reach (the end is the reach's, which moves with the
#: foothold) is reused for a foothold at most this far (m, along the heading's axis) from where it was found.
REGION_REUSE_M = 0.05

HeightFunction = Callable[[float, float], float]
FootholdPlacement = Callable[[float, float, float, float], tuple[float, float]]


def fit_clearance(prediction: TerrainPrediction, command: Command) -> Command:
    """``command``, or a copy with a smaller clearance if the swing path over ``prediction`` would reach the CoM.

    The swing foot's apex over the stance contact is at most
    ``max(dz0, dz1) + z_cl + |dz1 - dz0| / 8`` and the references need it below
    the CoM at ``H + min(dz0, 0)`` (:func:`amlip_qp.alip.outputs.check_ground`).
    A large ``--clearance`` over a large step would otherwise stop the walk with
    an error mid-run; here that step's clearance is lowered instead, to keep the
    apex :data:`APEX_MARGIN_M` below the CoM (never below 0 m). The same object
    comes back when the clearance fits (every run of the named scenarios).
    """
    dz0, dz1 = prediction.dz_sw0_m, prediction.dz_sw_m
    room = command.com_height_m + min(dz0, 0.0) - max(dz0, dz1) - 0.125 * abs(dz1 - dz0) - APEX_MARGIN_M
    if command.clearance_m <= room:
        return command
    return replace(command, clearance_m=max(room, 0.0))


def _clip(value: float, limit: float) -> float:
    return limit if value > limit else -limit if value < -limit else value


class GroundPredictor:
    """Makes the planner's :class:`TerrainPrediction` (module doc).

    Args:
        mode: One of :data:`GROUND_MODES`.
        height_fn: World ``(x, y)`` m -> ground height m; required by ``"aware"``, refused otherwise.
        foot_extent_m: ``(front, back)``: the foot from its contact point along the heading, m, that
            ``"aware"`` fits on one tread (the robot's own:
            :func:`~amlip_qp.robots.foot_extent.foot_extent_m`; ``(0, 0)``: a point foot).
    """

    def __init__(
        self,
        mode: str = "flat",
        height_fn: HeightFunction | None = None,
        foot_extent_m: tuple[float, float] = (0.0, 0.0),
    ):
        if mode not in GROUND_MODES:
            raise InputError(f"ground mode must be one of {', '.join(GROUND_MODES)}, got {mode!r}")
        if (mode == "aware") != (height_fn is not None):
            raise InputError(
                "the 'aware' ground mode needs a terrain height function and the other modes take none; "
                f"got mode {mode!r} with height_fn={height_fn!r}"
            )
        if height_fn is not None and not callable(height_fn):
            raise InputError(f"height_fn must be callable (x_m, y_m) -> z_m, got {height_fn!r}")
        self.mode = mode
        self.height_fn = height_fn
        #: The footholds (blind mode) and the plane fitted to them at the last touchdown.
        self.footholds = FootholdPlane(max_slope_rad=MAX_PITCH_RAD)
        self._plane = GroundPlane(0.0, 0.0, 0.0, 0.0, 0)
        self._heading = 0.0
        self._stance_xy = (math.nan, math.nan)  # the stance contact, world m
        self._liftoff_xy = (math.nan, math.nan)  # the previous stance contact, world m
        #: The rise of the step being planned over an edge between lift-off and target, m ("aware"; else 0).
        self.edge_rise_m = 0.0
        self._stance_z = math.nan  # ground under it (aware) or its foothold (blind), m
        self._liftoff_dz = 0.0  # ground where the swing foot lifted off minus the stance's, m
        #: Ground pitch under the stance foot along the heading, rad (positive = descending ahead).
        self.stance_pitch_rad = 0.0
        self._liftoff_pitch = 0.0
        #: Moves swing targets off the terrain's edges ("aware" only; None otherwise).
        front_m, back_m = foot_extent_m
        self.selector = FootholdSelector(self._height, front_m, back_m) if mode == "aware" else None
        # the MPC's regions found so far (their extent along the heading's axis, m, and the region) and their heading
        self._regions_cache: list[tuple[float, float, float, tuple[float, ...]]] = []
        self._regions_heading = math.nan

    @property
    def active(self) -> bool:
        """True unless the mode is ``"flat"`` (no prediction)."""
        return self.mode != "flat"

    def reset(self) -> None:
        """Forget the footholds (a new run)."""
        self.footholds.reset()
        self._plane = GroundPlane(0.0, 0.0, 0.0, 0.0, 0)
        self._stance_xy = (math.nan, math.nan)
        self._liftoff_xy = (math.nan, math.nan)
        self.edge_rise_m = 0.0
        self._stance_z = math.nan
        self._liftoff_dz = 0.0
        self.stance_pitch_rad = 0.0
        self._liftoff_pitch = 0.0
        if self.selector is not None:
            self.selector.reset()
        self._regions_cache.clear()
        self._regions_heading = math.nan

    def touchdown(self, stance_contact_m: np.ndarray, heading_rad: float) -> None:
        """A new stance contact (world, m) on a step of heading ``heading_rad`` (rad): a foothold."""
        x, y, z = (float(v) for v in stance_contact_m[:3])
        if self.mode == "blind":
            self.footholds.add(stance_contact_m, heading_rad)
            self._plane = self.footholds.plane(heading_rad)
        self._heading = heading_rad
        if self.selector is not None:
            self.selector.new_step()
            z = self._height(x, y)
        previous = self._stance_z
        self._liftoff_dz = 0.0 if math.isnan(previous) else _clip(previous - z, MAX_DZ_M)
        self._liftoff_pitch = self.stance_pitch_rad
        self._liftoff_xy = self._stance_xy
        self._stance_xy, self._stance_z = (x, y), z
        self.stance_pitch_rad = self._pitch_at(x, y, heading_rad)

    def foothold(self) -> FootholdPlacement | None:
        """The planner's foothold hook: world ``(x, y)``, heading, phase -> foothold ``(x, y)`` ("aware"; else None)."""
        return self.selector.place if self.selector is not None else None

    def regions(self, footholds_xy_m: np.ndarray, heading_rad: float) -> list[tuple[float, ...]] | None:
        """Foothold regions for the step-timing MPC, one per planned foothold (world ``(n, 2)``, m), in the
        ``"aware"`` mode with a heading within :data:`REGION_MAX_ANGLE_RAD` of a world axis; else ``None``.

        Each is the world box ``(x_lo, x_hi, y_lo, y_hi, z)`` (m) of the stretch of ground along the heading
        where the footprint fits nearest to the foothold (:meth:`FootholdSelector.region
        <amlip_qp.control.walking.footprint.FootholdSelector.region>`: a stair's tread less the foot and
        its margins), unbounded across the heading, with the ground's height at the stretch's middle. A
        foothold on a stretch found before between two edges (at the same heading) gets that region again
        without sampling; on a stretch with an open end only within :data:`REGION_REUSE_M` of where it was found.
        """
        if self.selector is None:
            return None
        c, s = math.cos(heading_rad), math.sin(heading_rad)
        along_x = abs(c) >= math.cos(REGION_MAX_ANGLE_RAD)
        if not (along_x or abs(s) >= math.cos(REGION_MAX_ANGLE_RAD)):
            return None
        if heading_rad != self._regions_heading:
            self._regions_cache.clear()
            self._regions_heading = heading_rad
        out: list[tuple[float, ...]] = []
        for x, y in np.asarray(footholds_xy_m, dtype=float).reshape(-1, 2).tolist():
            u = x if along_x else y
            known = next(
                (r for r in self._regions_cache if r[0] <= u <= r[1] and not abs(u - r[2]) > REGION_REUSE_M), None
            )
            if known is not None:  # the foothold is on a stretch found before, near where it was: the same region
                out.append(known[3])
                continue
            lo, hi = self.selector.region(x, y, heading_rad)
            if lo > hi:  # no stretch long enough for the foot: its middle
                lo = hi = 0.5 * (lo + hi)
            mid = 0.5 * (lo + hi)
            z = self._height(x + mid * c, y + mid * s)
            if along_x:
                a, b = sorted((x + lo * c, x + hi * c))
                region: tuple[float, ...] = (a, b, -REGION_OPEN_M, REGION_OPEN_M, z)
            else:
                a, b = sorted((y + lo * s, y + hi * s))
                region = (-REGION_OPEN_M, REGION_OPEN_M, a, b, z)
            out.append(region)
            if len(self._regions_cache) >= MAX_CACHED_REGIONS:
                self._regions_cache.pop(0)
            # between two edges the region holds for any foothold on it (u0 = NaN); an end at the reach moves
            bounded = -self.selector.reach_m < lo and hi < self.selector.reach_m
            self._regions_cache.append((a, b, math.nan if bounded else u, region))
        return out

    def fit(self, prediction: TerrainPrediction, command: Command) -> Command:
        """The command for a step over ``prediction``: over an edge up or down ("aware") the clearance is raised
        by the rise (:attr:`edge_rise_m`), so that the toe clears the edge early; then :func:`fit_clearance`."""
        if self.edge_rise_m > 0.0:
            command = replace(command, clearance_m=command.clearance_m + self.edge_rise_m)
        return fit_clearance(prediction, command)

    def _edge_rise(self, x: float, y: float, dz: float, heading_rad: float) -> float:
        """The height (m) the swing foot climbs or drops from lift-off to the target ``(x, y)`` m if an edge lies
        between them; else 0."""
        rise = abs(dz - self._liftoff_dz)
        lx, ly = self._liftoff_xy
        if not rise > EDGE_RISE_M or not math.isfinite(lx):
            return 0.0
        assert self.selector is not None
        reach = math.cos(heading_rad) * (x - lx) + math.sin(heading_rad) * (y - ly)
        return rise if self.selector.edges(lx, ly, heading_rad, min(0.0, reach), max(0.0, reach)) else 0.0

    def _height(self, x: float, y: float) -> float:
        """The height function at ``(x, y)`` m; where it has no ground (NaN), the stance's (or 0 before any)."""
        assert self.height_fn is not None
        z = float(self.height_fn(x, y))
        if math.isfinite(z):
            return z
        return self._stance_z if math.isfinite(self._stance_z) else 0.0

    def _pitch_at(self, x: float, y: float, heading_rad: float) -> float:
        """The ground pitch along the heading at world ``(x, y)`` m, rad (clipped)."""
        c, s = math.cos(heading_rad), math.sin(heading_rad)
        if self.mode == "aware":
            # The gentler of the two one-sided grades: the same on a smooth slope,
            # the tread's (level) beside a stair's edge rather than the riser's.
            d = PITCH_HALF_BASE_M
            h = self._height(x, y)
            back, front = h - self._height(x - d * c, y - d * s), self._height(x + d * c, y + d * s) - h
            rise = back if abs(back) < abs(front) else front
            return _clip(-math.atan2(rise, d), MAX_PITCH_RAD)
        return self._plane.pitch_rad

    def predict(self, target_xy_m: np.ndarray, heading_rad: float) -> TerrainPrediction:
        """The ground for the planner with the swing target at world ``target_xy_m`` (m).

        Call :meth:`touchdown` first (at the first step too); not in the ``"flat"`` mode.
        """
        x, y = float(target_xy_m[0]), float(target_xy_m[1])
        if self.mode == "aware":
            dz = self._height(x, y) - self._stance_z
        else:
            # the plane's grades (fitted at the touchdown) times the offset in the step's heading frame
            dz = self._plane.rise_m(x - self._stance_xy[0], y - self._stance_xy[1], self._heading)
        dz = _clip(dz, MAX_DZ_M)
        if self.selector is not None:
            self.edge_rise_m = self._edge_rise(x, y, dz, heading_rad)
        return TerrainPrediction(
            dz_next_m=dz,
            dz_sw_m=dz,
            dz_sw0_m=self._liftoff_dz,
            slope_pitch_rad=self._pitch_at(x, y, heading_rad),
            slope_pitch0_rad=self._liftoff_pitch,
        )
