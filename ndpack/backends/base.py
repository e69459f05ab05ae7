"""The small interface between the packing driver and the code that runs its hot loops.

A backend sees plain arrays and an oracle; it holds no packing state. The driver
(:mod:`ndpack.drivers.greedy.protosphere`) decides what to move, what to insert and when to stop; the backend
moves prototypes, measures clearances and finds the spheres near a box. Subclasses import their
framework lazily and raise :class:`~ndpack.errors.BackendError` with an install hint when it is
missing.

Vocabulary
----------
clearance
    Distance from a point to the nearest obstacle, i.e. the shape's boundary or an inserted
    sphere; positive in free space. A sphere of that radius around the point is free.
neighbours
    ``(n, k)`` int64 indices of the spheres that can be nearest to each prototype, padded at the end with
    ``len(centers)``, an index the backend maps to a sphere at infinity.
"""

from __future__ import annotations

import numpy as np

from .prototypes import HostPrototypes, best_starts


class Backend:
    """Base class: the operations the ProtoSphere driver needs, on NumPy arrays in and out."""

    name = "base"
    #: Whether a launch costs about as long as its slowest item, however many items it has (a GPU):
    #: the fast mode then does work ahead in lanes a launch would leave idle (``rounds.POLISH_AHEAD``).
    launch_bound = False

    def distance(self, shape, points) -> np.ndarray:
        """The shape's signed distance at ``points`` (n, d), evaluated by this backend: (n,) float64.

        What a user measures a backend's oracle speed with; the packing loops call the shape's
        kernel inside their own kernels instead.
        """
        return shape._distance(np.ascontiguousarray(points, dtype=np.float64))

    def clearance(self, shape, points, centers, radii, neighbours) -> np.ndarray:
        """Clearance of each point.

        Parameters
        ----------
        shape : Oracle
        points : (n, d) float64
        centers : (m, d) float64 and radii : (m,) float64
            The inserted spheres.
        neighbours : (n, k) int64
            Candidate spheres per point, padded with ``m``.

        Returns
        -------
        (n,) float64
        """
        return self._free_space(shape, points, centers, radii, neighbours, directions=False)[0]

    def free_space(self, shape, points, centers, radii, neighbours):
        """Clearance (n,) and the direction (n, d) away from each point's nearest obstacle.

        The direction is ``-grad`` of the shape's distance where the boundary is nearest (unit
        for an exact distance), else the unit vector from the nearest sphere's centre. Arguments
        as in :meth:`clearance`.
        """
        return self._free_space(shape, points, centers, radii, neighbours, directions=True)

    def _free_space(self, shape, points, centers, radii, neighbours, directions):
        """What :meth:`clearance` and :meth:`free_space` run: with ``directions=False`` the
        direction array may have no rows, which spares the compiled backends that work."""
        raise NotImplementedError

    def converge(self, shape, points, cell_lower, cell_upper, centers, radii, neighbours, steps, wall=None,
                 starts=None):
        """Move each prototype ``p <- p + eps * (p - q)`` away from its nearest obstacle point ``q``.

        Parameters
        ----------
        points, cell_lower, cell_upper : (n, d) float64
            Prototypes and the boxes of their grid cells, which confine them.
        centers, radii, neighbours :
            As in :meth:`clearance`.
        steps : (T,) float64
            The cooling schedule: ``eps`` of each iteration.
        wall : (n,) float64, optional
            A lower bound of the boundary's distance at each cell's centre. Where a sphere is
            nearer than ``wall - |x - centre|``, the boundary cannot be nearest and the shape's
            distance is not evaluated: the same result, faster deep inside. None: always evaluate.
        starts : (t, n, d) float64, optional
            Restart points: each prototype starts from the first of its point and its starts with
            the largest clearance.

        Returns
        -------
        points : (n, d) float64
            Converged positions.
        clearance : (n,) float64
            Their clearances.
        """
        raise NotImplementedError

    def _best_of_starts(self, shape, points, starts, centers, radii, neighbours):
        """:meth:`converge`'s starting points, for backends that choose them apart from converging."""
        if starts is None or len(starts) == 0:
            return points
        return best_starts(self, shape, np.concatenate([points[None], starts]), centers, radii, neighbours)[0]

    def near_spheres(self, box_lower, box_upper, reach, centers, radii, return_bound=False):
        """Spheres whose surface comes within ``reach`` of each box.

        Parameters
        ----------
        box_lower, box_upper : (n, d) float64
        reach : (n,) float64
            Upper bound of the clearance of any point of the box.
        centers : (m, d) float64 and radii : (m,) float64

        return_bound : bool
            Also return the tightened reach: no point of a box is farther than half its diagonal
            from its centre, so its clearance is below the centre's gap to any sphere plus that.

        Returns
        -------
        (n, k) int64
            Indices per box, padded with ``m``; the spheres within the tightened reach.
        (n,) float64
            The tightened reach, with ``return_bound``: a clearance bound for the stored cells.
        """
        raise NotImplementedError

    def tightened_reach(self, box_lower, box_upper, reach, centers, radii) -> np.ndarray:
        """The reach (n,) float64 of each box tightened by the spheres, as :meth:`near_spheres`
        returns it with ``return_bound``, without the table (backends may skip building it)."""
        return self.near_spheres(box_lower, box_upper, reach, centers, radii, return_bound=True)[1]

    def touched(self, points, clearance, new_centers, new_radii) -> np.ndarray:
        """Which prototypes the new spheres (k, d), (k,) touch, and the nearest that does.

        Returns (n,) int64: per prototype (``points`` (n, d), ``clearance`` (n,)), the new sphere
        of smallest gap ``|p - c| - r`` (the first of equals) where that gap is below its
        clearance (its clearance ball meets the sphere), else -1. The driver restarts a touched
        prototype just outside that sphere.
        """
        raise NotImplementedError

    def prototypes(self, shape, cell_lower, cell_upper, reach, points, clearance, wall=None):
        """The driver's prototype store (:mod:`ndpack.backends.prototypes`), in this backend's memory.

        CPU backends keep it on the host; GPU backends override this to keep it on their device.
        Arguments as in :class:`~ndpack.backends.prototypes.Prototypes`.
        """
        return HostPrototypes(self, shape, cell_lower, cell_upper, reach, points, clearance, wall)

    def __repr__(self) -> str:
        return f"<ndpack backend {self.name!r}>"


def tightened_reach(box_lower, box_upper, reach, centers, radii, table) -> np.ndarray:
    """The reach :meth:`Backend.near_spheres` returns, from its table (n, k): (n,) float64.

    Every sphere that tightens a box's reach is within it of the box, so it is in the table.
    """
    middles = 0.5 * (box_lower + box_upper)
    half = 0.5 * np.linalg.norm(box_upper - box_lower, axis=1)
    padded_centers = np.vstack([centers, np.full((1, centers.shape[1]), np.inf)])
    padded_radii = np.append(radii, 0.0)
    gaps = np.linalg.norm(middles[:, None, :] - padded_centers[table], axis=2) - padded_radii[table]
    return np.minimum(reach, gaps.min(axis=1, initial=np.inf) + half)


#: Rows of a pinned host buffer at first (see :func:`staging_rows`): a round's answers reach tens
#: of thousands of rows, and every regrowth frees pinned memory, which waits for the device.
FIRST_STAGING_ROWS = 1 << 16


def staging_rows(current: int, need: int) -> int:
    """Rows of a pinned host buffer that must hold ``need`` rows and holds ``current`` (0: none
    yet): at least twice ``current`` (``FIRST_STAGING_ROWS`` at first), because freeing pinned
    memory waits for the device (116 regrowths took 0.33 s of a 4.5 s packing on an H100 when each
    grew to the need alone; starting at 256 rows, 81 regrowths still took 0.17 s of 2.9 s)."""
    return max(need, 2 * current if current else FIRST_STAGING_ROWS)
