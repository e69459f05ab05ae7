"""Reading, checking and repairing triangle meshes before they become distance oracles.

trimesh does the reading, welding and orientation repair; this module decides what is an error
(nothing to pack), what is repaired (and reported), and which sign method the oracle uses.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field

import numpy as np

from ..errors import DimensionError, ShapeError
from . import holes as hole_caps

SIGN_METHODS = ("auto", "pseudonormal", "winding")
#: What to do with an open mesh: close each hole with a cap, or refuse it.
HOLE_OPTIONS = ("cap", "refuse")


@dataclass
class Surface:
    """A cleaned triangle mesh and what was done to it.

    Attributes
    ----------
    vertices : (v, 3) float64
    faces : (f, 3) int64
        Welded, without degenerate or repeated triangles, outward oriented where that could be
        decided; the caps of the holes (if any) are the last rows, and their centres the last
        vertices.
    closed : bool
        The mesh as given (before any caps) had every edge shared by exactly two triangles with
        opposite directions.
    volume : float
        Enclosed volume by the divergence theorem, caps included (exact when nothing crosses).
    given_count : int
        How many rows of ``faces`` are the given mesh's (the rest are caps).
    holes : int
        Holes capped.
    largest_hole : float
        The largest hole's size (its rim's bounding-box diagonal); 0 without holes.
    notes : list of str
        The repairs made, in words.
    """

    vertices: np.ndarray
    faces: np.ndarray
    closed: bool
    volume: float
    given_count: int
    holes: int = 0
    largest_hole: float = 0.0
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
        # Unprocessed: trimesh's processing drops the triangles of a NaN vertex silently, which
        # would turn a broken file into a mesh with holes.
        loaded = trimesh.load(path, force="mesh", process=False)
    except Exception as error:  # noqa: BLE001 - trimesh raises many kinds for unreadable files
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
        raise ShapeError(f"the mesh file {path!r} has {broken} {'vertex' if broken == 1 else 'vertices'} "
                         "with non-finite coordinates (NaN or infinity): repair or remove them in the file")
    # Not trimesh's process(): its welding tolerance is absolute (1e-8), which merges a small
    # mesh's vertices; prepare() does the same work relative to the mesh's size.
    if len(loaded.faces) == 0:
        raise ShapeError(f"the mesh file {path!r} has no triangles ({len(loaded.vertices)} vertices)")
    return loaded


def check_arrays(vertices, faces) -> tuple[np.ndarray, np.ndarray]:
    """``vertices`` as (v, 3) float64 and ``faces`` as (f, 3) int64, or one clear error line."""
    try:
        vertices = np.asarray(vertices, dtype=np.float64)
    except (TypeError, ValueError) as error:
        raise ShapeError(f"vertices must be a (v, 3) array of coordinates: {error}") from None
    if vertices.ndim != 2 or vertices.shape[1] != 3:
        hint = ""
        if vertices.ndim == 2 and vertices.shape[1] == 2:
            hint = "; a 2-D outline is an ndpack.Polygon (or a manifold3d.CrossSection)"
        raise DimensionError(f"a triangle mesh needs 3-D vertices, an array of shape (v, 3); "
                             f"got {vertices.shape}{hint}")
    if len(vertices) == 0:
        raise ShapeError("the mesh has no vertices: vertices has shape (0, 3)")
    broken = ~np.isfinite(vertices).all(axis=1)
    if broken.any():
        count, first = int(broken.sum()), int(np.flatnonzero(broken)[0])
        raise ShapeError(
            f"{count} of the mesh's {len(vertices)} vertices {'is' if count == 1 else 'are'} not finite (NaN or "
            f"infinity), the first at index {first}: fix their coordinates, or remove them and the triangles "
            "that use them")
    try:
        faces = np.asarray(faces)
    except ValueError as error:  # ragged lists
        raise ShapeError(f"faces must be an (f, 3) array of vertex indices: {error}") from None
    if faces.ndim != 2 or faces.shape[1] != 3:
        raise ShapeError(
            f"faces must be an (f, 3) array of vertex indices (triangles), got shape {faces.shape}; "
            "triangulate other polygons first (trimesh does it when it loads a file)"
        )
    if len(faces) == 0:
        raise ShapeError(f"the mesh has no triangles (faces has shape (0, 3), for {len(vertices)} vertices)")
    if not np.issubdtype(faces.dtype, np.integer):
        try:
            whole = np.asarray(faces, dtype=np.float64)
        except (TypeError, ValueError):
            whole = np.array(np.nan)
        if not np.all(whole % 1 == 0):
            raise ShapeError(f"faces must hold whole-number vertex indices, got {faces.dtype} values such as "
                             f"{faces.ravel()[0]!r}")
    faces = faces.astype(np.int64)
    outside = (faces < 0) | (faces >= len(vertices))
    if outside.any():
        rows = np.flatnonzero(outside.any(axis=1))
        raise ShapeError(
            f"{len(rows)} of {len(faces)} faces refer to vertices that do not exist (indices {faces.min()}..."
            f"{faces.max()}, but there are {len(vertices)} vertices; the first such face is row {rows[0]}, "
            f"{faces[rows[0]].tolist()}): indices start at 0, and negative ones are not allowed"
        )
    return vertices, faces


def prepare(vertices, faces, holes: str = "cap") -> Surface:
    """Weld, clean, orient and (where asked) close a mesh; raise :class:`ShapeError` if it encloses
    no volume, or is open and ``holes="refuse"``.

    Every tolerance is relative to the mesh's size: trimesh's (welding at 1e-8, triangles thinner
    than 1e-8 dropped) apply to the vertices moved to the centre of their box and divided by a
    power of two near the mesh's extent, so that a mesh and its copy moved or scaled by any factor
    are cleaned the same way. The vertices kept are the given ones, bit for bit.
    """
    import trimesh

    if holes not in HOLE_OPTIONS:
        raise ShapeError(f"holes must be one of {HOLE_OPTIONS}, got {holes!r}")
    vertices, faces = check_arrays(vertices, faces)
    used = vertices[np.unique(faces)]
    lower, upper = used.min(axis=0), used.max(axis=0)
    extent = float((upper - lower).max())
    if extent == 0:
        raise ShapeError("the mesh has no volume: all its triangles' vertices are the same point")
    centre, unit = 0.5 * (lower + upper), 2.0 ** np.floor(np.log2(extent))
    notes = []
    mesh = trimesh.Trimesh((vertices - centre) / unit, faces, process=False)
    # Each kept vertex's row in `vertices` (trimesh carries vertex attributes through its edits).
    mesh.vertex_attributes["given"] = np.arange(len(vertices))
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
    size = float(np.ptp(mesh.vertices, axis=0).max())  # in units of `unit`: between 1 and 2
    centred = mesh.vertices - mesh.vertices.mean(axis=0)
    if np.linalg.svd(centred, compute_uv=False)[-1] <= 1e-9 * size * np.sqrt(len(centred)):
        raise ShapeError(
            "the mesh has no volume: all its vertices lie in one plane; a flat part is a 2-D "
            "ndpack.Polygon, or thicken it first"
        )

    if not mesh.is_winding_consistent:
        trimesh.repair.fix_winding(mesh)
        notes.append("made the triangles' orientation consistent" if mesh.is_winding_consistent
                     else "could not make the triangles' orientation consistent (non-manifold edges)")
    closed = bool(mesh.is_watertight and mesh.is_winding_consistent)
    given = len(mesh.faces)
    kept = vertices[mesh.vertex_attributes["given"]]
    caps = hole_caps.cap(np.asarray(mesh.vertices), np.asarray(mesh.faces)) if not closed else hole_caps.NONE
    if caps.count and holes == "refuse":
        raise ShapeError(
            f"the mesh is open: {caps.count} {'hole' if caps.count == 1 else 'holes'} (the largest "
            f"{caps.sizes.max() * unit:.3g} across, for a mesh {size * unit:.3g} across); close it first, or pass "
            "holes='cap' (--holes cap) to close each hole with a fan of triangles")
    if caps.count:
        corners = np.vstack([mesh.vertices, caps.centers])[caps.faces]
        # Only caps with no area at all (a rim edge through its rim's centre) are left out: they
        # add nothing to the winding number and have no normal. Thin caps stay, or the surface
        # would not close.
        flat = ~np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]).any(axis=1)
        mesh = trimesh.Trimesh(np.vstack([mesh.vertices, caps.centers]),
                               np.vstack([mesh.faces, caps.faces[~flat]]), process=False)
        kept = np.vstack([kept, caps.centers * unit + centre])
        notes.append(
            f"capped {caps.count} {'hole' if caps.count == 1 else 'holes'} with {int((~flat).sum())} triangles "
            f"(fans to each rim's centre; the largest hole {caps.sizes.max() * unit:.3g} across)")
    volume = float(mesh.volume)  # by the divergence theorem, caps included
    if abs(volume) <= 1e-9 * size**3:
        raise ShapeError(f"the mesh encloses no volume (volume {volume * unit**3:.3g} for a size of "
                         f"{size * unit:.3g})")
    if volume < 0:
        mesh.invert()
        notes.append("turned the triangles outward (they faced inward)")
    return Surface(kept, np.asarray(mesh.faces, dtype=np.int64),
                   closed, abs(volume) * unit**3, given, caps.count,
                   float(caps.sizes.max(initial=0.0)) * unit, notes)
