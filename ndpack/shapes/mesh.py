"""Triangle meshes as exact distance oracles.

The unsigned distance is exact: a bounding-volume hierarchy finds the nearest triangle
(:mod:`ndpack.meshes`). The sign comes from one of two methods, chosen by a check of the mesh:

- ``"pseudonormal"``: the angle-weighted pseudo-normal of the nearest feature (face, edge or
  vertex). Exact and fast, for closed, consistently oriented surfaces that do not cross themselves.
- ``"winding"``: the generalised winding number above 1/2 (hierarchical, first order). Robust for
  open meshes (scans with holes), surfaces that cross themselves, and leftover seams.

The distance is computed in coordinates normalised to the mesh's box, so float32 backends (Warp)
keep their precision; every result is in the user's units.
"""

from __future__ import annotations

import warnings

import numpy as np

from ..errors import MeshWarning, ShapeError
from ..meshes import kernels, layout, queries, surface
from ..oracle import Oracle, as_points, unit_rows

#: Points sampled to compare the two sign methods on a closed mesh: where they disagree away from
#: the surface, the surface crosses itself and only the winding number is right.
SIGN_CHECK_SAMPLES = 20_000


class TriangleMesh(Oracle):
    """A solid bounded by a triangle mesh.

    Parameters
    ----------
    vertices : (v, 3) array_like
    faces : (f, 3) array_like of int
        Triangles as vertex indices. Duplicate vertices are welded, triangles without area and
        repeated triangles dropped, and the orientation made consistent and outward.
    sign : {"auto", "pseudonormal", "winding"}
        How inside is decided. ``"auto"`` takes pseudo-normals for a closed surface that passes the
        self-crossing check, else the winding number (with a :class:`~ndpack.MeshWarning` for an
        open mesh).
    name : str, optional
        Shown in ``repr`` (the file name for :meth:`load`).

    Attributes
    ----------
    vertices : (v, 3) float64
    faces : (f, 3) int64
        The cleaned mesh the distances are computed to.
    closed : bool
        Whether every edge joins exactly two consistently oriented triangles.
    sign_method : str
        ``"pseudonormal"`` or ``"winding"``.
    notes : list of str
        What was repaired and why the sign method was chosen.

    Notes
    -----
    Inside a closed mesh the distance is exact (``exact_inside``). With the winding number on a
    closed surface that crosses itself, the distance is to every triangle, the inner sheets too, so
    it is a lower bound. On an open mesh the inside is the region of winding number above 1/2, and
    the distance ignores the holes: a sphere next to a hole may reach through it by up to the hole's
    size. Close such meshes first where that matters.
    """

    dim = 3
    convex = False

    def __init__(self, vertices, faces, sign: str = "auto", name: str | None = None):
        if sign not in surface.SIGN_METHODS:
            raise ShapeError(f"sign must be one of {surface.SIGN_METHODS}, got {sign!r}")
        prepared = surface.prepare(vertices, faces)
        self.vertices, self.faces, self.closed = prepared.vertices, prepared.faces, prepared.closed
        self.notes = list(prepared.notes)
        self.name = name
        self._bounds = np.array([self.vertices.min(axis=0), self.vertices.max(axis=0)])
        # Built for pseudo-normals first; the sign method is one number in the header.
        self._block, self._order = layout.pack_mesh(self.vertices, self.faces, "pseudonormal")
        self.sign_method = self._choose_sign(sign)
        self._block[1] = layout.SIGN_CODES[self.sign_method]
        self.exact_inside = self.exact_outside = self.sign_method == "pseudonormal"
        self._volume = prepared.volume if self.closed else None

    def _choose_sign(self, asked: str) -> str:
        where = f"{self!r}"
        if not self.closed:
            if asked == "pseudonormal":
                warnings.warn(f"{where} is open; pseudo-normal signs are wrong near its holes (asked for anyway)",
                              MeshWarning, stacklevel=3)
                return asked
            self.notes.append("open surface: inside where the winding number exceeds 1/2")
            if asked == "winding":
                return asked  # chosen knowingly: no warning
            warnings.warn(
                f"{where} is not closed (it has holes or unwelded seams): inside is decided by the generalised "
                "winding number, and spheres next to a hole may reach through it; pass sign='winding' to "
                "silence this, or close the mesh", MeshWarning, stacklevel=3)
            return "winding"
        if asked != "auto":
            return asked
        disagree = self._sign_disagreements()
        if disagree:
            self.notes.append(
                f"the surface crosses itself: pseudo-normal and winding-number signs disagree at {disagree} of "
                f"{SIGN_CHECK_SAMPLES} sample points, so the winding number decides inside")
            return "winding"
        return "pseudonormal"

    def _sign_disagreements(self) -> int:
        """Sample points (away from the surface) where the two sign methods disagree."""
        lower, upper = self._bounds
        points = lower + (upper - lower) * np.random.default_rng(0).random((SIGN_CHECK_SAMPLES, 3))
        distance = queries.signed_distance(self._block, points)  # the block still says pseudo-normals
        winding = queries.winding_number(self._block, points)
        clear = np.abs(distance) > 1e-6 * self.scale
        return int(np.count_nonzero(clear & ((distance < 0) != (winding > 0.5))))

    # ------------------------------------------------------------------ constructors
    @classmethod
    def load(cls, path, sign: str = "auto") -> TriangleMesh:
        """Read a mesh file (anything trimesh reads: STL, OBJ, PLY, OFF, GLB, ...)."""
        import os

        mesh = surface.read(path)
        return cls(mesh.vertices, mesh.faces, sign=sign, name=os.path.basename(os.fspath(path)))

    @classmethod
    def from_trimesh(cls, mesh, sign: str = "auto") -> TriangleMesh:
        """Wrap a ``trimesh.Trimesh``."""
        return cls(mesh.vertices, mesh.faces, sign=sign)

    # ------------------------------------------------------------------ queries
    @property
    def n_triangles(self) -> int:
        return len(self.faces)

    def closest_points(self, points, max_distance: float = np.inf):
        """Nearest points on the surface, searched only within ``max_distance``.

        Parameters
        ----------
        points : (n, 3) array_like
        max_distance : float
            Points farther than this from the surface get NaN (a smaller bound prunes more of
            the tree: the packing driver rarely needs distances beyond its current candidate).

        Returns
        -------
        distance : (n,) float64
            Unsigned distances (``max_distance`` where nothing is that close).
        closest : (n, 3) float64
        triangle : (n,) int64
            Row of :attr:`faces` holding the nearest point, or -1.
        """
        points = as_points(points, 3)
        if not max_distance > 0:
            raise ShapeError(f"max_distance must be positive, got {max_distance}")
        distance, closest, triangle = queries.closest(self._block, points, max_distance)
        return distance, closest, np.where(triangle >= 0, self._order[np.maximum(triangle, 0)], -1)

    def winding_number(self, points) -> np.ndarray:
        """(n,) generalised winding numbers: about 1 inside, 0 outside (fast, first-order accurate)."""
        return queries.winding_number(self._block, as_points(points, 3))

    # ------------------------------------------------------------------ oracle
    def _distance(self, points: np.ndarray) -> np.ndarray:
        return queries.signed_distance(self._block, points)

    def _distance_and_gradient(self, points: np.ndarray):
        distance, closest, triangle = queries.closest(self._block, points, signed=True)
        away = points - closest
        length = np.abs(distance)
        gradient = np.sign(distance)[:, None] * away / np.where(length > 0, length, 1.0)[:, None]
        # On the surface the offset has no direction: use the normal of the nearest triangle.
        on_surface = length <= 1e-12 * self.scale
        if on_surface.any():
            corners = self.vertices[self.faces[self._order[triangle[on_surface]]]]
            gradient[on_surface] = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
        return distance, unit_rows(gradient)

    def _gradient(self, points: np.ndarray) -> np.ndarray:
        return self._distance_and_gradient(points)[1]

    def _exact_volume(self):
        return self._volume if self.sign_method == "pseudonormal" else None

    def _kernel(self, program):
        offset = program.add_params(layout.relocate(self._block, program.next_offset))
        program.add_device_values(offset + kernels.MESH_ID, 4, self._warp_mesh_id)
        distance = kernels.add_queries(program)
        kernels.add_gradient(program, self, offset)
        return program.define(f"def _(p, prm):\n    return {distance}(p, prm, {offset})\n")

    def _tape(self, tape):
        tape.surface(self._block, self._warp_mesh_id)

    def _warp_mesh_id(self, device) -> np.ndarray:
        """The 16-bit pieces of the id of this mesh's ``wp.Mesh`` on ``device`` (built once, kept)."""
        meshes = self.__dict__.setdefault("_warp_meshes", {})
        key = str(device)
        if key not in meshes:
            meshes[key] = layout.warp_mesh_id(self._block, device)
        return meshes[key][0]

    def __repr__(self) -> str:
        what = f"{self.name!r}, " if self.name else ""
        return f"TriangleMesh({what}{self.n_triangles} triangles)"

