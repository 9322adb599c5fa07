"""Height grids of the terrains that are MuJoCo height fields (``rough``, ``waves``, ``hfield``).

A :class:`HeightGrid` holds the samples MuJoCo is given and answers the
height of MuJoCo's own surface between them: a height field is a grid of
``nrow x ncol`` points (row ``r`` at ``y0 + r dy``, column ``c`` at
``x0 + c dx``), each cell split into two triangles along the diagonal from
``(c, r)`` to ``(c + 1, r + 1)``, and the data MuJoCo stores is normalised to
``[0, 1]`` in float32 (surface ``z = z0 + elevation * data``). The grid keeps
exactly those float32 samples, so :meth:`HeightGrid.height_m` is the surface
MuJoCo collides with, not a smooth function near it.
"""

from __future__ import annotations

import math
import os
import struct
import warnings
from dataclasses import dataclass

import numpy as np

from amlip_qp.exceptions import InputError

#: Grid spacing of the generated height fields (rough ground, waves), m.
GRID_SPACING_M = 0.05
#: The generated height fields span x from this far behind the robot's start, m.
BACK_M = 4.0
#: ... to this far ahead of it, m.
FRONT_M = 30.0
#: Half width (y) of the generated terrains, m.
HALF_WIDTH_M = 4.0
#: Rough ground: flat within this radius of the start, full relief beyond FLAT_PATCH_BLEND_M, m.
FLAT_PATCH_RADIUS_M = 0.75
FLAT_PATCH_BLEND_M = 1.5
#: Rough ground: wavelengths of its random plane waves, m (shortest, longest) and how many.
ROUGH_WAVELENGTHS_M = (0.6, 3.0)
ROUGH_MODES = 24
#: Most pixels of a height map (``hfield:PATH.png``): 4096 x 4096 = 16,777,216. MuJoCo keeps a height
#: field as one float32 a sample and builds it from a Python list of them: loading the Cassie plant on
#: a 4096 x 4096 map took 2.8 s and 1.0 GB of peak memory (2048 x 2048: 0.7 s, 0.37 GB); only
#: decoding a 12000 x 12000 one took 4.5 s and 2.3 GB, with Pillow's decompression-bomb warning
#: (its limit: 89.5 million pixels). 4096 columns over a 20 m map are 5 mm apart, finer than the
#: 20 mm radius of Cassie's foot contacts.
MAX_HFIELD_PIXELS = 4096 * 4096
#: The 8-byte signature of a PNG file, followed by its IHDR chunk (width, height: big-endian uint32).
_PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


@dataclass(frozen=True, eq=False)
class HeightGrid:
    """MuJoCo's height-field surface: float32 samples in ``[0, 1]`` on a regular grid.

    Attributes:
        x0_m: x of column 0, m.
        y0_m: y of row 0, m.
        dx_m: Column spacing, m.
        dy_m: Row spacing, m.
        z0_m: Height of a sample 0, m.
        elevation_m: Height of a sample 1 above a sample 0, m (> 0).
        data: (nrow, ncol) float32 samples, min 0 and max 1 (MuJoCo's normalisation leaves them).
    """

    x0_m: float
    y0_m: float
    dx_m: float
    dy_m: float
    z0_m: float
    elevation_m: float
    data: np.ndarray

    @property
    def nrow(self) -> int:
        return int(self.data.shape[0])

    @property
    def ncol(self) -> int:
        return int(self.data.shape[1])

    @property
    def half_size_m(self) -> tuple[float, float]:
        """MuJoCo's ``size[0]``, ``size[1]``: half extents in x and y, m."""
        return 0.5 * self.dx_m * (self.ncol - 1), 0.5 * self.dy_m * (self.nrow - 1)

    @property
    def centre_m(self) -> tuple[float, float]:
        """Where the height-field geom goes (x, y), m."""
        hx, hy = self.half_size_m
        return self.x0_m + hx, self.y0_m + hy

    def covers(self, x_m: float, y_m: float) -> bool:
        """Whether (x, y) lies on the grid (edges included)."""
        hx, hy = self.half_size_m
        return 0.0 <= x_m - self.x0_m <= 2.0 * hx and 0.0 <= y_m - self.y0_m <= 2.0 * hy

    def height_m(self, x_m: float, y_m: float) -> float:
        """The surface height at (x, y), m (the point must be covered, :meth:`covers`)."""
        u = (x_m - self.x0_m) / self.dx_m
        v = (y_m - self.y0_m) / self.dy_m
        c = min(max(int(math.floor(u)), 0), self.ncol - 2)
        r = min(max(int(math.floor(v)), 0), self.nrow - 2)
        fu, fv = u - c, v - r
        d = self.data
        f00, f10 = float(d[r, c]), float(d[r, c + 1])
        f01, f11 = float(d[r + 1, c]), float(d[r + 1, c + 1])
        if fu >= fv:  # the triangle (c, r), (c + 1, r), (c + 1, r + 1)
            h = f00 + fu * (f10 - f00) + fv * (f11 - f10)
        else:  # the triangle (c, r), (c + 1, r + 1), (c, r + 1)
            h = f00 + fu * (f11 - f01) + fv * (f01 - f00)
        return self.z0_m + self.elevation_m * h


def _from_heights(x0_m: float, y0_m: float, dx_m: float, dy_m: float, heights_m: np.ndarray) -> HeightGrid:
    """The grid of the heights ``heights_m`` (nrow, ncol), normalised to [0, 1] as MuJoCo stores them."""
    lo, hi = float(np.min(heights_m)), float(np.max(heights_m))
    span = hi - lo
    if span <= 0.0:  # a level map: MuJoCo needs a positive elevation
        flat = np.zeros(heights_m.shape, dtype=np.float32)
        flat.flags.writeable = False
        return HeightGrid(x0_m, y0_m, dx_m, dy_m, lo, 1e-6, flat)
    data = ((heights_m - lo) / span).astype(np.float32)
    data.flags.writeable = False
    return HeightGrid(x0_m, y0_m, dx_m, dy_m, lo, span, data)


def _axis(lo_m: float, hi_m: float, spacing_m: float) -> tuple[float, np.ndarray]:
    """Spacing (<= ``spacing_m``) and the sample positions covering [lo, hi] with both ends on the grid."""
    n = max(int(math.ceil((hi_m - lo_m) / spacing_m)), 1)
    step = (hi_m - lo_m) / n
    return step, lo_m + step * np.arange(n + 1)


def rough_grid(amplitude_m: float, seed: int) -> HeightGrid:
    """Smooth random relief, ``max |height| = amplitude_m``, flat around the start (x = y = 0).

    A sum of :data:`ROUGH_MODES` plane waves with random directions, phases and
    wavelengths in :data:`ROUGH_WAVELENGTHS_M` (amplitude proportional to the
    wavelength), from ``numpy.random.default_rng(seed)``; multiplied by a
    smoothstep that is 0 within :data:`FLAT_PATCH_RADIUS_M` of the start and 1
    beyond :data:`FLAT_PATCH_BLEND_M`; scaled so its largest magnitude on the
    grid is ``amplitude_m``.
    """
    rng = np.random.default_rng(seed)
    dx, xs = _axis(-BACK_M, FRONT_M, GRID_SPACING_M)
    dy, ys = _axis(-HALF_WIDTH_M, HALF_WIDTH_M, GRID_SPACING_M)
    X, Y = np.meshgrid(xs, ys)
    lo, hi = ROUGH_WAVELENGTHS_M
    wavelengths = 1.0 / rng.uniform(1.0 / hi, 1.0 / lo, ROUGH_MODES)
    directions = rng.uniform(0.0, 2.0 * math.pi, ROUGH_MODES)
    phases = rng.uniform(0.0, 2.0 * math.pi, ROUGH_MODES)
    field = np.zeros_like(X)
    for lam, ang, ph in zip(wavelengths, directions, phases):
        k = 2.0 * math.pi / lam
        field += lam * np.sin(k * (math.cos(ang) * X + math.sin(ang) * Y) + ph)
    s = np.clip((np.hypot(X, Y) - FLAT_PATCH_RADIUS_M) / (FLAT_PATCH_BLEND_M - FLAT_PATCH_RADIUS_M), 0.0, 1.0)
    field *= s * s * (3.0 - 2.0 * s)
    field *= amplitude_m / float(np.max(np.abs(field)))
    return _from_heights(-BACK_M, -HALF_WIDTH_M, dx, dy, field)


def waves_height_m(
    x_m: float | np.ndarray,
    y_m: float | np.ndarray,
    height_m: float,
    wavelength_m: float,
    heading_deg: float,
    start_x_m: float,
) -> float | np.ndarray:
    """The smooth wave field ``height/2 (1 - cos(2 pi u / wavelength))``, m, before it is sampled on a grid.

    ``u`` is the distance across the ridges: ``u = (x - start_x_m) cos(heading) + y sin(heading)``
    for heading 0 (ridges across the path from ``start_x_m`` on, flat before it), and
    ``u = x cos(heading) + y sin(heading)`` for any other heading (ridges everywhere, at
    ``heading`` to the path: at 90 deg they run along it). ``u = 0`` is a trough, so the
    robot's start (x = y = 0) is on a valley floor at every heading. Outside the grid of
    :func:`waves_grid` the terrain is the flat floor (0 m); this function does not clip.
    """
    c, s = math.cos(math.radians(heading_deg)), math.sin(math.radians(heading_deg))
    x0 = start_x_m if heading_deg == 0.0 else 0.0
    u = (np.asarray(x_m) - x0) * c + np.asarray(y_m) * s
    return 0.5 * height_m * (1.0 - np.cos(2.0 * math.pi * u / wavelength_m))


def waves_grid(height_m: float, wavelength_m: float, start_x_m: float, heading_deg: float = 0.0) -> HeightGrid:
    """Ridges at ``heading_deg`` to the path (0: across it), sampled from :func:`waves_height_m`.

    Heading 0: ``height/2 (1 - cos(2 pi (x - start) / wavelength))`` from ``start_x_m`` on, whole
    wavelengths up to at least :data:`FRONT_M`, troughs (0 m) at both ends, one row every 0.5 m
    (the field does not change along y). Any other heading: the field over the whole terrain
    (x from :data:`BACK_M` behind the start to :data:`FRONT_M` ahead, ``|y| <=``
    :data:`HALF_WIDTH_M`), on a :data:`GRID_SPACING_M` grid both ways; the robot starts on the
    valley floor through x = y = 0 (at 90 deg it walks along that valley).
    """
    if heading_deg == 0.0:
        n_waves = max(int(math.ceil((FRONT_M - start_x_m) / wavelength_m)), 1)
        dx, xs = _axis(start_x_m, start_x_m + n_waves * wavelength_m, GRID_SPACING_M)
        dy, ys = _axis(-HALF_WIDTH_M, HALF_WIDTH_M, 0.5)
        profile = 0.5 * height_m * (1.0 - np.cos(2.0 * math.pi * (xs - start_x_m) / wavelength_m))
        profile[0] = profile[-1] = 0.0
        return _from_heights(start_x_m, -HALF_WIDTH_M, dx, dy, np.tile(profile, (ys.size, 1)))
    dx, xs = _axis(-BACK_M, FRONT_M, GRID_SPACING_M)
    dy, ys = _axis(-HALF_WIDTH_M, HALF_WIDTH_M, GRID_SPACING_M)
    X, Y = np.meshgrid(xs, ys)
    field = np.asarray(waves_height_m(X, Y, height_m, wavelength_m, heading_deg, start_x_m))
    return _from_heights(-BACK_M, -HALF_WIDTH_M, dx, dy, field)


def _too_large(path: str, what: str) -> str:
    return (
        f"height map {path} has {what}; at most {MAX_HFIELD_PIXELS} pixels (4096 x 4096) are read: "
        "downsample it (MuJoCo holds every pixel of a height field in memory)"
    )


def image_size(path: str) -> tuple[int, int] | None:
    """``(columns, rows)`` of the image at ``path`` from its header, without decoding it; ``None`` if unknown.

    A PNG's IHDR chunk is read directly; other formats through Pillow's lazy
    ``Image.open``.

    Raises:
        InputError: Pillow refuses to open the image at all (more than twice its
            decompression-bomb limit, far above :data:`MAX_HFIELD_PIXELS`).
    """
    with open(path, "rb") as fh:
        head = fh.read(24)
    if head[:8] == _PNG_SIGNATURE and head[12:16] == b"IHDR":
        cols, rows = struct.unpack(">II", head[16:24])
        return int(cols), int(rows)
    from PIL import Image

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", Image.DecompressionBombWarning)
            with Image.open(path) as img:
                return int(img.size[0]), int(img.size[1])
    except Image.DecompressionBombError:
        raise InputError(_too_large(path, "more pixels than Pillow opens")) from None
    except Exception:  # not an image Pillow knows: the decoder below says so
        return None


def read_gray_png(path: str) -> np.ndarray:
    """The PNG at ``path`` as gray levels in [0, 1], shape (rows, cols), top row first.

    Colour images are averaged over R, G, B (alpha ignored). Its size is read
    from the header first: more than :data:`MAX_HFIELD_PIXELS` pixels are
    refused before any decoding.

    Raises:
        InputError: Missing, unreadable, smaller than 2 x 2 pixels, or larger
            than :data:`MAX_HFIELD_PIXELS` pixels.
    """
    if not os.path.isfile(path):
        raise InputError(f"height map not found: {path}; give the path of a grayscale PNG")
    size = image_size(path)
    if size is not None and size[0] * size[1] > MAX_HFIELD_PIXELS:
        raise InputError(_too_large(path, f"{size[0]} x {size[1]} pixels"))
    import imageio.v3 as iio

    try:
        img = np.asarray(iio.imread(path, plugin="pillow"))
    except Exception as exc:
        raise InputError(f"cannot read the height map {path} as an image ({type(exc).__name__}); give a PNG") from None
    if img.dtype.kind == "u":
        gray = img.astype(float) / float(np.iinfo(img.dtype).max)
    elif img.dtype.kind == "f":
        gray = np.clip(img.astype(float), 0.0, 1.0)
    else:
        raise InputError(f"height map {path} has pixels of type {img.dtype}; give an 8- or 16-bit PNG")
    if gray.ndim == 3:
        if gray.shape[-1] in (2, 4):  # gray + alpha, RGB + alpha: the alpha channel is no height
            gray = gray[..., :-1]
        gray = gray.mean(axis=2)
    if gray.ndim != 2 or min(gray.shape) < 2:
        raise InputError(f"height map {path} must be an image of at least 2 x 2 pixels, got shape {img.shape}")
    return gray


def png_grid(gray: np.ndarray, size_x_m: float, size_y_m: float, height_m: float, back_m: float) -> HeightGrid:
    """A gray map as a grid: black 0 m, white ``height_m``; ``size_x_m`` by ``size_y_m``, centred on y = 0.

    Columns run along +x from ``-back_m``, the image's top row is the +y edge.
    """
    rows, cols = gray.shape
    dx, dy = size_x_m / (cols - 1), size_y_m / (rows - 1)
    return _from_heights(-back_m, -0.5 * size_y_m, dx, dy, height_m * gray[::-1])
