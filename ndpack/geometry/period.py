"""Periodic domains: which axes of a box wrap around, and the geometry of images across them.

A periodic axis of a cell ``lower <= x < upper`` identifies ``x`` with ``x + k * (upper - lower)``
for every integer ``k``. A sphere then also stands at each of its *images* (its centre moved by
whole periods), and two spheres overlap when any images of them do. The driver keeps the images
of each sphere that come near the cell as extra obstacles (``images``), so that every backend
kernel sees a periodic packing as an ordinary one; the host's checks measure the nearest image
(``difference``) and search a k-d tree that wraps (``frame`` and SciPy's ``boxsize``).
"""

from __future__ import annotations

import numpy as np

from ..errors import ParameterError


class Period:
    """The periodic axes of a cell.

    Parameters
    ----------
    lower, upper : (d,) float64
        The cell's corners; along a periodic axis the period is ``upper - lower``.
    axes : (d,) bool
        Which axes are periodic (at least one).
    """

    def __init__(self, lower, upper, axes):
        self.lower = np.asarray(lower, dtype=np.float64)
        self.upper = np.asarray(upper, dtype=np.float64)
        self.axes = np.asarray(axes, dtype=bool)
        if not self.axes.any():
            raise ParameterError("a periodic domain needs at least one periodic axis")
        self.lengths = np.where(self.axes, self.upper - self.lower, np.inf)

    @property
    def dim(self) -> int:
        return len(self.axes)

    @property
    def shortest(self) -> float:
        """The shortest period: no sphere may be wider than it (it would meet its own image)."""
        return float(self.lengths.min())

    @property
    def periods(self) -> list:
        """Each axis's period, None where the axis is not periodic (the form files record)."""
        return [float(length) if periodic else None for length, periodic in zip(self.lengths, self.axes)]

    def wrap(self, points: np.ndarray) -> np.ndarray:
        """``points`` (n, d) with each periodic coordinate moved by whole periods into
        ``[lower, upper)``; (n, d) float64."""
        points = np.array(points, dtype=np.float64)
        for axis in np.flatnonzero(self.axes):
            low, length = self.lower[axis], self.lengths[axis]
            wrapped = low + np.mod(points[:, axis] - low, length)
            points[:, axis] = np.where(wrapped >= self.upper[axis], low, wrapped)  # a rounding of mod up to it
        return points

    def difference(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """``a - b`` (n, d) between the nearest images: each periodic component within half a period."""
        delta = np.asarray(a, dtype=np.float64) - np.asarray(b, dtype=np.float64)
        for axis in np.flatnonzero(self.axes):
            length = self.lengths[axis]
            delta[..., axis] -= length * np.round(delta[..., axis] / length)
        return delta

    def images(self, centers: np.ndarray, radii: np.ndarray, reach: float):
        """The images of spheres ``centers`` (n, d), ``radii`` (n,) (centres in the cell) that come
        within ``reach`` of the cell: moved by -1, 0 or +1 period along each periodic axis, not
        all 0. Returns their centres (m, d), radii (m,) and the sphere each is an image of (m,).

        A sphere no wider than the shortest period has no other image within a period of the
        cell, and ``reach`` never exceeds half a period (:meth:`shortest`), so no image
        farther than one period can come nearer than ``reach``. Built axis by axis, each step
        keeping only images whose way to the cell so far (the root of the summed squares of
        the axes' excess) is within reach: a sphere deep in the cell makes no work.
        """
        centers = np.asarray(centers, dtype=np.float64)
        radii = np.asarray(radii, dtype=np.float64)
        source = np.arange(len(radii))
        moved = np.zeros(len(radii), dtype=bool)
        excess = np.zeros(len(radii))  # squared distance from the image to the cell so far
        limit = (reach + radii) ** 2
        for axis in np.flatnonzero(self.axes):
            parts = [(centers, source, moved, excess)]
            for shift in (-1.0, 1.0):
                coordinate = centers[:, axis] + shift * self.lengths[axis]
                outside = np.maximum(self.lower[axis] - coordinate, coordinate - self.upper[axis])
                grown = excess + np.maximum(outside, 0.0) ** 2
                near = grown <= limit[source]
                shifted = centers[near].copy()
                shifted[:, axis] = coordinate[near]
                parts.append((shifted, source[near], np.ones(int(near.sum()), dtype=bool), grown[near]))
            centers, source, moved, excess = (np.concatenate(values) for values in zip(*parts))
        return centers[moved], radii[source[moved]], source[moved]

    def frame(self, points: np.ndarray, reach: float):
        """``points`` (n, d) in the frame of a wrapping k-d tree, and its ``boxsize`` (d,): each
        periodic coordinate wrapped into ``[0, period)``; each other one counted from the
        lowest point, in a box so wide (twice the points' extent and ``reach``) that no search
        within ``reach`` wraps around it."""
        frame = self.wrap(points) - np.where(self.axes, self.lower, 0.0)
        boxsize = self.lengths.copy()
        if len(frame):
            low = frame.min(axis=0)
            span = frame.max(axis=0) - low
            free = ~self.axes
            frame[:, free] -= low[free]
            boxsize[free] = 2.0 * (span[free] + reach) + 1.0
        else:
            boxsize[~self.axes] = 1.0
        # SciPy wants every coordinate below the box size: a wrapped point may round up to it.
        return np.minimum(frame, np.nextafter(boxsize, 0.0)), boxsize

    def tree(self, points: np.ndarray, reach: float):
        """A k-d tree of ``points`` (n, d) whose distances are the nearest images', for searches
        within ``reach``; and the points in its frame (n, d), to query it with."""
        from scipy.spatial import cKDTree

        frame, boxsize = self.frame(points, reach)
        return cKDTree(frame, boxsize=boxsize), frame

    def __repr__(self) -> str:
        axes = np.flatnonzero(self.axes).tolist()
        return f"Period(axes={axes}, lengths={self.lengths[self.axes].tolist()})"


def period_of(shape):
    """The :class:`Period` of a periodic shape (:class:`ndpack.Periodic`), None for any other."""
    return getattr(shape, "period", None)
