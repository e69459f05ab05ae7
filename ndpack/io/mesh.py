"""Sphere surfaces (``mesh``, ``.obj`` ``.stl`` ``.glb``, 3-D): an icosphere per sphere, in one
triangle mesh, written and read with trimesh.

OBJ keeps float64 (17 decimals). STL and GLB store float32: their radii are shrunk by the
rounding (:func:`_float32_safe_radii`), so that the spheres read back lie inside the packed ones
and verify. Reading splits the faces into blocks, checks that each block is a closed icosphere
and takes its vertices' mean as the centre and their mean distance from it as the radius
(:func:`spheres_from_mesh`); a mesh merged, edited or made elsewhere is refused.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..errors import DimensionError, NdpackError
from ..packing import Packing
from .metadata import packing_from
from .registry import Format, register, require_dim


def sphere_mesh(centers, radii, subdivisions: int = 1):
    """One icosphere per sphere, all in one triangle mesh (built without a loop over spheres).

    Parameters
    ----------
    centers : (n, 3) float64
    radii : (n,) float64
    subdivisions : int
        Of the unit icosphere: 0 gives 12 vertices and 20 triangles a sphere, 1 gives 42 and 80,
        and each one more multiplies the triangles by 4.

    Returns
    -------
    trimesh.Trimesh
        ``n * (10 * 4**s + 2)`` vertices and ``n * 20 * 4**s`` faces; sphere ``i`` owns the
        ``i``-th block of each. Every vertex lies on its sphere (to float64 rounding).
    """
    import trimesh

    centers = np.asarray(centers, dtype=np.float64)
    radii = np.asarray(radii, dtype=np.float64)
    if centers.ndim != 2 or centers.shape[1] != 3:
        raise DimensionError(f"a sphere mesh needs 3-D centres of shape (n, 3), got {centers.shape}")
    if not (isinstance(subdivisions, (int, np.integer)) and 0 <= subdivisions <= 6):
        raise NdpackError(f"subdivisions must be an integer from 0 to 6, got {subdivisions!r}")
    unit = trimesh.creation.icosphere(subdivisions=int(subdivisions))
    vertices = (centers[:, None, :] + radii[:, None, None] * unit.vertices[None]).reshape(-1, 3)
    offsets = np.arange(len(radii), dtype=np.int64) * len(unit.vertices)
    faces = (unit.faces[None].astype(np.int64) + offsets[:, None, None]).reshape(-1, 3)
    # process=False: no vertex merging, so that the per-sphere blocks stay as built.
    return trimesh.Trimesh(vertices, faces, process=False)


def spheres_from_mesh(vertices, faces) -> tuple[np.ndarray, np.ndarray]:
    """Recover the spheres of a mesh made by :func:`sphere_mesh` (its faces in the same order).

    The faces per sphere, ``20 * 4**s``, are the smallest block size that cuts the faces into
    closed surfaces of ``10 * 4**s + 2`` vertices each (vertices matched by exact coordinates).
    This needs no vertex merging with a tolerance (STL stores every triangle's corners apart)
    and checks that every block is an icosphere; spheres that touch at a shared vertex stay apart.

    Parameters
    ----------
    vertices : (v, 3) float
    faces : (f, 3) int
        As read, unmerged: trimesh's ``process=False``.

    Returns
    -------
    centers : (n, 3) float64
        The mean of each icosphere's vertices (the icosphere is centrally symmetric).
    radii : (n,) float64
        The mean distance of its vertices from that centre (they lie on the sphere).
    """
    corners = np.asarray(vertices, dtype=np.float64)[np.asarray(faces, dtype=np.int64)]  # (f, 3, 3)
    count = len(corners)
    if count == 0:
        return np.zeros((0, 3)), np.zeros(0)
    table, ids = np.unique(corners.reshape(-1, 3), axis=0, return_inverse=True)
    ids = ids.reshape(count, 3)
    s = 0
    while 20 * 4**s <= count:
        per_sphere = 20 * 4**s
        if count % per_sphere == 0:
            found = _icosphere_blocks(table, ids, per_sphere, 10 * 4**s + 2)
            if found is not None:
                return found
        s += 1
    raise ValueError(f"its {count} triangles are not icospheres of one size written by ndpack")


def _icosphere_blocks(table: np.ndarray, ids: np.ndarray, per_sphere: int, vertex_count: int):
    """Centres ``(n, 3)`` and radii ``(n,)`` if every block of ``per_sphere`` faces is a closed
    icosphere, else None. ``table``: ``(u, 3)`` distinct vertices; ``ids``: ``(f, 3)`` into it."""
    count = len(ids) // per_sphere
    block = np.repeat(np.arange(count), per_sphere * 3)
    # Closed: every edge of a block is shared by exactly two of its faces.
    edges = np.sort(np.stack([ids, np.roll(ids, -1, axis=1)], axis=2).reshape(-1, 2), axis=1)
    _, uses = np.unique(np.column_stack([block, edges]), axis=0, return_counts=True)
    if not np.all(uses == 2):
        return None
    corners = np.sort(ids.reshape(count, per_sphere * 3), axis=1)
    first = np.ones(corners.shape, dtype=bool)
    first[:, 1:] = corners[:, 1:] != corners[:, :-1]
    if not np.all(first.sum(axis=1) == vertex_count):
        return None
    points = table[corners[first]].reshape(count, vertex_count, 3)
    centers = points.mean(axis=1)
    radii = np.linalg.norm(points - centers[:, None, :], axis=2).mean(axis=1)
    return centers, radii


def _float32_safe_radii(centers, radii, subdivisions: int) -> np.ndarray:
    """Radii to write in a float32 mesh (STL, GLB) so that the spheres read back from its rounded
    vertices (as :func:`spheres_from_mesh` recovers them) lie inside the given ones: a packing's
    file then verifies as the packing does. Each radius shrinks by about the float32 rounding of
    its coordinates (1e-7 of them), found by rounding the vertices as the writer will.

    Parameters
    ----------
    centers : (n, 3) float64
    radii : (n,) float64
    subdivisions : int

    Returns
    -------
    (n,) float64
    """
    centers = np.asarray(centers, dtype=np.float64)
    radii = np.asarray(radii, dtype=np.float64)
    # float32's spacing at each sphere's largest coordinate: the step its vertices round to.
    step = np.spacing(np.float32(np.abs(centers).max(axis=1) + radii)).astype(np.float64)
    written = radii.copy()
    for _ in range(8):
        vertices = sphere_mesh(centers, written, subdivisions).vertices
        stored = vertices.astype(np.float32).astype(np.float64).reshape(len(radii), -1, 3)
        read_centers = stored.mean(axis=1)
        read_radii = np.linalg.norm(stored - read_centers[:, None, :], axis=2).mean(axis=1)
        excess = np.linalg.norm(read_centers - centers, axis=1) + read_radii - radii
        beyond = excess > -step  # within a rounding step of reaching out: shrink it
        if not beyond.any():
            break
        written[beyond] -= excess[beyond] + 2 * step[beyond]
    else:
        raise NdpackError("float32 cannot hold these spheres inside their own radii; save as .obj or .npz")
    if np.any(written <= 0):
        raise NdpackError(f"{int(np.count_nonzero(written <= 0))} spheres are smaller than float32 can place at "
                          "their coordinates (STL and GLB store float32): save as .obj or .npz, which keep float64")
    return written


def _write_mesh(packing: Packing, path: Path, subdivisions: int = 1) -> None:
    require_dim(packing.dim, range(3, 4), "a sphere mesh (.obj, .stl, .glb)")
    if not len(packing):
        raise NdpackError("an empty packing makes no sphere mesh (a mesh file with no triangles)")
    float32 = path.suffix.lower() != ".obj"
    radii = _float32_safe_radii(packing.centers, packing.radii, subdivisions) if float32 else packing.radii
    mesh = sphere_mesh(packing.centers, radii, subdivisions)
    if not float32:
        # 17 decimals: OBJ keeps float64 to about 1e-17; STL and GLB store float32.
        header = f"ndpack: {len(packing)} icospheres of {20 * 4**subdivisions} triangles"
        mesh.export(path, file_type="obj", include_normals=False, digits=17, header=header)
    else:
        mesh.export(path, file_type=path.suffix.lower()[1:])


def _read_mesh(path: Path) -> Packing:
    import trimesh

    try:
        # process=False: no merging or reordering, so that each sphere stays one block of faces.
        mesh = trimesh.load(path, force="mesh", process=False)
    except Exception as error:  # trimesh raises many kinds for unreadable files
        raise ValueError(f"trimesh cannot read it ({type(error).__name__}: {error})") from error
    if not isinstance(mesh, trimesh.Trimesh):
        raise ValueError(f"it holds a {type(mesh).__name__}, not a triangle mesh")
    if len(mesh.faces) == 0:
        raise ValueError("it has no triangles")
    centers, radii = spheres_from_mesh(mesh.vertices, mesh.faces)
    return packing_from(None, centers, radii)


register(Format("mesh", (".obj", ".stl", ".glb"), "3", "an icosphere per sphere (STL, GLB: float32)",
                {"subdivisions": "1"}, _write_mesh, _read_mesh), default_for=(".obj", ".stl", ".glb"))
