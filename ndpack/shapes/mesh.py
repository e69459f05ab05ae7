"""Triangle meshes as exact distance oracles.

The unsigned distance is exact: a bounding-volume hierarchy finds the nearest triangle
(:mod:`ndpack.meshes`). The sign comes from one of two methods, chosen by a check of the mesh:

- ``"pseudonormal"``: the angle-weighted pseudo-normal of the nearest feature (face, edge or
  vertex). Exact and fast, for closed, consistently oriented surfaces that do not cross themselves.
- ``"winding"``: the generalised winding number above 1/2 (hierarchical, first order). Robust for
  surfaces that cross themselves, non-manifold edges, and meshes whose holes were capped.

An open mesh (a scan with holes) is closed first: each hole's rim gets a fan of triangles to its
centre (:mod:`ndpack.meshes.holes`), so that the distance, not only the sign, respects the holes.

The distance is computed in coordinates normalised to the mesh's box, so float32 backends (Warp)
keep their precision; every result is in the user's units.
"""

from __future__ import annotations

import warnings

import numpy as np

from ..errors import MeshWarning, ShapeError
from ..meshes import kernels, layout, queries, solid_angles, surface
from ..oracle import Oracle, as_points, tree, unit_rows

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
        self-crossing check, else the winding number (always for a mesh whose holes were capped:
        a cap may fold over itself or cross the surface, which pseudo-normals get wrong).
    name : str, optional
        Shown in ``repr`` (the file name for :meth:`load`).
    holes : {"cap", "refuse"}, optional
        What to do with an open mesh (edges of one triangle only, or rims of any kind). ``"cap"``
        closes each hole with a fan of triangles from its rim to the rim's centre, and the caps are
        part of the surface from then on (distance and sign); ``"refuse"`` raises
        :class:`~ndpack.ShapeError`. Default: cap, with a :class:`~ndpack.MeshWarning` that says
        what was capped (pass ``holes="cap"`` to silence it).

    Attributes
    ----------
    vertices : (v, 3) float64
    faces : (f, 3) int64
        The cleaned mesh the distances are computed to: the given triangles first, then the caps
        of its holes (whose centres are the last vertices).
    given_faces : (g, 3) int64
        The rows of ``faces`` that came with the mesh (cleaned and oriented, without the caps).
    closed : bool
        Whether the given mesh had every edge join exactly two consistently oriented triangles.
    holes : int
        Holes capped (0 for a closed mesh).
    hole_option : {"cap", "refuse"} or None
        What inside means at the holes, as a packing records it (``params["holes"]``, so that
        ``ndpack verify`` and ``render`` reload the mesh the same way): the ``holes`` given, else
        ``"cap"`` where holes were capped by default, else None (a closed mesh, no choice made).
    sign_method : str
        ``"pseudonormal"`` or ``"winding"``.
    notes : list of str
        What was repaired and why the sign method was chosen.

    Notes
    -----
    Inside means: where the generalised winding number of the (capped) surface exceeds 1/2. For a
    closed surface that does not cross itself that is the solid it bounds, and the distance is exact
    (``exact_inside``). For a surface that crosses itself (or is not a manifold), inside is the
    union of the regions it wraps at least once, and the distance, to every triangle (inner sheets
    too), is a lower bound, which keeps spheres inside. An open mesh is what its caps close: for
    one hole with a planar rim that is also where the given triangles' own winding number exceeds
    1/2, but with several holes, or a rim off its plane, that number can fall below 1/2 inside
    the caps (each hole takes its solid angle from it), so the caps are the definition.

    Every tolerance of the cleaning (welding, triangles without area, the flatness and volume
    checks) is relative to the mesh's size: a mesh scaled by any factor is cleaned the same way.
    """

    dim = 3
    convex = False

    def __init__(self, vertices, faces, sign: str = "auto", name: str | None = None, holes: str | None = None):
        if sign not in surface.SIGN_METHODS:
            raise ShapeError(f"sign must be one of {surface.SIGN_METHODS}, got {sign!r}")
        queries.compile_ahead()  # a fresh machine's mesh kernels, by helpers while the surface is prepared
        prepared = surface.prepare(vertices, faces, "cap" if holes is None else holes)
        self.vertices, self.faces, self.closed = prepared.vertices, prepared.faces, prepared.closed
        self.given_faces = self.faces[:prepared.given_count]
        self.holes = prepared.holes
        self.hole_option = holes if holes is not None else ("cap" if self.holes else None)
        self.notes = list(prepared.notes)
        self.name = name
        self._bounds = np.array([self.vertices.min(axis=0), self.vertices.max(axis=0)])
        # Built for pseudo-normals first; the sign method is one number in the header.
        self._block, self._order = layout.pack_mesh(self.vertices, self.faces, "pseudonormal")
        if self.holes and holes is None:
            many = "holes, the largest" if self.holes > 1 else "hole,"
            warnings.warn(
                f"{self!r} is open ({self.holes} {many} {prepared.largest_hole:.3g} across): each hole is closed by "
                "a cap, a fan of triangles to its rim's centre, and spheres stay inside the caps; pass holes='cap' "
                "to silence this, or holes='refuse' to refuse open meshes", MeshWarning, stacklevel=2)
        self.sign_method = self._choose_sign(sign)
        self._block[1] = layout.SIGN_CODES[self.sign_method]
        self.exact_inside = self.exact_outside = self.sign_method == "pseudonormal"
        self._volume = prepared.volume

    def _choose_sign(self, asked: str) -> str:
        if self.holes:
            if asked == "pseudonormal":
                warnings.warn(f"{self!r}: pseudo-normal signs are wrong where a cap of a hole folds over (a rim "
                              "that is not planar and convex); asked for anyway", MeshWarning, stacklevel=3)
                return asked
            self.notes.append("capped surface: inside where the winding number exceeds 1/2")
            return "winding"
        if not self.closed:
            self.notes.append("not a manifold surface (edges of more than two triangles, or orientations that "
                              "cannot agree): inside where the winding number exceeds 1/2")
            return "winding" if asked == "auto" else asked
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
        # Clear of the surface by a millionth of the mesh's size (not of `scale`, which grows with
        # the distance from the origin), and by more than float64 rounding at its coordinates.
        clear = np.abs(distance) > max(1e-6 * float(np.ptp(self._bounds, axis=0).max()), 1e-12 * self.scale)
        return int(np.count_nonzero(clear & ((distance < 0) != (winding > 0.5))))

    # ------------------------------------------------------------------ constructors
    @classmethod
    def load(cls, path, sign: str = "auto", holes: str | None = None) -> TriangleMesh:
        """Read a mesh file (anything trimesh reads: STL, OBJ, PLY, OFF, GLB, ...); ``sign`` and
        ``holes`` as for the class."""
        import os

        queries.compile_ahead()  # before reading: the helpers start while the file is read and cleaned
        mesh = surface.read(path)
        return cls(mesh.vertices, mesh.faces, sign=sign, name=os.path.basename(os.fspath(path)), holes=holes)

    @classmethod
    def from_trimesh(cls, mesh, sign: str = "auto", holes: str | None = None) -> TriangleMesh:
        """Wrap a ``trimesh.Trimesh`` (``sign`` and ``holes`` as for the class)."""
        return cls(mesh.vertices, mesh.faces, sign=sign, holes=holes)

    # ------------------------------------------------------------------ queries
    @property
    def n_triangles(self) -> int:
        return len(self.faces)

    def closest_points(self, points, max_distance: float = np.inf) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
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

    def exact_winding_number(self, points, caps: bool = True) -> np.ndarray:
        """(n,) exact winding numbers of ``points`` (n, 3), summed over every triangle in NumPy.

        Nothing is shared with the packing's queries (no tree, no far-field approximation, no
        compiled code: :mod:`ndpack.meshes.solid_angles`), which makes it the independent check of
        :func:`ndpack.verify` (``independent=True``). Slow: points x triangles.

        Parameters
        ----------
        points : (n, 3) array_like
        caps : bool
            Count the caps of the holes (the surface whose inside the packing fills), or only the
            given triangles. The two agree for a mesh with one planar hole; with several holes the
            given triangles' winding number may fall below 1/2 inside the caps, as each hole takes
            its solid angle from it.
        """
        faces = self.faces if caps else self.given_faces
        return solid_angles.winding_number(self.vertices[faces], as_points(points, 3))

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

    def _step_inside(self, points, lower, upper, steps, margin):
        # The base class's loop compiled (ndpack.meshes.queries.step_in), the same numbers: a fast
        # packing's set-up steps a thousand points of the armadillo 20 times, 24 ms on 2 cores in
        # NumPy's loop, whose each step is one query of all (a thread's below 1,000 points).
        return queries.step_in(self._block, points, lower, upper, steps, margin, 1e-12 * self.scale,
                               np.ascontiguousarray(self.vertices, dtype=np.float64),
                               np.ascontiguousarray(self.faces, dtype=np.int64),
                               np.ascontiguousarray(self._order, dtype=np.int64))

    def _exact_volume(self):
        return self._volume if self.sign_method == "pseudonormal" else None

    def _kernel(self, program):
        offset = program.add_params(layout.relocate(self._block, program.next_offset))
        program.add_device_values(offset + kernels.MESH_ID, 4, self._warp_mesh_id)
        distance = kernels.add_queries(program)
        kernels.add_gradient(program, self, offset)
        return program.define(f"def _(p, prm):\n    return {distance}(p, prm, {offset})\n")

    def _tape(self, tape):
        offset = tape.params(layout.relocate(self._block, tape.next_offset))
        tape.add_device_values(offset + kernels.MESH_ID, 4, self._warp_mesh_id)
        tape.surface(offset, kernels.add_interpreter_queries)

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


def mesh_notes(shape) -> list[str]:
    """What was made of the meshes in ``shape``'s tree before use: capped holes, welded vertices,
    the winding number deciding inside (each mesh's :attr:`TriangleMesh.notes`, named)."""
    notes = []
    for node in tree(shape):
        if isinstance(node, TriangleMesh):
            if node.holes:
                notes.append(f"{node!r} is open: {node.holes} hole(s) closed by caps; the solid is the capped one")
            notes.extend(f"{node!r}: {note}" for note in node.notes)
    return notes


def recorded_holes(shape) -> str | None:
    """What a packing of ``shape`` records as ``params["holes"]``: ``"cap"`` where a mesh of its
    tree had its holes capped or was loaded with ``holes="cap"``, else ``"refuse"`` where one was
    loaded so, else None (no mesh, or no choice made). Capping leaves a closed mesh as it is, so
    one answer holds for a tree of several meshes."""
    options = {getattr(node, "hole_option", None) for node in tree(shape) if isinstance(node, TriangleMesh)}
    return "cap" if "cap" in options else "refuse" if "refuse" in options else None
