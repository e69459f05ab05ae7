"""The NumPy backend: the reference every other backend is compared with.

Plain vectorised NumPy over all prototypes at once; loops run only over iterations and over
chunks that keep temporary arrays near ``CHUNK_FLOATS`` entries.
"""

from __future__ import annotations

import numpy as np

from .base import Backend

#: Largest temporary array (in float64 entries) built at once by the pairwise loops.
CHUNK_FLOATS = 4_000_000


def _chunks(count: int, per_item: int):
    size = max(1, CHUNK_FLOATS // max(per_item, 1))
    for start in range(0, count, size):
        yield slice(start, min(count, start + size))


def _with_sphere_at_infinity(centers, radii):
    """Append the padding sphere: centre at infinity, radius 0, so its clearance is +inf."""
    dim = centers.shape[1]
    return (
        np.vstack([centers, np.full((1, dim), np.inf)]),
        np.append(radii, 0.0),
    )


class NumpyBackend(Backend):
    """Reference implementation in NumPy (float64, single thread)."""

    name = "numpy"

    def _free_space_among(self, shape, points, neighbour_centers, neighbour_radii):
        """Clearance and the unit direction away from the nearest obstacle, for (n, d) points."""
        distances, gradients = shape._distance_and_gradient(points)
        clearance = -distances
        direction = -gradients
        if neighbour_centers.shape[1]:
            offsets = points[:, None, :] - neighbour_centers
            lengths = np.sqrt(np.einsum("nkd,nkd->nk", offsets, offsets))
            gaps = lengths - neighbour_radii
            nearest = np.argmin(gaps, axis=1)
            rows = np.arange(len(points))
            gap = gaps[rows, nearest]
            closer = gap < clearance
            if closer.any():
                chosen = rows[closer]
                length = lengths[chosen, nearest[closer]]
                away = offsets[chosen, nearest[closer]]
                # A prototype exactly at a sphere centre has no preferred way out: take axis 0.
                safe = length > 0
                away[safe] /= length[safe, None]
                away[~safe] = np.eye(points.shape[1])[0]
                direction[chosen] = away
                clearance[chosen] = gap[closer]
        return clearance, direction

    def clearance(self, shape, points, centers, radii, neighbours):
        return self.free_space(shape, points, centers, radii, neighbours)[0]

    def free_space(self, shape, points, centers, radii, neighbours):
        centers, radii = _with_sphere_at_infinity(centers, radii)
        # In chunks of points: the neighbours' centres are (n, w, d), and in high dimensions
        # every sphere is near every cell (12-D, 1,614 spheres: 4.8 GB for one restart).
        parts = list(_chunks(len(points), neighbours.shape[1] * points.shape[1])) or [slice(0, 0)]
        found = [self._free_space_among(shape, points[part], centers[neighbours[part]], radii[neighbours[part]])
                 for part in parts]
        return np.concatenate([c for c, _ in found]), np.concatenate([g for _, g in found])

    def converge(self, shape, points, cell_lower, cell_upper, centers, radii, neighbours, steps, wall=None,
                 starts=None):
        # ``wall`` only lets the compiled backends skip distances that cannot matter; the
        # reference evaluates them all.
        points = self._best_of_starts(shape, points, starts, centers, radii, neighbours)
        centers, radii = _with_sphere_at_infinity(centers, radii)
        best_points, best = np.empty_like(points), np.empty(len(points))
        for part in _chunks(len(points), neighbours.shape[1] * points.shape[1]):  # bounded memory, as above
            best_points[part], best[part] = self._converge_among(
                shape, points[part], cell_lower[part], cell_upper[part], centers[neighbours[part]],
                radii[neighbours[part]], steps)
        return best_points, best

    def _converge_among(self, shape, points, cell_lower, cell_upper, neighbour_centers, neighbour_radii, steps):
        """:meth:`converge` from ``points`` (n, d) among their neighbours (n, w, d), (n, w)."""
        points = points.copy()
        best_points = points.copy()
        best = np.full(len(points), -np.inf)
        # One evaluation more than there are steps: the point after the last step counts too.
        for eps in [*steps, 0.0]:
            clearance, direction = self._free_space_among(shape, points, neighbour_centers, neighbour_radii)
            # The zig-zag around a Voronoi node is not monotone: keep the best point seen.
            better = clearance > best
            best[better] = clearance[better]
            best_points[better] = points[better]
            # |clearance|: a prototype inside an obstacle also moves towards free space.
            points += (eps * np.abs(clearance))[:, None] * direction
            np.clip(points, cell_lower, cell_upper, out=points)
        return best_points, best

    def near_spheres(self, box_lower, box_upper, reach, centers, radii, return_bound=False):
        count, dim = box_lower.shape
        if len(centers) == 0:
            table = np.zeros((count, 0), dtype=np.int64)
            return (table, np.asarray(reach, dtype=np.float64).copy()) if return_bound else table
        middles = (box_lower + box_upper) / 2
        half_diagonals = np.linalg.norm(box_upper - box_lower, axis=1) / 2
        hits, bounds = [], []
        for part in _chunks(count, len(centers) * dim):
            # Distance from each sphere to each box, and to the box's centre.
            below = box_lower[part, None, :] - centers
            above = centers - box_upper[part, None, :]
            outside = np.maximum(np.maximum(below, above), 0.0)
            box_gap = np.sqrt(np.einsum("nmd,nmd->nm", outside, outside)) - radii
            offsets = middles[part, None, :] - centers
            centre_gap = np.sqrt(np.einsum("nmd,nmd->nm", offsets, offsets)) - radii
            # No point of the box is farther than half a diagonal from the centre, so its
            # clearance is below the centre's gap to any sphere plus that: a tighter reach.
            bound = np.minimum(reach[part], centre_gap.min(axis=1) + half_diagonals[part])
            hits.append(box_gap <= bound[:, None])
            bounds.append(bound)
        hits = np.concatenate(hits)
        width = int(hits.sum(axis=1).max())
        neighbours = np.full((count, width), len(centers), dtype=np.int64)
        rows, columns = np.nonzero(hits)
        # Rank of each hit within its row: its slot in the padded table.
        starts = np.searchsorted(rows, np.arange(count))
        neighbours[rows, np.arange(len(rows)) - starts[rows]] = columns
        return (neighbours, np.concatenate(bounds)) if return_bound else neighbours

    def touched(self, points, clearance, new_centers, new_radii):
        nearest = np.full(len(points), -1, dtype=np.int64)
        gap_min = np.array(clearance, dtype=np.float64)
        for part in _chunks(len(new_centers), len(points) * points.shape[1]):
            offsets = points[:, None, :] - new_centers[part]
            gaps = np.sqrt(np.einsum("nkd,nkd->nk", offsets, offsets)) - new_radii[part]
            best = np.argmin(gaps, axis=1)  # the first of equals, and chunks come in order
            gap = gaps[np.arange(len(points)), best]
            closer = gap < gap_min
            nearest[closer], gap_min[closer] = part.start + best[closer], gap[closer]
        return nearest
