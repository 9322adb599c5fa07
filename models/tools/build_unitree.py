"""Build ``amlip_qp/models/unitree_h1/`` and ``unitree_g1/`` (package data) from MuJoCo Menagerie's Unitree folders.

Usage::

    python models/tools/build_unitree.py [--menagerie DIR] [--out DIR] [--check]

``--menagerie`` is a folder holding Menagerie's ``unitree_h1/`` and
``unitree_g1/`` (default: ``../shared/menagerie`` beside the repository).
For each robot the script writes, under ``--out`` (default
``amlip_qp/models/``):

- the robot's MJCF (``h1.xml``, ``g1.xml``) and ``LICENSE``, byte for byte as
  Menagerie ships them;
- ``assets/``: its meshes, under their own names, simplified
  (:mod:`stl_meshes`): a mesh of more than :data:`KEEP_TRIANGLES` triangles
  keeps :data:`FRACTION` of them. A mesh that a colliding geom uses keeps its
  convex hull exactly, so MuJoCo's collision geometry is unchanged. Both files
  give every body an explicit ``<inertial>``, so no mass or inertia comes from
  a mesh;
- ``README.md``: where the files come from and what was changed.

Menagerie's scenes and G1's MJX variant are not copied. The output is
deterministic. ``--check`` writes nothing: it exits 1, naming each file that
differs from what the script would write (or is missing, or should not be
there). Needs ``fast-simplification`` (the ``models`` extra), which the library
does not use.
"""

from __future__ import annotations

import argparse
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from stl_meshes import read_stl, simplified, write_stl

REPO = Path(__file__).resolve().parents[2]
DEFAULT_MENAGERIE = REPO.parent / "shared" / "menagerie"
DEFAULT_OUT = REPO / "amlip_qp" / "models"

#: The Menagerie revision the committed files were built from.
MENAGERIE_REVISION = "main branch as of 2025-06-11, after its pull request 181"
#: A mesh of at most this many triangles is copied unchanged.
KEEP_TRIANGLES = 3000
#: The fraction of its triangles that a larger mesh keeps (but never fewer than KEEP_TRIANGLES).
FRACTION = 0.25
#: fast-simplification's ``agg`` (lower keeps the shape better; 7 is its default).
AGGRESSIVENESS = 3.0


@dataclass(frozen=True)
class Robot:
    """One Menagerie folder and what to say about it."""

    folder: str
    xml: str
    title: str
    actuators: str


ROBOTS = (
    Robot("unitree_h1", "h1.xml", "Unitree H1", "19 torque motors (`<motor>`, gear 1)"),
    Robot("unitree_g1", "g1.xml", "Unitree G1 (29 DOF)", "29 position servos (`<position>`, kp 500, dampratio 1)"),
)


def colliding_mesh_files(xml_path: Path) -> tuple[list[str], set[str]]:
    """All mesh files of the model (in asset order) and those a geom with contype or conaffinity uses."""
    import mujoco

    spec = mujoco.MjSpec.from_file(str(xml_path))
    model = spec.compile()
    files = [m.file for m in spec.meshes]
    used = set()
    for g in range(model.ngeom):
        if model.geom_type[g] == mujoco.mjtGeom.mjGEOM_MESH and (model.geom_contype[g] or model.geom_conaffinity[g]):
            used.add(files[int(model.geom_dataid[g])])
    return files, used


def mesh_bytes(data: bytes, name: str, keep_hull: bool) -> tuple[bytes, int, int, int]:
    """The bytes to ship for one STL file; its triangles before, drawn after, and zero-area after.

    The file is copied unchanged if it has at most :data:`KEEP_TRIANGLES` triangles, or if the
    simplified one (with the hull's zero-area triangles) would not have fewer.
    """
    vertices, triangles = read_stl(data, name)
    n = len(triangles)
    if n <= KEEP_TRIANGLES:
        return data, n, n, 0
    v, t = simplified(vertices, triangles, max(KEEP_TRIANGLES, round(FRACTION * n)), AGGRESSIVENESS, keep_hull)
    if len(t) >= n:
        return data, n, n, 0
    zero_area = int(((t[:, 0] == t[:, 1]) & (t[:, 1] == t[:, 2])).sum())
    return write_stl(v, t), n, len(t) - zero_area, zero_area


def readme(robot: Robot, stats: list[tuple[str, int, int, int, bool]]) -> str:
    """The README.md of one output folder, from (file, triangles before, drawn, zero-area, collides) per mesh."""
    import fast_simplification

    before, drawn, zero = (sum(s[i] for s in stats) for i in (1, 2, 3))
    unchanged = sum(1 for s in stats if s[1] == s[2] and s[3] == 0)
    colliding = sum(1 for s in stats if s[4])
    lines = [
        f"# {robot.title}, from MuJoCo Menagerie",
        "",
        f"The model of the {robot.title} humanoid robot by Unitree Robotics, from MuJoCo Menagerie",
        f"(google-deepmind/mujoco_menagerie, folder `{robot.folder}`, {MENAGERIE_REVISION}),",
        "under the BSD-3-Clause licence in [LICENSE](LICENSE), copyright Unitree Robotics.",
        "",
        f"- `{robot.xml}` and `LICENSE` are Menagerie's files, unchanged. Actuators: {robot.actuators}.",
        f"- `assets/` holds the {len(stats)} meshes under their own names. {unchanged} of them (at most "
        f"{KEEP_TRIANGLES} triangles, or not made smaller) {'is' if unchanged == 1 else 'are'} Menagerie's files; "
        f"the others are simplified to about {FRACTION:.0%} of their triangles, never fewer than {KEEP_TRIANGLES} "
        "(quadric edge collapse, fast-simplification "
        f"{fast_simplification.__version__}): {drawn} triangles are drawn, of Menagerie's {before}.",
    ]
    if colliding:
        lines.append(
            f"- {colliding} meshes are used by colliding geoms. MuJoCo collides a mesh as its convex hull, and "
            f"each simplified one keeps that hull vertex for vertex ({zero} vertices added as zero-area "
            "triangles, which draw nothing), so the collision geometry is Menagerie's."
        )
    lines += [
        "- Masses and inertias are the file's `<inertial>` elements, so they are Menagerie's.",
        "- Menagerie's scene files, pictures and any MJX variant are not included.",
        "",
        "Generated by `models/tools/build_unitree.py`; do not edit by hand.",
    ]
    return "\n".join(lines) + "\n"


def build(menagerie: Path, log=print) -> dict[str, bytes]:
    """Every output file (path relative to the models folder -> bytes)."""
    out: dict[str, bytes] = {}
    for robot in ROBOTS:
        source = menagerie / robot.folder
        if not (source / robot.xml).is_file():
            raise SystemExit(f"{source / robot.xml} not found: pass --menagerie DIR (the folder with {robot.folder}/)")
        out[f"{robot.folder}/{robot.xml}"] = (source / robot.xml).read_bytes()
        out[f"{robot.folder}/LICENSE"] = (source / "LICENSE").read_bytes()
        files, colliding = colliding_mesh_files(source / robot.xml)
        stats = []
        for name in files:
            data, n0, n1, z = mesh_bytes((source / "assets" / name).read_bytes(), name, name in colliding)
            out[f"{robot.folder}/assets/{name}"] = data
            stats.append((name, n0, n1, z, name in colliding))
            hull = f" + {z} zero-area (hull kept)" if z else ""
            log(f"  {robot.folder}/assets/{name}: {n0} -> {n1} triangles{hull}")
        out[f"{robot.folder}/README.md"] = readme(robot, stats).encode()
    return out


def stale_files(expected: dict[str, bytes], out_dir: Path) -> list[str]:
    """The files under the robots' output folders that differ from ``expected``, are missing, or are extra."""
    stale = [f"{p} (missing)" for p in expected if not (out_dir / p).is_file()]
    stale += [
        f"{p} (differs)"
        for p, data in expected.items()
        if (out_dir / p).is_file() and (out_dir / p).read_bytes() != data
    ]
    for robot in ROBOTS:
        for f in sorted((out_dir / robot.folder).rglob("*")):
            rel = f.relative_to(out_dir).as_posix()
            if f.is_file() and rel not in expected:
                stale.append(f"{rel} (not built by this script)")
    return sorted(stale)


def _hull_support_m(model, data, geom: int, directions: np.ndarray) -> np.ndarray:
    """max over the mesh's vertices of u . x (world frame) for each direction u: its convex hull's support."""
    mesh = int(model.geom_dataid[geom])
    start, count = int(model.mesh_vertadr[mesh]), int(model.mesh_vertnum[mesh])
    local = model.mesh_vert[start : start + count].astype(np.float64)
    world = local @ data.geom_xmat[geom].reshape(3, 3).T + data.geom_xpos[geom]
    return (world @ directions.T).max(axis=0)


def compare(menagerie: Path, out_dir: Path, log=print) -> None:
    """Compile each original and built model and log how they differ.

    Bodies: the largest change of body_mass, body_inertia, body_ipos and body_iquat. Colliding mesh geoms: the
    largest change of the convex hull's support function (2000 directions) at a random configuration.
    """
    import mujoco

    rng = np.random.default_rng(0)
    directions = rng.normal(size=(2000, 3))
    directions /= np.sqrt((directions * directions).sum(axis=1, keepdims=True))
    for robot in ROBOTS:
        a = mujoco.MjModel.from_xml_path(str(menagerie / robot.folder / robot.xml))
        b = mujoco.MjModel.from_xml_path(str(out_dir / robot.folder / robot.xml))
        log(f"{robot.folder}: total mass {b.body_mass.sum():.9f} kg; largest change of")
        for field in ("body_mass", "body_inertia", "body_ipos", "body_iquat"):
            log(f"  {field}: {float(np.abs(getattr(a, field) - getattr(b, field)).max()):.3g}")
        qpos = a.qpos0.copy()
        qpos[7:] += rng.uniform(-0.3, 0.3, a.nq - 7)
        da, db = mujoco.MjData(a), mujoco.MjData(b)
        da.qpos[:] = db.qpos[:] = qpos
        mujoco.mj_kinematics(a, da)
        mujoco.mj_kinematics(b, db)
        meshes = [
            g
            for g in range(a.ngeom)
            if a.geom_type[g] == mujoco.mjtGeom.mjGEOM_MESH and (a.geom_contype[g] or a.geom_conaffinity[g])
        ]
        worst = 0.0
        for g in meshes:
            change = np.abs(_hull_support_m(a, da, g, directions) - _hull_support_m(b, db, g, directions))
            worst = max(worst, float(change.max()))
        log(f"  convex hull support of the {len(meshes)} colliding mesh geoms: {worst:.3g} m")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--menagerie", type=Path, default=DEFAULT_MENAGERIE)
    ap.add_argument("--out", type=Path, default=DEFAULT_OUT)
    ap.add_argument("--check", action="store_true", help="write nothing; exit 1 naming the stale files")
    args = ap.parse_args(argv)
    expected = build(args.menagerie, log=(lambda _: None) if args.check else print)
    if args.check:
        stale = stale_files(expected, args.out)
        for s in stale:
            print(f"stale: {s}")
        print(f"{len(stale)} stale of {len(expected)} files" if stale else f"all {len(expected)} files up to date")
        return 1 if stale else 0
    for robot in ROBOTS:
        for f in sorted((args.out / robot.folder).rglob("*"), reverse=True):
            rel = f.relative_to(args.out).as_posix()
            if f.is_file() and rel not in expected:
                f.unlink()
    for rel, data in expected.items():
        path = args.out / rel
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(data)
    total = sum(len(d) for d in expected.values())
    print(f"wrote {len(expected)} files, {total} bytes, under {args.out}")
    compare(args.menagerie, args.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
