"""Independent references for fuzzing: which points a shape tree holds, written from first principles.

Each function returns a :class:`Reference` of one primitive or node, built from the numbers the
generator drew (:mod:`fuzz_shapes`), never from an ndpack object: the exact membership of each
primitive composed with and / or / not; meshes, manifold3d solids and cross-sections through
libigl's winding number of their own meshes (a cross-section through its own extrusion; an open
mesh through the closed one it was cut from);
polygons and shapely geometries through shapely. Where the reference knows the exact signed
distance (balls, boxes, capsules, cylinders, tori and their rigid motions), offsets, shells and
smooth unions are defined from it.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

def _none(points):
    return np.zeros((len(points), 0, points.shape[1]))


@dataclass
class Reference:
    """The independent membership of a tree, and where its spheres are worth sampling.

    Attributes
    ----------
    dim : int
    inside : callable
        ``(m, d) float64 -> (m,) bool``: strictly inside (up to float64 rounding at the boundary).
    box : (2, d) float64
        A box holding the set; infinite entries for unbounded sets.
    distance : callable or None
        ``(m, d) -> (m,)``: the exact signed distance (negative inside), where the reference
        knows it (primitives of :data:`EXACT_KINDS` and their rigid motions and scalings).
    anchors : callable
        ``(m, d) -> (m, k, d)``: points that matter for a sphere centred at each point (the
        primitives' centres, axes and nearest boundary points): the check samples each sphere
        towards and away from them, and at them when they lie within it.
    normals : callable
        ``(m, d) -> (m, k, d)``: unit directions (facet normals) whose extreme sphere points
        the check samples.
    """

    dim: int
    inside: callable
    box: np.ndarray
    distance: callable = None
    anchors: callable = field(default=_none)
    normals: callable = field(default=_none)


def _stack(*arrays):
    """Concatenate (m, k_i, d) arrays along k."""
    return np.concatenate(arrays, axis=1)


def _union_box(boxes):
    boxes = np.stack(boxes)
    return np.stack([boxes[:, 0].min(axis=0), boxes[:, 1].max(axis=0)])


def _pad(box, amount):
    return box + np.array([[-amount], [amount]])


# ---------------------------------------------------------------------- primitives
def ball(center, radius) -> Reference:
    def distance(x):
        return np.sqrt(((x - center) ** 2).sum(axis=1)) - radius

    return Reference(len(center), lambda x: ((x - center) ** 2).sum(axis=1) < radius**2,
                     np.array([center - radius, center + radius]), distance,
                     anchors=lambda x: np.broadcast_to(center, x.shape)[:, None].copy())


def _box_distance(x, lower, upper):
    """Exact signed distance to ``[lower, upper]``: outside the gap to the clamped point,
    inside minus the gap to the nearest face."""
    gap = np.sqrt(((x - np.clip(x, lower, upper)) ** 2).sum(axis=1))
    depth = np.minimum(x - lower, upper - x).min(axis=1)
    return np.where(gap > 0, gap, -np.maximum(depth, 0.0))


def _box_nearest(x, lower, upper):
    """The nearest point of the box's surface to each point."""
    clamped = np.clip(x, lower, upper)
    inner = np.all((x > lower) & (x < upper), axis=1)
    to_lower, to_upper = x - lower, upper - x
    axis = np.argmin(np.minimum(to_lower, to_upper), axis=1)
    rows = np.flatnonzero(inner)
    low = to_lower[rows, axis[rows]] < to_upper[rows, axis[rows]]
    clamped[rows, axis[rows]] = np.where(low, lower[axis[rows]], upper[axis[rows]])
    return clamped


def box(lower, upper) -> Reference:
    def anchors(x):
        return np.stack([np.broadcast_to((lower + upper) / 2, x.shape), _box_nearest(x, lower, upper)], axis=1)

    return Reference(len(lower), lambda x: np.all((x > lower) & (x < upper), axis=1),
                     np.array([lower, upper]), lambda x: _box_distance(x, lower, upper), anchors)


def rounded_box(lower, upper, radius) -> Reference:
    """The inner box ``[lower + r, upper - r]`` grown by ``r``."""
    inner_lower, inner_upper = lower + radius, upper - radius

    def distance(x):
        return _box_distance(x, inner_lower, inner_upper) - radius

    def anchors(x):
        return np.stack([np.clip(x, inner_lower, inner_upper), _box_nearest(x, lower, upper)], axis=1)

    return Reference(len(lower), lambda x: distance(x) < 0, np.array([lower, upper]), distance, anchors)


def _segment_point(x, a, b):
    """The nearest point of the segment ``ab`` to each point (``a`` where ``a == b``)."""
    ab = b - a
    length_sq = float(ab @ ab)
    t = np.zeros(len(x)) if length_sq == 0 else np.clip((x - a) @ ab / length_sq, 0.0, 1.0)
    return a + t[:, None] * ab


def capsule(a, b, radius) -> Reference:
    def distance(x):
        return np.sqrt(((x - _segment_point(x, a, b)) ** 2).sum(axis=1)) - radius

    box_ = np.array([np.minimum(a, b) - radius, np.maximum(a, b) + radius])
    return Reference(len(a), lambda x: distance(x) < 0, box_, distance,
                     anchors=lambda x: _segment_point(x, a, b)[:, None])


def cylinder(a, b, radius) -> Reference:
    """A (d-1)-ball of ``radius`` swept along the segment ``ab`` (flat ends)."""
    axis = (b - a) / np.linalg.norm(b - a)
    half = np.linalg.norm(b - a) / 2
    middle = (a + b) / 2

    def split(x):
        along = (x - middle) @ axis
        across = np.sqrt(np.maximum(((x - middle) ** 2).sum(axis=1) - along**2, 0.0))
        return along, across

    def distance(x):
        along, across = split(x)
        axial, radial = np.abs(along) - half, across - radius
        outside = np.hypot(np.maximum(axial, 0.0), np.maximum(radial, 0.0))
        return np.where((axial > 0) | (radial > 0), outside, np.maximum(axial, radial))

    def anchors(x):
        return np.stack([_segment_point(x, a, b), np.broadcast_to(a, x.shape), np.broadcast_to(b, x.shape)], axis=1)

    # Each end disc reaches radius * sqrt(1 - axis_i^2) along axis i.
    reach = radius * np.sqrt(np.maximum(1 - axis**2, 0.0))
    box_ = np.array([np.minimum(a, b) - reach, np.maximum(a, b) + reach])
    return Reference(len(a), lambda x: distance(x) < 0, box_, distance, anchors,
                     normals=lambda x: np.broadcast_to(np.stack([axis, -axis]), (len(x), 2, len(a))))


def polytope(normals, offsets, vertices) -> Reference:
    """``normals @ x < offsets`` (rows of any length); ``vertices`` (the generator's) bound it."""
    units = normals / np.linalg.norm(normals, axis=1)[:, None]
    center = vertices.mean(axis=0)
    return Reference(normals.shape[1], lambda x: np.all(x @ normals.T < offsets, axis=1),
                     np.array([vertices.min(axis=0), vertices.max(axis=0)]),
                     anchors=lambda x: np.broadcast_to(center, x.shape)[:, None].copy(),
                     normals=lambda x: np.broadcast_to(units, (len(x),) + units.shape))


def simplex(vertices) -> Reference:
    """Barycentric coordinates all positive: ``x = v_0 + E lambda``, ``lambda_0 = 1 - sum``."""
    edges = (vertices[1:] - vertices[0]).T
    inverse = np.linalg.inv(edges)
    # Outward facet normals: minus the gradients of the barycentric coordinates.
    gradients = np.vstack([-inverse.sum(axis=0), inverse])
    units = -gradients / np.linalg.norm(gradients, axis=1)[:, None]
    center = vertices.mean(axis=0)

    def inside(x):
        rest = (x - vertices[0]) @ inverse.T
        return np.all(rest > 0, axis=1) & (rest.sum(axis=1) < 1)

    return Reference(vertices.shape[1], inside, np.array([vertices.min(axis=0), vertices.max(axis=0)]),
                     anchors=lambda x: np.broadcast_to(center, x.shape)[:, None].copy(),
                     normals=lambda x: np.broadcast_to(units, (len(x),) + units.shape))


def ellipsoid(center, radii) -> Reference:
    return Reference(len(center), lambda x: (((x - center) / radii) ** 2).sum(axis=1) < 1,
                     np.array([center - radii, center + radii]),
                     anchors=lambda x: np.broadcast_to(center, x.shape)[:, None].copy())


def torus(center, major, minor) -> Reference:
    """Points within ``minor`` of the circle of radius ``major`` about the z axis through ``center``."""
    def core(x):
        planar = x - center
        planar[:, 2] = 0.0
        rho = np.sqrt((planar**2).sum(axis=1))
        direction = np.where(rho[:, None] > 0, planar / np.maximum(rho, 1e-300)[:, None], [1.0, 0.0, 0.0])
        return center + major * direction

    def distance(x):
        return np.sqrt(((x - core(x)) ** 2).sum(axis=1)) - minor

    reach = np.array([major + minor, major + minor, minor])
    return Reference(3, lambda x: distance(x) < 0, np.array([center - reach, center + reach]), distance,
                     anchors=lambda x: core(x)[:, None])


def half_space(normal, offset) -> Reference:
    unit = normal / np.linalg.norm(normal)
    dim = len(normal)
    return Reference(dim, lambda x: x @ normal < offset, np.array([np.full(dim, -np.inf), np.full(dim, np.inf)]),
                     lambda x: (x @ normal - offset) / np.linalg.norm(normal),
                     normals=lambda x: np.broadcast_to(unit, x.shape)[:, None].copy())


def slab(normal, lower, upper) -> Reference:
    unit = normal / np.linalg.norm(normal)
    dim = len(normal)
    return Reference(dim, lambda x: (x @ unit > lower) & (x @ unit < upper),
                     np.array([np.full(dim, -np.inf), np.full(dim, np.inf)]),
                     lambda x: np.abs(x @ unit - (lower + upper) / 2) - (upper - lower) / 2,
                     normals=lambda x: np.broadcast_to(np.stack([unit, -unit]), (len(x), 2, dim)))


# ---------------------------------------------------------------------- meshes and outlines
def _nearest_vertices(vertices, count=4):
    from scipy.spatial import cKDTree

    tree = cKDTree(vertices)
    count = min(count, len(vertices))
    return lambda x: vertices[tree.query(x, k=count)[1].reshape(len(x), count)]


def winding_mesh(vertices, faces) -> Reference:
    """A closed triangle mesh, inside where libigl's winding number exceeds one half."""
    import igl

    vertices = np.ascontiguousarray(vertices, dtype=np.float64)
    faces = np.ascontiguousarray(faces, dtype=np.int64)
    if len(faces) == 0:
        return Reference(3, lambda x: np.zeros(len(x), bool), np.zeros((2, 3)))

    def inside(x):
        return igl.winding_number(vertices, faces, np.ascontiguousarray(x, dtype=np.float64)) > 0.5

    return Reference(3, inside, np.array([vertices.min(axis=0), vertices.max(axis=0)]),
                     anchors=_nearest_vertices(vertices))


def capped_mesh(vertices, faces, removed) -> Reference:
    """An open mesh whose holes are the triangles ``removed`` (rows of ``faces``, sharing no
    vertex), capped: inside by libigl's winding number of all of ``faces``, the removed ones
    included (a cap in a triangle's plane covers it). The holes' centres are anchors, so that
    the spheres next to a hole are sampled towards it."""
    closed = winding_mesh(vertices, faces)
    centers = np.asarray(vertices, dtype=np.float64)[np.asarray(faces)[removed]].mean(axis=1)
    near = _nearest_vertices(np.vstack([np.asarray(vertices, dtype=np.float64), centers]))
    closed.anchors = lambda x: np.concatenate([near(x), np.broadcast_to(centers, (len(x),) + centers.shape)], axis=1)
    return closed


def manifold_solid(solid) -> Reference:
    mesh = solid.to_mesh64()
    return winding_mesh(np.asarray(mesh.vert_properties)[:, :3], np.asarray(mesh.tri_verts))


def cross_section(section) -> Reference:
    """A manifold3d cross-section, through manifold3d's own extrusion: inside at mid-height."""
    import manifold3d as m3d

    reference = manifold_solid(m3d.Manifold.extrude(section, 1.0))

    def lift(x):
        return np.column_stack([x, np.full(len(x), 0.5)])

    def anchors(x):
        return reference.anchors(lift(x))[:, :, :2]

    return Reference(2, lambda x: reference.inside(lift(x)), reference.box[:, :2], anchors=anchors)


def shapely_region(geometry) -> Reference:
    import shapely

    coordinates = np.asarray(shapely.get_coordinates(geometry.boundary))
    lower, upper = np.asarray(geometry.bounds[:2]), np.asarray(geometry.bounds[2:])
    return Reference(2, lambda x: shapely.contains_xy(geometry, x[:, 0], x[:, 1]), np.array([lower, upper]),
                     anchors=_nearest_vertices(coordinates) if len(coordinates) else _none)


def even_odd(rings) -> Reference:
    """Inside an odd number of the nested rings (shapely tells inside each ring)."""
    import shapely

    polygons = [shapely.Polygon(ring) for ring in rings]
    vertices = np.concatenate(rings)

    def inside(x):
        count = sum(shapely.contains_xy(p, x[:, 0], x[:, 1]).astype(int) for p in polygons)
        return count % 2 == 1

    return Reference(2, inside, np.array([vertices.min(axis=0), vertices.max(axis=0)]),
                     anchors=_nearest_vertices(vertices))


# ---------------------------------------------------------------------- nodes
def union(*children: Reference) -> Reference:
    return Reference(children[0].dim, lambda x: np.any([c.inside(x) for c in children], axis=0),
                     _union_box([c.box for c in children]),
                     anchors=lambda x: _stack(*[c.anchors(x) for c in children]),
                     normals=lambda x: _stack(*[c.normals(x) for c in children]))


def intersection(*children: Reference) -> Reference:
    boxes = np.stack([c.box for c in children])
    return Reference(children[0].dim, lambda x: np.all([c.inside(x) for c in children], axis=0),
                     np.stack([boxes[:, 0].max(axis=0), boxes[:, 1].min(axis=0)]),
                     anchors=lambda x: _stack(*[c.anchors(x) for c in children]),
                     normals=lambda x: _stack(*[c.normals(x) for c in children]))


def complement(child: Reference) -> Reference:
    dim = child.dim
    distance = None if child.distance is None else (lambda x: -child.distance(x))
    return Reference(dim, lambda x: ~child.inside(x), np.array([np.full(dim, -np.inf), np.full(dim, np.inf)]),
                     distance, child.anchors, child.normals)


def difference(a: Reference, b: Reference) -> Reference:
    both = intersection(a, complement(b))
    both.box = a.box.copy()
    return both


def smooth_union(a: Reference, b: Reference, blend: float) -> Reference:
    """``{smin(a, b) < 0}`` with the polynomial smooth minimum of the exact distances: with
    ``h = clip(1/2 + (b - a) / 2k)``, ``smin = b + h (a - b) - k h (1 - h)``, at most ``k / 4``
    below ``min(a, b)``, so the set lies within ``k / 4`` of the union."""
    def value(x):
        da, db = a.distance(x), b.distance(x)
        h = np.clip(0.5 + (db - da) / (2 * blend), 0.0, 1.0)
        return db + h * (da - db) - blend * h * (1 - h)

    joined = union(a, b)
    return Reference(a.dim, lambda x: value(x) < 0, _pad(joined.box, blend / 4),
                     anchors=joined.anchors, normals=joined.normals)


def offset(child: Reference, amount: float) -> Reference:
    """Grown (``amount > 0``) or shrunk: ``{distance < amount}`` of the exact distance."""
    return Reference(child.dim, lambda x: child.distance(x) < amount, _pad(child.box, max(amount, 0.0)),
                     anchors=child.anchors, normals=child.normals)


def shell(child: Reference, thickness: float) -> Reference:
    return Reference(child.dim, lambda x: np.abs(child.distance(x)) < thickness / 2, _pad(child.box, thickness / 2),
                     anchors=child.anchors, normals=child.normals)


def _box_corners(box):
    dim = box.shape[1]
    choice = (np.arange(2**dim)[:, None] >> np.arange(dim)) & 1
    return box[choice, np.arange(dim)]


def mapped(child: Reference, to_child, from_child, linear, factor=1.0) -> Reference:
    """The child seen through an affine map: ``x`` is inside when ``to_child(x)`` is inside the child.

    ``from_child`` maps child points back (boxes, anchors), ``linear`` (d, d) child directions
    back (row vectors: ``v @ linear``), and ``factor`` scales distances.
    """
    if np.all(np.isfinite(child.box)):
        corners = from_child(_box_corners(child.box))
        box_ = np.array([corners.min(axis=0), corners.max(axis=0)])
    else:
        box_ = np.array([np.full(child.dim, -np.inf), np.full(child.dim, np.inf)])

    def anchors(x):
        found = child.anchors(to_child(x))
        return from_child(found.reshape(-1, child.dim)).reshape(found.shape)

    distance = None if child.distance is None else (lambda x: factor * child.distance(to_child(x)))
    return Reference(child.dim, lambda x: child.inside(to_child(x)), box_, distance, anchors,
                     lambda x: child.normals(to_child(x)) @ linear)


def translated(child: Reference, shift) -> Reference:
    return mapped(child, lambda x: x - shift, lambda y: y + shift, np.eye(child.dim))


def rotated(child: Reference, matrix, center) -> Reference:
    """ndpack's convention: the child turned by ``matrix`` about ``center``, so a world point
    ``x`` came from the child point ``matrix^T (x - center) + center``."""
    return mapped(child, lambda x: (x - center) @ matrix + center, lambda y: (y - center) @ matrix.T + center,
                  matrix.T)


def scaled(child: Reference, factor, center) -> Reference:
    return mapped(child, lambda x: (x - center) / factor + center, lambda y: (y - center) * factor + center,
                  np.eye(child.dim), factor)
