"""Random points on a shape's boundary and in its interior, for coverings and their checks.

A covering is built and checked on samples: every boundary sample must lie in some sphere, and
the interior samples make sure that the union holds the inside too. Meshes and polygons are
sampled exactly on their triangles and edges (uniform by area and length); any other shape, of
any dimension, by projecting points of a band around its boundary onto the zero set along the
gradient (``x - f(x) grad f(x)``, repeated), which lands on the boundary wherever the distance
is exact and converges like sphere tracing where it is a lower bound.
"""

from __future__ import annotations

import numpy as np

from .errors import ShapeError
from .oracle import Oracle, unit_rows

#: Projections of a band sample onto the boundary; exact oracles need one, lower bounds a few.
PROJECTIONS = 6


def boundary_samples(shape: Oracle, count: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """``count`` random points on the boundary of ``shape`` and the outward normals there.

    Parameters
    ----------
    shape : Oracle
        A bounded shape.
    count : int
    rng : numpy.random.Generator

    Returns
    -------
    points : (count, d) float64
    normals : (count, d) float64
        Unit outward normals (the distance's gradient for shapes other than meshes and polygons).
    """
    faces = getattr(shape, "given_faces", None)
    if faces is not None and getattr(shape, "vertices", None) is not None:
        return _mesh_samples(shape.vertices, shape.faces, count, rng)
    if hasattr(shape, "_start") and hasattr(shape, "_normal") and shape.dim == 2:
        return _outline_samples(shape._start, shape._end, shape._normal, count, rng)
    return _projected_samples(shape, count, rng)


def interior_samples(shape: Oracle, count: int, rng: np.random.Generator, tries: int = 200) -> np.ndarray:
    """``count`` points uniform in the inside of ``shape``, (count, d) float64 (rejection in its bounds)."""
    lower, upper = shape.bounds
    found, total = [], 0
    batch = max(4 * count, 1024)
    for _ in range(tries):
        points = lower + (upper - lower) * rng.random((batch, shape.dim))
        inside = points[shape._distance(points) < 0]
        found.append(inside)
        total += len(inside)
        if total >= count:
            return np.vstack(found)[:count]
    raise ShapeError(f"found only {total} of {count} points inside {shape!r} in {tries * batch} tries over its "
                     "bounds: the shape is almost empty or far smaller than its bounds; tighten the bounds")


def _mesh_samples(vertices, faces, count, rng):
    corners = vertices[faces]
    first, second = corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]
    cross = np.cross(first, second)
    areas = np.linalg.norm(cross, axis=1)
    which = rng.choice(len(faces), size=count, p=areas / areas.sum())
    u, v = rng.random(count), rng.random(count)
    flip = u + v > 1  # fold the parallelogram's far half back onto the triangle
    u[flip], v[flip] = 1 - u[flip], 1 - v[flip]
    points = corners[which, 0] + u[:, None] * first[which] + v[:, None] * second[which]
    return points, cross[which] / areas[which, None]


def _outline_samples(starts, ends, normals, count, rng):
    lengths = np.linalg.norm(ends - starts, axis=1)
    which = rng.choice(len(starts), size=count, p=lengths / lengths.sum())
    t = rng.random(count)[:, None]
    return starts[which] + t * (ends[which] - starts[which]), normals[which].copy()


def _projected_samples(shape, count, rng, tries: int = 400):
    lower, upper = shape.bounds
    extent = upper - lower
    band = 0.02 * float(extent.max())
    # The boundary may touch the bounds: sample a little beyond them.
    lower, upper = lower - band, upper + band
    tolerance = 1e-9 * shape.scale
    found, total = [], 0
    for _ in range(tries):
        points = lower + (upper - lower) * rng.random((max(8 * count, 4096), shape.dim))
        points = points[np.abs(shape._distance(points)) < band]
        for _ in range(PROJECTIONS):
            distances, gradients = shape._distance_and_gradient(points)
            points = points - distances[:, None] * gradients
        distances, gradients = shape._distance_and_gradient(points)
        on = np.abs(distances) <= tolerance
        found.append((points[on], unit_rows(gradients[on])))
        total += int(on.sum())
        if total >= count:
            break
    if total < count:
        raise ShapeError(f"found only {total} of {count} points on the boundary of {shape!r}: its distance does not "
                         "lead onto its boundary (is it 1-Lipschitz with a gradient?)")
    points = np.vstack([pair[0] for pair in found])[:count]
    normals = np.vstack([pair[1] for pair in found])[:count]
    return points, normals
