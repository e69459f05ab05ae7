"""Exact 2-D polygons with holes, given by their vertex lists.

The distance is the minimum over all edges of the point-segment distance; the sign comes from
the even-odd rule over all rings (outer ring and holes). Everything is vectorised over points
and edges, in chunks of points so that memory stays bounded for polygons with many vertices.
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import ShapeError
from ..meshes import kernels, layout
from ..oracle import Oracle


def _as_ring(vertices, what: str) -> np.ndarray:
    """Validate one ring and return it as an ``(m, 2)`` float64 array without repeated vertices.

    A closing vertex equal to the first one is dropped, and so are consecutive duplicates: they
    would make zero-length edges, which have no normal.
    """
    try:
        ring = np.asarray(vertices, dtype=np.float64)
    except (TypeError, ValueError) as error:
        raise ShapeError(f"{what} must be an (m, 2) array of vertex coordinates: {error}") from None
    if ring.ndim != 2 or ring.shape[1] != 2:
        hint = ""
        if ring.ndim == 1 and ring.shape == (2,):
            hint = " (a single vertex: to give one hole, pass holes=[hole], a list of rings)"
        raise ShapeError(
            f"{what} must be an (m, 2) array of vertices, got shape {ring.shape}{hint}"
        )
    if not np.all(np.isfinite(ring)):
        raise ShapeError(f"{what} has non-finite coordinates (NaN or inf)")
    keep = np.any(ring != np.roll(ring, 1, axis=0), axis=1)
    if len(ring) and not keep.any():  # every vertex the same point
        keep[0] = True
    ring = ring[keep]
    if len(ring) < 3:
        raise ShapeError(f"{what} needs at least 3 distinct vertices, got {len(ring)}")
    return ring


def _signed_area(ring: np.ndarray) -> float:
    """Shoelace formula: positive for a counter-clockwise ring."""
    x, y = ring[:, 0], ring[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y))


#: Largest difference between a polygon's area from its rings and its even-odd area for simple
#: rings: this fraction of the area, plus the perimeter times this fraction of the outline's size
#: (manifold3d rounds coordinates: a 1 by 1e-7 sliver measured 4e-9 off in unit size).
AREA_AGREEMENT, COORDINATE_ROUNDING = 1e-6, 1e-7


def _check_simple(rings: list, area: float, perimeter: float) -> None:
    """Refuse rings whose region is not what their areas say: a ring that crosses itself, holes
    that overlap (the distance and the packing follow the even-odd rule, the area would not)."""
    import manifold3d

    # In units of the outline's size: manifold3d rounds coordinates to a fixed precision.
    points = np.concatenate(rings)
    center = 0.5 * (points.min(axis=0) + points.max(axis=0))
    size = float(np.ptp(points, axis=0).max())
    unit = [np.ascontiguousarray((ring - center) / size) for ring in rings]
    even_odd = manifold3d.CrossSection(unit, manifold3d.FillRule.EvenOdd).area() * size**2
    if abs(even_odd - area) > AREA_AGREEMENT * max(abs(area), even_odd) + COORDINATE_ROUNDING * size * perimeter:
        raise ShapeError(
            f"the rings cross themselves or each other: their areas add up to {area:.6g} but the region "
            f"they bound (even-odd rule) has area {even_odd:.6g}; split a self-crossing ring into simple "
            "rings, or build the outline as a manifold3d.CrossSection (its fill rule says which parts are "
            "inside), which ndpack packs as simple rings"
        )


def _ring_area(ring: np.ndarray, what: str) -> float:
    """The signed area of a ring, or a :class:`ShapeError` naming it when it has none."""
    area = _signed_area(ring)
    size = float(np.ptp(ring, axis=0).max())
    if abs(area) <= 1e-12 * size**2:
        # No area, and yet the vertices may span the plane: a bow-tie's two loops cancel.
        offsets = ring - ring[0]
        far = offsets[np.argmax((offsets**2).sum(axis=1))]
        if np.abs(offsets[:, 0] * far[1] - offsets[:, 1] * far[0]).max() <= 1e-12 * size**2:
            raise ShapeError(f"{what} has zero area: its vertices are all on one line")
        raise ShapeError(f"{what} crosses itself: its loops turn opposite ways, so their signed areas cancel "
                         "(a bow-tie); split it into simple rings, or build the outline as a "
                         "manifold3d.CrossSection (its fill rule says which parts are inside)")
    return area


def _crossing_parity(points: np.ndarray, start: np.ndarray, end: np.ndarray) -> np.ndarray:
    """Even-odd rule: (n,) bool, True where a ray towards +x crosses an odd number of edges.

    Parameters
    ----------
    points : (n, 2) float64
    start, end : (e, 2) float64
        Edge end points.
    """
    x, y = points[:, 0:1], points[:, 1:2]
    # Comparing raw coordinates (not differences) classifies each vertex the same way for both
    # of its edges, so the parity stays consistent at vertices.
    above_start = start[:, 1] > y
    straddles = above_start != (end[:, 1] > y)
    # Sign of the cross product says on which side of the edge line the point is; the ray
    # crosses the edge when the point is left of an upward edge or right of a downward one.
    edge = end - start
    cross = edge[:, 0] * (y - start[:, 1]) - (x - start[:, 0]) * edge[:, 1]
    upward = edge[:, 1] > 0
    crossings = straddles & ((cross > 0) == upward)
    return (np.count_nonzero(crossings, axis=1) % 2).astype(bool)


class Polygon(Oracle):
    """An exact 2-D polygon with holes.

    Parameters
    ----------
    outer : (m, 2) array_like
        Vertices of the outer ring, in either orientation; repeating the first vertex at the end
        is optional.
    holes : sequence of (k, 2) array_like
        Vertices of each hole, same conventions. Every hole must lie inside the outer ring.

    Attributes
    ----------
    outer : (m, 2) float64
        The outer ring, counter-clockwise, without a closing vertex.
    holes : tuple of (k, 2) float64
        The holes, clockwise, so that the region is always on the left of an edge.

    Notes
    -----
    The distance is exact inside and outside. Only the vertices of a hole are checked to be inside
    the outer ring; a hole whose edges cross the outer ring, or holes that overlap each other,
    are not detected, and the even-odd rule then decides what is inside.
    """

    dim = 2
    exact_inside = True
    exact_outside = True
    convex = False

    #: Largest number of (point, edge) pairs handled at once; each temporary array of a chunk
    #: holds this many floats (8 MB), a handful of them are alive together.
    chunk_pairs = 1_000_000

    def __init__(self, outer, holes=()):
        outer = _as_ring(outer, "the outer ring")
        holes = () if holes is None else holes
        if isinstance(holes, np.ndarray) and holes.ndim == 2:
            raise ShapeError(
                f"holes must be a list of (k, 2) rings, got one array of shape {holes.shape}; "
                "to give one hole, pass holes=[hole]"
            )
        holes = [_as_ring(hole, f"hole {i}") for i, hole in enumerate(holes)]

        areas = [_ring_area(outer, "the outer ring"), *(_ring_area(hole, f"hole {i}") for i, hole in enumerate(holes))]

        # Outer counter-clockwise, holes clockwise: the region is on the left of every edge,
        # so the outward normal of edge (dx, dy) is always (dy, -dx) / length.
        self.outer = outer if areas[0] > 0 else outer[::-1].copy()
        self.holes = tuple(
            hole if area < 0 else hole[::-1].copy() for hole, area in zip(holes, areas[1:])
        )

        outer_end = np.roll(self.outer, -1, axis=0)
        chunk = max(1, self.chunk_pairs // len(self.outer))
        for i, hole in enumerate(self.holes):
            inside = np.concatenate([
                _crossing_parity(hole[begin:begin + chunk], self.outer, outer_end)
                for begin in range(0, len(hole), chunk)
            ])
            if not inside.all():
                vertex = hole[int(np.flatnonzero(~inside)[0])]
                raise ShapeError(
                    f"hole {i} is not inside the outer ring: its vertex {vertex.tolist()} is "
                    "outside"
                )

        self._setup([self.outer, *self.holes], abs(areas[0]) - sum(abs(a) for a in areas[1:]))

    def _setup(self, rings, area: float):
        """Edge arrays of oriented ``rings`` (region on the left of every edge) and the area; a
        :class:`ShapeError` where the rings cross (:func:`_check_simple`)."""
        self._area = area
        self._rings = tuple(rings)
        self._start = np.ascontiguousarray(np.concatenate(rings))
        ends = [np.roll(ring, -1, axis=0) for ring in rings]
        self._end = np.ascontiguousarray(np.concatenate(ends))
        edge = self._end - self._start
        self._edge = edge
        self._inv_length2 = 1.0 / np.einsum("ij,ij->i", edge, edge)
        _check_simple(rings, area, float(np.sqrt(1.0 / self._inv_length2).sum()))
        self._normal = edge[:, ::-1] * np.array([1.0, -1.0]) * np.sqrt(self._inv_length2)[:, None]
        self._bounds = np.array([self._start.min(axis=0), self._start.max(axis=0)])
        for ring in rings:  # the edges were computed from them: changing them would do nothing
            ring.flags.writeable = False

    @classmethod
    def from_rings(cls, rings) -> Polygon:
        """A region bounded by any number of non-crossing rings: islands, holes, islands in holes.

        What is inside follows the even-odd rule: a ring inside an odd number of other rings is a
        hole. This is how manifold3d cross-sections and shapely multipolygons come in.

        Parameters
        ----------
        rings : sequence of (m, 2) array_like
            In any orientation and order.

        Notes
        -----
        ``outer`` is then the largest island, ``holes`` every other ring (holes and further islands).
        """
        rings = [_as_ring(ring, f"ring {i}") for i, ring in enumerate(rings)]
        if not rings:
            raise ShapeError("a polygon needs at least one ring")
        areas = np.array([_ring_area(ring, f"ring {i}") for i, ring in enumerate(rings)])
        # Nesting depth of each ring: how many other rings hold its first vertex.
        depth = np.zeros(len(rings), dtype=int)
        for j, other in enumerate(rings):
            firsts = np.array([ring[0] for i, ring in enumerate(rings) if i != j])
            if len(firsts):
                inside = _crossing_parity(firsts, other, np.roll(other, -1, axis=0))
                depth[[i for i in range(len(rings)) if i != j]] += inside
        hole = depth % 2 == 1
        # Islands counter-clockwise, holes clockwise: the region is on the left of every edge.
        oriented = [ring if (area > 0) != is_hole else ring[::-1].copy()
                    for ring, area, is_hole in zip(rings, areas, hole)]
        polygon = cls.__new__(cls)
        largest = int(np.argmax(np.where(hole, -np.inf, np.abs(areas))))
        polygon.outer = oriented[largest]
        polygon.holes = tuple(ring for i, ring in enumerate(oriented) if i != largest)
        polygon._setup([polygon.outer, *polygon.holes], float(np.sum(np.where(hole, -1, 1) * np.abs(areas))))
        return polygon

    @classmethod
    def regular(cls, n_sides: int, radius: float = 1.0, center=(0, 0)) -> Polygon:
        """A regular polygon with a vertex at angle 0.

        Parameters
        ----------
        n_sides : int
            Number of sides, at least 3.
        radius : float
            Distance from the centre to each vertex (circumradius).
        center : (2,) array_like
        """
        if int(n_sides) != n_sides or n_sides < 3:
            raise ShapeError(f"a regular polygon needs an integer n_sides >= 3, got {n_sides}")
        if not (math.isfinite(radius) and radius > 0):
            raise ShapeError(f"radius must be positive and finite, got {radius}")
        center = np.asarray(center, dtype=np.float64)
        if center.shape != (2,):
            raise ShapeError(f"center must have 2 coordinates, got shape {center.shape}")
        angles = 2 * np.pi * np.arange(int(n_sides)) / int(n_sides)
        return cls(center + radius * np.column_stack([np.cos(angles), np.sin(angles)]))

    @property
    def n_edges(self) -> int:
        return len(self._start)

    # ------------------------------------------------------------------ oracle
    def _distance(self, points: np.ndarray) -> np.ndarray:
        return self._evaluate(points, with_gradient=False)[0]

    def _gradient(self, points: np.ndarray) -> np.ndarray:
        return self._evaluate(points, with_gradient=True)[1]

    def _distance_and_gradient(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return self._evaluate(points, with_gradient=True)

    def _exact_volume(self) -> float:
        return self._area

    def _evaluate(self, points: np.ndarray, with_gradient: bool):
        """Signed distances (n,) and, if asked, unit gradients (n, 2), chunk by chunk."""
        n = len(points)
        distance = np.empty(n)
        gradient = np.empty((n if with_gradient else 0, 2))
        chunk = max(1, self.chunk_pairs // self.n_edges)
        for begin in range(0, n, chunk):
            part = slice(begin, min(begin + chunk, n))
            d, g = self._evaluate_chunk(points[part], with_gradient)
            distance[part] = d
            if with_gradient:
                gradient[part] = g
        return distance, gradient if with_gradient else None

    def _evaluate_chunk(self, points: np.ndarray, with_gradient: bool):
        start, edge = self._start, self._edge
        # (c, e) offsets from each edge's start, then the clamped projection parameter t.
        dx = points[:, 0:1] - start[:, 0]
        dy = points[:, 1:2] - start[:, 1]
        t = dx * edge[:, 0]
        t += dy * edge[:, 1]
        t *= self._inv_length2
        np.clip(t, 0.0, 1.0, out=t)
        # Offsets from the nearest point of each edge, overwriting dx, dy to save memory.
        dx -= t * edge[:, 0]
        dy -= t * edge[:, 1]
        squared = dx * dx
        squared += dy * dy
        nearest_edge = np.argmin(squared, axis=1)
        rows = np.arange(len(points))
        unsigned = np.sqrt(squared[rows, nearest_edge])
        del squared, dx, dy

        inside = _crossing_parity(points, start, self._end)
        distance = np.where(inside, -unsigned, unsigned)
        if not with_gradient:
            return distance, None

        nearest = start[nearest_edge] + t[rows, nearest_edge][:, None] * edge[nearest_edge]
        away = points - nearest
        sign = np.where(inside, -1.0, 1.0)[:, None]
        # On the boundary (up to rounding) the direction to the nearest point is meaningless:
        # use the outward normal of the nearest edge instead.
        on_boundary = unsigned <= 1e-12 * self.scale
        safe = np.where(on_boundary, 1.0, unsigned)[:, None]
        gradient = np.where(on_boundary[:, None], self._normal[nearest_edge], sign * away / safe)
        return distance, gradient

    def _outline(self) -> np.ndarray:
        """The edges in a segment hierarchy (ndpack.meshes), so a query costs about log(edges)."""
        block = self.__dict__.get("_outline_block")
        if block is None:
            block = self._outline_block = layout.pack_outline(
                np.stack([self._start, self._end], axis=1), self._vertex_normals())
        return block

    def _tape(self, tape):
        offset = tape.params(layout.relocate(self._outline(), tape.next_offset))
        tape.surface(offset, kernels.add_interpreter_queries)

    def _kernel(self, program):
        offset = program.add_params(layout.relocate(self._outline(), program.next_offset))
        distance = kernels.add_queries(program)
        kernels.add_gradient(program, self, offset)
        return program.define(f"def _(p, prm):\n    return {distance}(p, prm, {offset})\n")

    def _vertex_normals(self) -> np.ndarray:
        """(e, 2, 2): the pseudo-normals at each edge's start and end (sums of the two edge normals)."""
        normals, at = [], 0
        for ring in self._rings:
            own = self._normal[at:at + len(ring)]
            normals.append(np.stack([own + np.roll(own, 1, axis=0), own + np.roll(own, -1, axis=0)], axis=1))
            at += len(ring)
        return np.concatenate(normals)

    def __repr__(self) -> str:
        text = f"Polygon({len(self.outer)} vertices"
        if self.holes:
            sizes = ", ".join(str(len(hole)) for hole in self.holes)
            plural = "s" if len(self.holes) > 1 else ""
            text += f", {len(self.holes)} hole{plural} of {sizes} vertices"
        return text + ")"
