"""The final check's distances at the spheres' centres, computed while the device works.

The driver's final check (:func:`ndpack.verify`) evaluates the shape's signed distance at every
sphere's centre, in float64 on the host: most of its time (the armadillo at 100,000 spheres, 2
cores: 0.21 s of 0.25 s; the rest finds overlaps). On a GPU a round ends by queueing its longest
launch, the move of the prototypes its spheres touched and of the new cells', and the host then
waits for it; so the round's spheres are looked at there, on the host, while that launch runs
(:meth:`CentreDistances.catch_up`), and the check at the end takes those distances, left with
the overlaps and the last round's spheres. A centre's distance is the same function of the same
point either way, so the verdict is the same.

In a background thread instead, the host's Python (the round's launches) and the distance
queries took turns at the interpreter's lock: a packing of the armadillo at 100,000 spheres waited
0.1-0.2 s at its end for the last batches (an H100 and an H200 lease), more than the check saved.
"""

from __future__ import annotations

import numpy as np


def during_rounds(backend) -> bool:
    """Whether a run on ``backend`` computes its spheres' centre distances while the device
    works: where launches run beside the host (a GPU); on a CPU the launch is the host's work."""
    return bool(getattr(backend, "launch_bound", False))


class CentreDistances:
    """The signed distance of ``shape`` (the one the final check uses) at the centre of every
    sphere placed, in the order they were placed.

    Parameters
    ----------
    shape : Oracle
        The final check's shape.
    compute : bool
        Keep the batches' centres, to compute their distances in :meth:`catch_up` (:func:`during_rounds`);
        otherwise only the batches given with their distances are kept, and :meth:`collect`
        returns None unless every batch was.
    """

    def __init__(self, shape, compute: bool):
        self.shape = shape
        self.compute = compute
        self._batches: list[np.ndarray | None] = []  # one a batch of spheres, in order: distances
        self._waiting: list[tuple[int, np.ndarray]] = []  # (batch, centres (k, d)) not yet computed
        self._count = 0

    def add(self, centers: np.ndarray, known: np.ndarray | None = None) -> None:
        """A batch of spheres placed after those before: ``centers`` (k, d) float64, as stored,
        and their distances (k,) where the caller has them already."""
        if known is not None:
            self._batches.append(np.asarray(known, dtype=np.float64))
        else:
            self._batches.append(None)
            if self.compute and len(centers):
                self._waiting.append((len(self._batches) - 1, np.array(centers, dtype=np.float64)))
        self._count += len(centers)

    def catch_up(self) -> None:
        """Compute the batches waiting, on this thread (in one call to the shape, which a mesh
        spreads over Numba's threads)."""
        if not self._waiting:
            return
        batches, centers = zip(*self._waiting)
        self._waiting = []
        distances = self.shape._distance(np.concatenate(centers))
        start = 0
        for batch, points in zip(batches, centers):
            self._batches[batch] = distances[start : start + len(points)]
            start += len(points)

    def collect(self, count: int) -> np.ndarray | None:
        """The distances (count,) of the first ``count`` spheres placed, or None where one of them
        was not computed."""
        self.catch_up()
        if any(batch is None for batch in self._batches) or self._count < count:
            return None
        distances = np.concatenate(self._batches) if self._batches else np.empty(0)
        return distances[:count]
