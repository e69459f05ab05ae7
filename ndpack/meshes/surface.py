"""Reading, checking and repairing triangle meshes before they become distance oracles.

trimesh does the reading, welding and orientation repair; this module decides what is an error
(nothing to pack), what is repaired (and reported), and which sign method the oracle uses.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field

import numpy as np

from ..errors import DimensionError, ShapeError

SIGN_METHODS = ("auto", "pseudonormal", "winding")


@dataclass
class Surface:
    """A cleaned triangle mesh and what was done to it.

    Attributes
    ----------
    vertices : (v, 3) float64
    faces : (f, 3) int64
        Welded, without degenerate or repeated triangles, outward oriented where that could be
        decided.
    closed : bool
        Every edge is shared by exactly two triangles with opposite directions.
    volume : float
        Enclosed volume by the divergence theorem (only meaningful when closed).
    notes : list of str
        The repairs made, in words.
    """

    vertices: np.ndarray
    faces: np.ndarray
    closed: bool
    volume: float
    notes: list[str] = field(default_factory=list)


def read(path) -> "trimesh.Trimesh":  # noqa: F821
    """Read a mesh file with trimesh (STL, OBJ, PLY, OFF, GLB, ...), raising clear errors."""
    import trimesh

    path = os.fspath(path)
    if not os.path.exists(path):
        raise ShapeError(f"no mesh file at {path!r}: check the path (relative paths start at {os.getcwd()!r})")
    if os.path.isdir(path):
        raise ShapeError(f"{path!r} is a folder, not a mesh file")
    if os.path.getsize(path) == 0:
        raise ShapeError(f"the mesh file {path!r} is empty (0 bytes)")
    try:
        # Unprocessed first: trimesh's processing drops the triangles of a NaN vertex silently,
        # which would turn a broken file into a mesh with holes. Processed below, as load would.
        loaded = trimesh.load(path, force="mesh", process=False)
    except Exception as error:  # trimesh raises many kinds for unreadable files
        raise ShapeError(
            f"trimesh cannot read {path!r} as a triangle mesh ({type(error).__name__}: {error}); "
            "use STL, OBJ, PLY, OFF or GLB"
        ) from None
    if not isinstance(loaded, trimesh.Trimesh):
        kind = type(loaded).__name__
        hint = " (a 2-D drawing: pack it with ndpack.Polygon)" if "Path2D" in kind else ""
        raise ShapeError(f"{path!r} holds a {kind}, not a triangle mesh{hint}")
    broken = int(np.count_nonzero(~np.isfinite(loaded.vertices).all(axis=1)))
    if broken:
        raise ShapeError(f"the mesh file {path!r} has {broken} {'vertex' if broken == 1 else 'vertices'} with non-finite "
                         "coordinates (NaN or infinity): repair or remove them in the file")
    loaded.process()
    if len(loaded.faces) == 0:
        raise ShapeError(f"the mesh file {path!r} has no triangles ({len(loaded.vertices)} vertices)")
    return loaded


def check_arrays(vertices, faces) -> tuple[np.ndarray, np.ndarray]:
    """``vertices`` as (v, 3) float64 and ``faces`` as (f, 3) int64, or a clear error."""
    try:
        vertices = np.asarray(vertices, dtype=np.float64)
    except (TypeError, ValueError) as error:
        raise ShapeError(f"vertices must be a (v, 3) array of coordinates: {error}") from None
    if vertices.ndim != 2 or vertices.shape[1] != 3:
        hint = ""
        if vertices.ndim == 2 and vertices.shape[1] == 2:
            hint = "; a 2-D outline is an ndpack.Polygon (or a manifold3d.CrossSection)"
        raise DimensionError(f"a triangle mesh needs 3-D vertices, an array of shape (v, 3); got {vertices.shape}{hint}")
    if not np.isfinite(vertices).all():
        raise ShapeError("the mesh has non-finite vertex coordinates (NaN or infinity)")
    faces = np.asarray(faces)
    if faces.ndim != 2 or faces.shape[1] != 3:
        raise ShapeError(
            f"faces must be an (f, 3) array of vertex indices (triangles), got shape {faces.shape}; "
            "triangulate other polygons first (trimesh does it when it loads a file)"
        )
    if len(faces) == 0:
        raise ShapeError("the mesh has no triangles")
    if not np.issubdtype(faces.dtype, np.integer):
        if not np.all(np.asarray(faces, dtype=np.float64) % 1 == 0):
            raise ShapeError("faces must hold integer vertex indices")
    faces = faces.astype(np.int64)
    if faces.min() < 0 or faces.max() >= len(vertices):
        raise ShapeError(
            f"faces refer to vertices {faces.min()}..{faces.max()}, but there are {len(vertices)} vertices "
            "(indices start at 0)"
        )
    return vertices, faces


def prepare(vertices, faces) -> Surface:
    """Weld, clean and orient a mesh; raise :class:`ShapeError` if it encloses no volume."""
    import trimesh

    vertices, faces = check_arrays(vertices, faces)
    notes = []
    mesh = trimesh.Trimesh(vertices, faces, process=False)
    count = len(mesh.vertices)
    mesh.merge_vertices(merge_tex=True, merge_norm=True)
    if len(mesh.vertices) < count:
        notes.append(f"welded {count - len(mesh.vertices)} duplicate vertices")
    keep = mesh.nondegenerate_faces()
    if not keep.all():
        notes.append(f"dropped {int((~keep).sum())} triangles without area")
    repeated = ~mesh.unique_faces() & keep
    if repeated.any():
        notes.append(f"dropped {int(repeated.sum())} repeated triangles")
    keep &= ~repeated
    if not keep.all():
        mesh.update_faces(keep)
        mesh.remove_unreferenced_vertices()
    if len(mesh.faces) == 0:
        raise ShapeError("the mesh has no triangles with area: nothing encloses a volume")
    extent = float(np.ptp(mesh.vertices, axis=0).max())
    centred = mesh.vertices - mesh.vertices.mean(axis=0)
    if np.linalg.svd(centred, compute_uv=False)[-1] <= 1e-9 * extent * np.sqrt(len(centred)):
        raise ShapeError(
            "the mesh has no volume: all its vertices lie in one plane; a flat part is a 2-D "
            "ndpack.Polygon, or thicken it first"
        )

    if not mesh.is_winding_consistent:
        trimesh.repair.fix_winding(mesh)
        notes.append("made the triangles' orientation consistent" if mesh.is_winding_consistent
                     else "could not make the triangles' orientation consistent (non-manifold edges)")
    closed = bool(mesh.is_watertight and mesh.is_winding_consistent)
    volume = float(mesh.volume)  # by the divergence theorem; only a guide for open meshes
    if closed and abs(volume) <= 1e-9 * extent**3:
        raise ShapeError(f"the mesh encloses no volume (volume {volume:.3g} for a size of {extent:.3g})")
    if volume < 0:
        mesh.invert()
        notes.append("turned the triangles outward (they faced inward)")
    return Surface(np.asarray(mesh.vertices, dtype=np.float64), np.asarray(mesh.faces, dtype=np.int64),
                   closed, abs(volume), notes)
