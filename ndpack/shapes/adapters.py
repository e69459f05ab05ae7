"""Shapes from other libraries as oracles: manifold3d solids and cross-sections, trimesh meshes,
shapely polygons.

:func:`as_oracle` is what :func:`ndpack.pack`, :func:`ndpack.verify` and the CSG operators call, so
these objects can be passed wherever an ndpack shape is expected (``nd.Box(...) - manifold``).
Each library is imported only when an object of it is seen.
"""

from __future__ import annotations

import numpy as np

from ..errors import ShapeError
from ..oracle import Oracle, operation
from .empty import Empty
from .mesh import TriangleMesh
from .polygon import Polygon


def _module_of(obj) -> str:
    return type(obj).__module__.split(".")[0]


def from_manifold(solid):
    """A :class:`~ndpack.TriangleMesh` of a ``manifold3d.Manifold`` (its float64 mesh).

    Raises
    ------
    ShapeError
        If manifold3d reports the solid invalid (for example a non-manifold input mesh), naming
        manifold3d's status. An empty solid is an :class:`~ndpack.shapes.empty.Empty`.
    """
    import manifold3d

    status = solid.status()
    if status != manifold3d.Error.NoError:
        raise ShapeError(
            f"the manifold3d solid is not valid ({status.name}): manifold3d could not build a closed "
            "2-manifold (check the input mesh: every edge must join exactly two triangles)"
        )
    if solid.is_empty():  # a valid part of a tree; packed alone, an error (see ndpack.shapes.empty)
        return Empty(3, "the manifold3d solid is empty (a difference or intersection removed everything)")
    mesh = solid.to_mesh64() if hasattr(solid, "to_mesh64") else solid.to_mesh()
    vertices = np.asarray(mesh.vert_properties, dtype=np.float64)[:, :3]
    faces = np.asarray(mesh.tri_verts, dtype=np.int64)
    # A valid Manifold is closed, oriented and never crosses itself: pseudo-normals are exact.
    return TriangleMesh(vertices, faces, sign="pseudonormal", name="manifold3d.Manifold")


def from_cross_section(section):
    """A :class:`~ndpack.Polygon` of a ``manifold3d.CrossSection`` (all its contours, holes too)."""
    if section.is_empty():
        return Empty(2, "the manifold3d cross-section is empty (a difference or intersection removed everything)")
    return Polygon.from_rings([np.asarray(ring, dtype=np.float64) for ring in section.to_polygons()])


def from_shapely(geometry):
    """A :class:`~ndpack.Polygon` of a shapely ``Polygon`` or ``MultiPolygon``."""
    if geometry.is_empty:  # an empty difference is a polygon, or a collection, of nothing
        return Empty(2, "the shapely polygon is empty")
    kind = geometry.geom_type
    if kind == "Polygon":
        parts = [geometry]
    elif kind == "MultiPolygon":
        parts = list(geometry.geoms)
    else:
        raise ShapeError(f"a shapely {kind} has no area to pack; pass a Polygon or MultiPolygon")
    if not geometry.is_valid:
        raise ShapeError("the shapely polygon is not valid (its rings cross); repair it with shapely.make_valid")
    rings = []
    for part in parts:
        rings.append(np.asarray(part.exterior.coords, dtype=np.float64))
        rings.extend(np.asarray(hole.coords, dtype=np.float64) for hole in part.interiors)
    return Polygon.from_rings(rings)


@operation("as_oracle")  # for Oracle's reflected operators: manifold - nd.Ball(...)
def as_oracle(obj):
    """``obj`` as an ndpack shape: ndpack shapes as they are, other libraries' objects converted.

    Accepts manifold3d ``Manifold`` and ``CrossSection``, ``trimesh.Trimesh`` and shapely
    ``Polygon``/``MultiPolygon``; anything else is returned unchanged (and rejected later with a
    message that says what a shape is).
    """
    if isinstance(obj, Oracle):
        return obj
    module, name = _module_of(obj), type(obj).__name__
    if module == "manifold3d" and name == "Manifold":
        return from_manifold(obj)
    if module == "manifold3d" and name == "CrossSection":
        return from_cross_section(obj)
    if module == "trimesh" and name == "Trimesh":
        return TriangleMesh.from_trimesh(obj)
    if module == "shapely":
        return from_shapely(obj)
    return obj
