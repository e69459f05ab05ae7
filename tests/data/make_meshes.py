"""Regenerate the small test meshes in tests/data/meshes/ from the full models.

Usage::

    python tests/data/make_meshes.py [SOURCE_DIR] [--out OUT_DIR]

SOURCE_DIR holds the original OBJ files (armadillo.obj, cow.obj, fandisk.obj,
rocker-arm.obj, stanford-bunny.obj, spot.obj); it defaults to
``../../../shared/data/meshes`` relative to this script.  OUT_DIR defaults to
``meshes/`` next to this script.

Every output is a binary little-endian PLY that ``trimesh.load(path,
force="mesh")`` reads.  Vertex positions are stored as float32 (trimesh's PLY
writer), so they differ from the OBJ text by float32 rounding only.

* cow, fandisk, rocker-arm: geometry unchanged, vertices welded by position.
* armadillo: decimated from 99,976 to 20,000 triangles with quadric edge
  collapse (fast-simplification); stays closed, consistently wound, and free of
  self-intersections.
* stanford-bunny: decimated from 69,451 to 12,000 triangles with the open
  boundary frozen (``preserve_border=True``), so the five holes in the base are
  exactly those of the original.
* spot: written as trimesh loads it, NOT welded: the texture coordinates are
  kept (PLY properties ``s``, ``t``), so vertices split along texture seams stay
  split when the PLY is loaded again, and the mesh only becomes watertight after
  ``merge_vertices(merge_tex=True, merge_norm=True)``.

The decimation needs ``fast-simplification`` (``pip install
fast-simplification``); the test suite itself does not, it only reads the PLY
files.  The script ends by re-reading every file it wrote and printing its
checks.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
import trimesh
from scipy.spatial import cKDTree

HERE = Path(__file__).resolve().parent
DEFAULT_SRC = HERE / ".." / ".." / ".." / "shared" / "data" / "meshes"
DEFAULT_OUT = HERE / "meshes"

ARMADILLO_TRIANGLES = 20_000
BUNNY_TRIANGLES = 12_000


# --------------------------------------------------------------------------
# helpers
# --------------------------------------------------------------------------


def load(path: Path) -> trimesh.Trimesh:
    return trimesh.load(str(path), force="mesh")


def welded(mesh: trimesh.Trimesh) -> trimesh.Trimesh:
    """Weld vertices by position (ignoring texture coordinates and normals)
    and return a bare mesh: no visuals, no normals."""
    mesh = mesh.copy()
    mesh.merge_vertices(merge_tex=True, merge_norm=True)
    return bare(mesh.vertices, mesh.faces)


def bare(vertices, faces) -> trimesh.Trimesh:
    return trimesh.Trimesh(
        np.asarray(vertices, dtype=np.float64), np.asarray(faces, dtype=np.int64), process=True
    )


def write_ply(mesh: trimesh.Trimesh, path: Path) -> None:
    data = trimesh.exchange.ply.export_ply(mesh, encoding="binary", vertex_normal=False)
    path.write_bytes(data)


def decimate(mesh: trimesh.Trimesh, target: int, preserve_border: bool) -> trimesh.Trimesh:
    try:
        import fast_simplification
    except ImportError:  # pragma: no cover - only for regenerating the data
        sys.exit(
            "make_meshes.py needs fast-simplification to decimate armadillo and "
            "stanford-bunny: pip install fast-simplification"
        )
    v, f = fast_simplification.simplify(
        np.asarray(mesh.vertices, dtype=np.float64),
        np.asarray(mesh.faces, dtype=np.int32),
        target_count=target,
        preserve_border=preserve_border,
    )
    return bare(v, f)


def boundary_loops(mesh: trimesh.Trimesh) -> list[int]:
    """Sizes (in edges) of the connected components of the boundary edges."""
    edges, counts = np.unique(mesh.edges_sorted, axis=0, return_counts=True)
    b = edges[counts == 1]
    if len(b) == 0:
        return []
    g = trimesh.graph.connected_components(b, min_len=1)
    return sorted(len(c) for c in g)


def _segment_hits_triangle(p0, p1, a, b, c):
    """Moller-Trumbore for segments p0->p1 against triangles abc (vectorized).
    Returns (hit, t).  Coplanar pairs are not reported."""
    d = p1 - p0
    e1 = b - a
    e2 = c - a
    h = np.cross(d, e2)
    det = np.einsum("ij,ij->i", e1, h)
    scale = np.linalg.norm(e1, axis=1) * np.linalg.norm(e2, axis=1) * np.linalg.norm(d, axis=1)
    ok = np.abs(det) > 1e-12 * scale
    inv = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)
    s = p0 - a
    u = inv * np.einsum("ij,ij->i", s, h)
    q = np.cross(s, e1)
    v = inv * np.einsum("ij,ij->i", d, q)
    t = inv * np.einsum("ij,ij->i", e2, q)
    eps = 1e-9
    hit = ok & (u >= -eps) & (v >= -eps) & (u + v <= 1 + eps) & (t >= -eps) & (t <= 1 + eps)
    return hit, t


def self_intersecting_pairs(mesh: trimesh.Trimesh) -> int:
    """Number of pairs of faces that cross each other (pairs that share an edge
    are skipped; pairs that share a vertex count only if they meet elsewhere)."""
    F = mesh.faces
    V = mesh.vertices
    tri = mesh.triangles
    lo, hi = tri.min(1), tri.max(1)
    centre = (lo + hi) / 2
    radius = np.linalg.norm(hi - lo, axis=1) / 2
    pairs = cKDTree(centre).query_pairs(2 * radius.max(), output_type="ndarray")
    i, j = pairs[:, 0], pairs[:, 1]
    keep = np.all((lo[i] <= hi[j]) & (lo[j] <= hi[i]), axis=1)
    i, j = i[keep], j[keep]
    shared = (F[i][:, :, None] == F[j][:, None, :]).sum((1, 2))
    i, j = i[shared < 2], j[shared < 2]
    bad = np.zeros(len(i), dtype=bool)
    for A, B in ((i, j), (j, i)):
        a, b, c = (V[F[B][:, k]] for k in range(3))
        for k in range(3):
            u0, u1 = F[A][:, k], F[A][:, (k + 1) % 3]
            hit, t = _segment_hits_triangle(V[u0], V[u1], a, b, c)
            at0 = (F[B] == u0[:, None]).any(1) & (t < 1e-6)
            at1 = (F[B] == u1[:, None]).any(1) & (t > 1 - 1e-6)
            bad |= hit & ~at0 & ~at1
    return int(bad.sum())


def describe(name: str, mesh: trimesh.Trimesh) -> str:
    vol = f"{mesh.volume:.6g}" if mesh.is_watertight else "-"
    return (
        f"{name:22s} tris={len(mesh.faces):6d} verts={len(mesh.vertices):6d} "
        f"watertight={mesh.is_watertight!s:5s} winding={mesh.is_winding_consistent!s:5s} "
        f"volume={vol:>10s} euler={mesh.euler_number:3d} bodies={mesh.body_count}"
    )


# --------------------------------------------------------------------------
# main
# --------------------------------------------------------------------------


def build(src: Path, out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    written: dict[str, Path] = {}
    originals: dict[str, trimesh.Trimesh] = {}

    # closed models, unchanged apart from welding
    for name in ("cow", "fandisk", "rocker-arm"):
        mesh = welded(load(src / f"{name}.obj"))
        originals[name] = mesh
        written[name] = out / f"{name}.ply"
        write_ply(mesh, written[name])

    # armadillo: decimate, keep closed
    arm = welded(load(src / "armadillo.obj"))
    originals["armadillo"] = arm
    small = decimate(arm, ARMADILLO_TRIANGLES, preserve_border=False)
    written["armadillo"] = out / "armadillo-20k.ply"
    write_ply(small, written["armadillo"])

    # bunny: decimate with the open boundary frozen
    bunny = welded(load(src / "stanford-bunny.obj"))
    originals["stanford-bunny"] = bunny
    small = decimate(bunny, BUNNY_TRIANGLES, preserve_border=True)
    written["stanford-bunny"] = out / "stanford-bunny-12k.ply"
    write_ply(small, written["stanford-bunny"])

    # spot: as loaded (texture seams split vertices); keep the uv so that
    # trimesh does not weld the vertices again when it loads the PLY
    spot = load(src / "spot.obj")
    originals["spot"] = welded(spot)
    written["spot"] = out / "spot-unwelded.ply"
    write_ply(spot, written["spot"])

    # ---- checks, on the files as the tests will read them ----
    print(f"source: {src}")
    print(f"output: {out}")
    total = 0
    for name, path in written.items():
        mesh = load(path)
        size = path.stat().st_size
        total += size
        print(f"{path.name:24s} {size:9,d} bytes")
        print("  " + describe("as loaded", mesh))
        if name == "spot":
            w = mesh.copy()
            w.merge_vertices(merge_tex=True, merge_norm=True)
            print("  " + describe("after merge_vertices", w))
            mesh = w
        orig = originals[name]
        print("  " + describe("original (welded)", orig))
        if orig.is_watertight and mesh.is_watertight:
            print(f"  volume / original volume = {mesh.volume / orig.volume:.6f}")
        if not mesh.is_watertight:
            print(f"  boundary loops (edges): {boundary_loops(mesh)}  original: {boundary_loops(orig)}")
        print(f"  self-intersecting face pairs: {self_intersecting_pairs(mesh)}")
    print(f"total: {total:,d} bytes")


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("source", nargs="?", type=Path, default=DEFAULT_SRC,
                        help="folder with the original OBJ files (default: %(default)s)")
    parser.add_argument("--out", type=Path, default=DEFAULT_OUT,
                        help="output folder (default: %(default)s)")
    args = parser.parse_args(argv)
    build(args.source.resolve(), args.out.resolve())


if __name__ == "__main__":
    main()
