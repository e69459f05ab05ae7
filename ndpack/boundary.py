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


def samples(shape: Oracle, count: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """``count`` boundary samples, then a quarter as many inside.

    Returns
    -------
    points : (count + count // 4, d) float64
    normals : (count + count // 4, d) float64
        Outward normals on the boundary; zero rows for the interior points.
    """
    boundary, normals = boundary_samples(shape, count, rng)
    inside = interior_samples(shape, max(count // 4, 1), rng)
    return np.vstack([boundary, inside]), np.vstack([normals, np.zeros_like(inside)])


def project(shape: Oracle, points) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Move ``points`` onto the boundary along the gradient (:data:`PROJECTIONS` times).

    Returns
    -------
    points : (n, d) float64
    normals : (n, d) float64
        The unit gradient there.
    on : (n,) bool
        Which landed on the boundary (within 1e-9 of the shape's scale).
    """
    for _ in range(PROJECTIONS):
        distances, gradients = shape._distance_and_gradient(points)
        points = points - distances[:, None] * gradients
    distances, gradients = shape._distance_and_gradient(points)
    return points, unit_rows(gradients), np.abs(distances) <= 1e-9 * shape.scale


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
    import trimesh

    mesh = trimesh.Trimesh(vertices, faces, process=False)  # ndpack's cleaned, outward-oriented triangles
    points, which = trimesh.sample.sample_surface(mesh, count, seed=int(rng.integers(2**32)))
    return np.asarray(points, dtype=np.float64), np.asarray(mesh.face_normals[which], dtype=np.float64)


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
    found, total = [], 0
    for _ in range(tries):
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
