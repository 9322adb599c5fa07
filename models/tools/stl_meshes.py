"""Binary STL meshes: read, write, and simplify them with a kept convex hull.

Used by ``build_unitree.py`` (not shipped with the package). The simplification is
quadric edge collapse (the ``fast-simplification`` package, needed by this tool only).

MuJoCo collides a mesh geom as the convex hull of the mesh's vertices. A mesh
whose geom collides is therefore simplified with its hull kept
(:func:`simplified`, ``keep_hull=True``): the simplified vertices that fall
outside the original hull are moved inside it, and every original hull vertex
is added back as a zero-area triangle (three times the same vertex). Zero-area
triangles draw nothing, so the rendered mesh is the simplified one, while the
vertex set has exactly the original hull (:func:`hull_vertices`).
"""

from __future__ import annotations

import numpy as np

#: One binary STL triangle: normal, three vertices (float32, little-endian), attribute word.
STL_TRIANGLE = np.dtype([("normal", "<f4", (3,)), ("vertices", "<f4", (3, 3)), ("attribute", "<u2")])
#: The 80-byte header of the STL files written here (it must not start with "solid", the ASCII STL keyword).
STL_HEADER = b"binary STL, simplified by amlip_qp models/tools/build_unitree.py".ljust(80, b" ")
#: A moved vertex ends this far inside every face plane of the original hull (m); well above float32 rounding.
HULL_MARGIN_M = 1e-6


def read_stl(data: bytes, name: str) -> tuple[np.ndarray, np.ndarray]:
    """The vertices (float32, unique, sorted) and triangles (int64 indices) of a binary STL file's bytes."""
    if len(data) < 84:
        raise ValueError(f"{name}: {len(data)} bytes is too short for a binary STL file")
    count = int.from_bytes(data[80:84], "little")
    if len(data) != 84 + STL_TRIANGLE.itemsize * count:
        raise ValueError(f"{name}: {len(data)} bytes do not hold the {count} triangles of its binary STL header")
    corners = np.frombuffer(data, dtype=STL_TRIANGLE, count=count, offset=84)["vertices"].reshape(-1, 3)
    vertices, index = np.unique(corners, axis=0, return_inverse=True)
    return vertices, index.reshape(-1, 3).astype(np.int64)


def write_stl(vertices: np.ndarray, triangles: np.ndarray) -> bytes:
    """The bytes of a binary STL file of these triangles (unit normals; zero for a zero-area triangle)."""
    corners = np.asarray(vertices, dtype=np.float32)[np.asarray(triangles)]
    c = corners.astype(np.float64)
    normals = np.cross(c[:, 1] - c[:, 0], c[:, 2] - c[:, 0])
    length = np.sqrt((normals * normals).sum(axis=1, keepdims=True))
    normals = np.divide(normals, length, out=np.zeros_like(normals), where=length > 0)
    rows = np.zeros(len(corners), dtype=STL_TRIANGLE)
    rows["normal"] = normals.astype(np.float32)
    rows["vertices"] = corners
    return STL_HEADER + len(rows).to_bytes(4, "little") + rows.tobytes()


def hull_vertices(vertices: np.ndarray) -> np.ndarray:
    """The vertices of the convex hull of ``vertices``, sorted row by row (float32 as given)."""
    from scipy.spatial import ConvexHull

    v = np.asarray(vertices)
    hull = ConvexHull(v.astype(np.float64))
    return np.unique(v[hull.vertices], axis=0)


def _moved_inside(points: np.ndarray, vertices: np.ndarray) -> np.ndarray:
    """``points`` with those outside the convex hull of ``vertices`` (float64) moved in towards its centre.

    A point p outside becomes c + t (p - c), with c the mean of the hull's vertices and t the largest
    factor that leaves it :data:`HULL_MARGIN_M` inside every face plane.
    """
    from scipy.spatial import ConvexHull

    hull = ConvexHull(vertices)
    normal, offset = hull.equations[:, :3], hull.equations[:, 3]  # normal . x + offset <= 0 inside
    centre = vertices[hull.vertices].mean(axis=0)
    out = (points @ normal.T + offset > -HULL_MARGIN_M).any(axis=1)
    if not out.any():
        return points
    d = points[out] - centre
    room = -(normal @ centre + offset) - HULL_MARGIN_M  # how far the centre is inside each plane, less the margin
    towards = d @ normal.T
    t = np.where(towards > 0, room / np.where(towards > 0, towards, 1.0), np.inf).min(axis=1)
    moved = points.copy()
    moved[out] = centre + np.minimum(t, 1.0)[:, None] * d
    return moved


def simplified(
    vertices: np.ndarray, triangles: np.ndarray, target: int, aggressiveness: float, keep_hull: bool
) -> tuple[np.ndarray, np.ndarray]:
    """A mesh of about ``target`` triangles (float32 vertices, int64 triangles); see the module docstring.

    Raises:
        RuntimeError: With ``keep_hull``, if the result's convex hull is not the original's.
    """
    import fast_simplification

    v64 = np.asarray(vertices, dtype=np.float64)
    points, tris = fast_simplification.simplify(
        v64, np.asarray(triangles, dtype=np.int32), target_count=target, agg=aggressiveness
    )
    points = np.asarray(points, dtype=np.float64)
    tris = np.asarray(tris, dtype=np.int64)
    if not keep_hull:
        return points.astype(np.float32), tris
    points = _moved_inside(points, v64).astype(np.float32)
    hull = hull_vertices(vertices)
    present = {row.tobytes() for row in points}
    extra = np.array([row for row in hull if row.tobytes() not in present], dtype=np.float32).reshape(-1, 3)
    start = len(points)
    out_v = np.vstack([points, extra])
    zero_area = np.repeat(np.arange(start, start + len(extra), dtype=np.int64)[:, None], 3, axis=1)
    out_t = np.vstack([tris, zero_area])
    if not np.array_equal(hull_vertices(out_v), hull):
        raise RuntimeError("the simplified mesh's convex hull is not the original's")
    return out_v, out_t
