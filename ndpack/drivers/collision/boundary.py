"""Random points on a shape's boundary and in its interior, for coverings and their checks.

A covering is built and checked on samples: every boundary sample must lie in some sphere, and
the interior samples make sure that the union holds the inside too. Meshes and polygons are
sampled exactly on their triangles and edges (uniform by area and length); any other shape, of
any dimension, by projecting points of a band around its boundary onto the zero set along the
gradient (``x - f(x) grad f(x)``, repeated), which lands on the boundary wherever the distance
is exact and converges like sphere tracing where it is a lower bound. The inside is drawn in the
cells of :mod:`ndpack.drivers.collision.inside_cells` known to be inside or on the boundary.
"""

from __future__ import annotations

import numpy as np

from ...errors import ShapeError
from ...oracle import Oracle, unit_rows
from .inside_cells import InsideCells

#: Projections of a band sample onto the boundary; exact oracles need one, lower bounds a few.
PROJECTIONS = 6
#: Half-width of the band around the boundary whose points are projected, as a share of the
#: bounds' largest extent.
BAND = 0.02


def boundary_samples(shape: Oracle, count: int, rng: np.random.Generator, cells=None) -> tuple[np.ndarray, np.ndarray]:
    """``count`` random points on the boundary of ``shape`` and the outward normals there.

    Parameters
    ----------
    shape : Oracle
        A bounded shape.
    count : int
    rng : numpy.random.Generator
    cells : InsideCells, optional
        The shape's grid from :func:`sample_cells`: the band of shapes other than meshes and
        polygons is then drawn in its boundary cells only, which spares most distances.

    Returns
    -------
    points : (count, d) float64
    normals : (count, d) float64
        Unit outward normals (the distance's gradient for shapes other than meshes and polygons).
    """
    if exactly_sampled(shape):
        if getattr(shape, "vertices", None) is not None:
            return _mesh_samples(shape.vertices, shape.faces, count, rng)
        return _outline_samples(shape._start, shape._end, shape._normal, count, rng)
    return _projected_samples(shape, count, rng, cells)


def exactly_sampled(shape: Oracle) -> bool:
    """Whether the boundary of ``shape`` is sampled on its own pieces (triangles, edges), not by projection."""
    return ((getattr(shape, "given_faces", None) is not None and getattr(shape, "vertices", None) is not None)
            or (hasattr(shape, "_start") and hasattr(shape, "_normal") and shape.dim == 2))


def sample_cells(shape: Oracle):
    """The shape's :class:`~ndpack.drivers.collision.inside_cells.InsideCells` for :func:`samples`: with a margin of
    the projection band where the boundary is sampled by projection."""
    return InsideCells(shape, margin=0.0 if exactly_sampled(shape) else _band(shape))


def _band(shape):
    lower, upper = shape.bounds
    return BAND * float(np.max(np.asarray(upper) - np.asarray(lower)))


def samples(shape: Oracle, count: int, rng: np.random.Generator, cells) -> tuple[np.ndarray, np.ndarray]:
    """``count`` boundary samples, then a quarter as many inside, drawn in ``cells`` (the shape's
    :class:`~ndpack.drivers.collision.inside_cells.InsideCells` from :func:`sample_cells`: far fewer distances).

    Returns
    -------
    points : (count + count // 4, d) float64
    normals : (count + count // 4, d) float64
        Outward normals on the boundary; zero rows for the interior points.
    """
    boundary, normals = boundary_samples(shape, count, rng, cells)
    inside = cells.interior(max(count // 4, 1), rng)
    return np.vstack([boundary, inside]), np.vstack([normals, np.zeros_like(inside)])


def project(shape: Oracle, points) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Move ``points`` onto the boundary along the gradient (at most :data:`PROJECTIONS` times;
    a point stops once on the boundary, after one step where the distance is exact).

    Returns
    -------
    points : (n, d) float64
    normals : (n, d) float64
        The unit gradient there.
    on : (n,) bool
        Which landed on the boundary (within 1e-9 of the shape's scale).
    """
    points = np.array(points, dtype=np.float64).reshape(-1, shape.dim)
    normals = np.zeros_like(points)
    on = np.zeros(len(points), dtype=bool)
    moving = np.arange(len(points))
    for step in range(PROJECTIONS + 1):
        distances, gradients = shape._distance_and_gradient(points[moving])
        landed = np.abs(distances) <= 1e-9 * shape.scale
        on[moving[landed]] = True
        last = step == PROJECTIONS
        finished = np.ones_like(landed) if last else landed
        normals[moving[finished]] = unit_rows(gradients[finished])
        moving, distances, gradients = moving[~finished], distances[~finished], gradients[~finished]
        if not len(moving):
            break
        points[moving] -= distances[:, None] * gradients
    return points, normals, on


def _mesh_samples(vertices, faces, count, rng):
    import trimesh

    mesh = trimesh.Trimesh(vertices, faces, process=False)  # ndpack's cleaned, outward-oriented triangles
    points, which = trimesh.sample.sample_surface(mesh, count, seed=int(rng.integers(2**32)))
    return np.asarray(points, dtype=np.float64), np.asarray(mesh.face_normals[which], dtype=np.float64)


def _outline_samples(starts, ends, normals, count, rng):
    lengths = np.linalg.norm(ends - starts, axis=1)
    which = rng.choice(len(starts), size=count, p=lengths / lengths.sum())
    t = rng.random(count)[:, None]
    return starts[which] + t * (ends[which] - starts[which]), normals[which].copy()


def _projected_samples(shape, count, rng, cells=None, tries: int = 400):
    """Points uniform in the band ``|f| < band`` (beyond the bounds too, so that edges and corners
    get the points outside them), projected onto the boundary."""
    lower, upper = shape.bounds
    band = _band(shape)
    lower, upper = lower - band, upper + band
    use_cells = cells is not None and cells.margin >= band
    found, total = [], 0
    for _ in range(tries):
        if use_cells:  # the same distribution: every point of the band lies in a boundary cell
            points, _ = cells.draw(max(3 * (count - total), 1024), rng, boundary=True)
        else:
            points = lower + (upper - lower) * rng.random((max(8 * count, 4096), shape.dim))
        points = points[np.abs(shape._distance(points)) < band]
        points, gradients, on = project(shape, points)
        found.append((points[on], gradients[on]))
        total += int(on.sum())
        if total >= count:
            break
    if total < count:
        raise ShapeError(f"found only {total} of {count} points on the boundary of {shape!r}: its distance does not "
                         "lead onto its boundary (is it 1-Lipschitz with a gradient?)")
    points = np.vstack([pair[0] for pair in found])[:count]
    normals = np.vstack([pair[1] for pair in found])[:count]
    return points, normals
