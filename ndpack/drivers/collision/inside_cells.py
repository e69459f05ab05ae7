"""A grid over a shape's bounds whose cells are known to lie inside, outside or across the boundary.

Coverings draw hundreds of thousands of interior points, and checking each with the oracle is
their main cost when the shape fills a small share of its bounds (the armadillo fills 11%: nine
in ten points drawn in its bounds are thrown away, after the most expensive distance queries,
those far from the surface). A cell whose centre lies farther from the boundary than its half
diagonal lies wholly on one side (this holds for every conservative oracle: a lower bound of the
distance only marks fewer cells). Points drawn in the cells not outside need a distance only in
the boundary cells, and a point's cell is found by index arithmetic.

The grid is refined level by level (each unknown cell splits into ``2**d`` children), so that the
distances evaluated are those of the cells near the boundary, and it stops at the finest level
within :data:`CELLS` cells and :data:`EVALUATIONS` distances per level.
"""

from __future__ import annotations

import math

import numpy as np

from ...errors import ShapeError
from ...oracle import Oracle

#: Cells of the finest grid, at most (one byte each).
CELLS = 2**21
#: Distances evaluated at one level, at most: refinement stops before a level would need more.
EVALUATIONS = 2**18
#: States of a cell.
INSIDE, BOUNDARY, OUTSIDE = -1, 0, 1


class InsideCells:
    """Cells of a regular grid over ``shape.bounds`` (``2**level`` per axis), each marked
    :data:`INSIDE` (wholly inside the shape), :data:`OUTSIDE` or :data:`BOUNDARY` (not known).

    Parameters
    ----------
    shape : Oracle
        A bounded shape.
    cells, evaluations : int
        The finest grid's cells, and the distances one level may evaluate, at most.
    margin : float
        A cell is inside (outside) only if all its points lie deeper than ``margin`` inside
        (outside), and the grid reaches ``margin`` beyond the bounds: then every point within
        ``margin`` of the boundary lies in a boundary cell.

    Attributes
    ----------
    state : (2**level,) * d int8
    lower : (d,) float64
        The grid's lowest corner (the shape's lower bound less the margin).
    size : (d,) float64
        A cell's edge lengths.
    evaluated : int
        Distances the refinement evaluated.
    """

    def __init__(self, shape: Oracle, cells: int = CELLS, evaluations: int = EVALUATIONS, margin: float = 0.0):
        self.shape, self.margin = shape, float(margin)
        lower, upper = (np.asarray(bound, dtype=np.float64) for bound in shape.bounds)
        if not (np.all(np.isfinite(lower)) and np.all(np.isfinite(upper)) and np.all(upper > lower)):
            raise ShapeError(f"{shape!r} has bounds {lower} .. {upper}: empty or unbounded, so there is no inside "
                             "to sample; give the shape finite bounds")
        lower, upper = lower - self.margin, upper + self.margin
        dim = shape.dim
        finest = max(int(math.log2(cells)) // dim, 1)
        state = np.zeros((1,) * dim, dtype=np.int8)
        self.evaluated = 0
        for level in range(finest + 1):
            size = (upper - lower) / 2**level
            unknown = np.argwhere(state == BOUNDARY)
            centers = lower + (unknown + 0.5) * size
            half = 0.5 * float(np.linalg.norm(size)) * (1 + 1e-9) + 1e-12 * shape.scale + self.margin
            distance = shape._distance(centers)
            self.evaluated += len(centers)
            state[tuple(unknown.T)] = np.where(distance < -half, INSIDE,
                                               np.where(distance > half, OUTSIDE, BOUNDARY)).astype(np.int8)
            left = int(np.count_nonzero(state == BOUNDARY))
            if level == finest or left * 2**dim > evaluations:
                break
            for axis in range(dim):  # every cell becomes 2**d children of its state
                state = np.repeat(state, 2, axis=axis)
        self.level, self.state, self.lower, self.size = level, state, lower, size
        self._flat = state.reshape(-1)
        self._open = np.flatnonzero(self._flat <= BOUNDARY)  # cells that may hold inside points
        self._boundary = np.flatnonzero(self._flat == BOUNDARY)
        if not len(self._open):
            raise ShapeError(f"no point of {shape!r}'s bounds is inside it: its distance is positive everywhere "
                             "the grid looked; is it empty, or are its bounds wrong?")

    @property
    def volume_bounds(self) -> tuple[float, float]:
        """The volume of the inside cells and of the cells not outside: the shape's volume lies between."""
        cell = float(np.prod(self.size))
        inside = int(np.count_nonzero(self._flat == INSIDE))
        return inside * cell, len(self._open) * cell

    def classify(self, points) -> np.ndarray:
        """Each point's cell state, (n,) int8: :data:`OUTSIDE` beyond the bounds."""
        points = np.asarray(points, dtype=np.float64)
        index = np.floor((points - self.lower) / self.size).astype(np.int64)
        within = np.all((index >= 0) & (index < self.state.shape[0]), axis=1)
        states = np.full(len(points), OUTSIDE, dtype=np.int8)
        states[within] = self.state[tuple(index[within].T)]
        return states

    def inside(self, points) -> np.ndarray:
        """Which points lie inside the shape, (n,) bool: distances only for those in boundary cells."""
        states = self.classify(points)
        result = states == INSIDE
        unknown = np.flatnonzero(states == BOUNDARY)
        if len(unknown):
            result[unknown] = self.shape._distance(np.asarray(points, dtype=np.float64)[unknown]) < 0
        return result

    def draw(self, count: int, rng: np.random.Generator, boundary: bool = False) -> tuple[np.ndarray, np.ndarray]:
        """``count`` points uniform in the cells not outside (or in the boundary cells only).

        Returns
        -------
        points : (count, d) float64
        sure : (count,) bool
            Which lie in an inside cell (the rest need a distance to tell).
        """
        pool = self._boundary if boundary else self._open
        if not len(pool):
            raise ShapeError(f"no cell of {self.shape!r}'s grid meets its boundary; are its bounds wrong?")
        cells = pool[rng.integers(len(pool), size=count)]
        index = np.column_stack(np.unravel_index(cells, self.state.shape))
        points = self.lower + (index + rng.random((count, self.shape.dim))) * self.size
        return points, self._flat[cells] == INSIDE

    def expected_share(self) -> float:
        """About the share of drawn points that lie inside (boundary cells counted half)."""
        inside = np.count_nonzero(self._flat == INSIDE)
        return float((inside + 0.5 * (len(self._open) - inside)) / len(self._open))

    def interior(self, count: int, rng: np.random.Generator, tries: int = 200) -> np.ndarray:
        """``count`` points uniform in the inside of the shape, (count, d) float64."""
        found, total = [], 0
        batch = max(int(1.3 * count / self.expected_share()), 1024)
        for _ in range(tries):
            points, sure = self.draw(batch, rng)
            unknown = np.flatnonzero(~sure)
            if len(unknown):
                sure[unknown] = self.shape._distance(points[unknown]) < 0
            found.append(points[sure])
            total += int(sure.sum())
            if total >= count:
                return np.vstack(found)[:count]
        raise ShapeError(f"found only {total} of {count} points inside {self.shape!r} in {tries * batch} tries in "
                         "its boundary cells: the shape is almost empty")


__all__ = ["InsideCells", "INSIDE", "BOUNDARY", "OUTSIDE"]
