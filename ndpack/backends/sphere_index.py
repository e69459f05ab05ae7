"""A spatial index of the inserted spheres, for radii that span many orders of magnitude.

A greedy packing's radii run from a third of the shape down to a millionth of it, so no single
grid suits them. The index keeps one hashed grid per octave of radius: level ``l`` has cells of
side ``top / 2**l`` and holds the spheres of radius a third to a sixth of that, each in the cell
of its centre. A query for the spheres near a box visits, per level that holds any sphere, the
cells within reach of the box (skipping the window's corners, farther than that: most of its cells
from 4-D up), or the level's whole list when that is shorter (the few largest spheres, or a level
with fewer spheres than cells to visit). Work per query is then bounded by what is near
the box, not by the packing's size.

Buckets are singly linked lists threaded through the sphere ids (``heads`` per bucket, ``next``
per sphere), so inserting a sphere is O(1) and spheres are never moved. The kernels are the
functions ``index_*`` of :mod:`ndpack.backends.index_kernels` (written once, printed for each
compiled backend) and the store's :mod:`ndpack.backends.store_kernels`. The host builds the
index of the CPU backends (:class:`SphereIndex`); a GPU builds its own (:class:`DeviceIndex`).

SciPy's k-d tree answers the same questions, but it cannot be called from inside a Numba (or
CUDA) kernel, where the queries run next to the prototype's work, and it cannot grow: a rebuild
per round costs 0.39 s at 1,000,000 spheres (measured on the 2-core machine), against the few
hundred rounds a million-sphere packing takes.
"""

from __future__ import annotations

import numpy as np

#: Octaves of radius the index tells apart: from ``top`` down to ``top / 2**47``.
LEVELS = 48


def owner(array: np.ndarray) -> np.ndarray:
    """The array that owns ``array``'s memory (itself, or the base of a view): the driver passes
    views of its growing sphere buffers, so two calls on one packing share it, and a call on
    other spheres (another run, another tile's obstacles) does not, whatever their values."""
    while isinstance(array.base, np.ndarray):
        array = array.base
    return array


def extends(centers: np.ndarray, count: int, buffer, first, last) -> bool:
    """Whether ``centers`` (m, d) extend the ``count`` rows indexed before: views of the same
    buffer (:func:`owner`), at least as long, with the same first and last indexed rows (a buffer
    refilled in place would change them). The values alone are not enough: two lists of spheres
    can share their first sphere and the one at ``count - 1`` and differ between them."""
    return (buffer is not None and owner(centers) is buffer and len(centers) >= count
            and (count == 0 or (np.array_equal(centers[0], first) and np.array_equal(centers[count - 1], last))))


class SphereIndex:
    """The index over a growing prefix of the driver's sphere arrays.

    Parameters
    ----------
    insert : callable
        The compiled ``index_insert_range(start, stop, centers, radii, *self.arrays)``.
    """

    def __init__(self, insert):
        self.insert = insert
        self.count = 0
        self.first = self.last = None
        self.buffer = None  # the owner of the arrays indexed (see owner())
        self.arrays = None

    def _reset(self, centers, radii, capacity):
        dim = centers.shape[1]
        buckets = 1 << int(np.ceil(np.log2(max(2 * capacity, 64))))
        # The coarsest cells are four times the largest radius seen so far; later larger spheres
        # still go to level 0, whose largest radius every query allows for.
        top = 4.0 * float(radii.max()) if len(radii) and radii.max() > 0 else 1.0
        self.arrays = (
            np.zeros(dim),                          # origin
            top,                                    # top
            np.full(buckets, -1, dtype=np.int64),   # heads
            np.full(capacity, -1, dtype=np.int64),  # next
            np.zeros(capacity, dtype=np.int64),     # level_of
            np.full(LEVELS, -1, dtype=np.int64),    # level_head
            np.full(capacity, -1, dtype=np.int64),  # level_next
            np.zeros(LEVELS, dtype=np.int64),       # level_count
            np.zeros(LEVELS),                       # level_rmax
        )
        self.count = 0

    @property
    def capacity(self) -> int:
        return 0 if self.arrays is None else len(self.arrays[3])

    def sync(self, centers: np.ndarray, radii: np.ndarray):
        """Index ``centers`` (m, d) float64 and ``radii`` (m,) float64; only new rows are inserted
        when the arrays extend the ones indexed before (:func:`extends`)."""
        count = len(radii)
        same_prefix = (self.arrays is not None and centers.shape[1] == len(self.arrays[0])
                       and extends(centers, self.count, self.buffer, self.first, self.last))
        self.buffer = owner(centers)
        if not same_prefix or count > self.capacity:
            self._reset(centers, radii, max(64, 2 * count))
        if count > self.count:
            self.insert(self.count, count, centers, radii, *self.arrays)
            self.count = count
            self.first, self.last = centers[0].copy(), centers[count - 1].copy()
        return self.arrays


class DeviceIndex:
    """A :class:`SphereIndex` built and kept on a GPU, for the device kernels' queries
    (``index_near``) over spheres already on the device.

    The device inserts the new spheres of each sync in one launch (``index_insert_range``,
    through atomics), so nothing but the launch crosses from the host: a host-built index cost a
    serial insert a sphere and a copy of every bucket head a sync (millions at a million spheres,
    several times a round): 1.3 s of a million-sphere packing of the armadillo on an H200
    (``bash bench/gpu_issue48_step5.sh host`` at 49cef62). The lists' order then follows the
    atomics: no query depends on it (a query's answers are sets, its nearest sphere the lowest id
    among equals).

    Parameters
    ----------
    dim : int
    device : object
        The store's device adapter: ``upload(host, kind)``, ``empty(shape, kind)`` and
        ``launch(kernel_name, threads, *args)`` with the kernels ``index_clear`` and
        ``index_insert_range``.
    """

    def __init__(self, dim: int, device):
        self.dim, self.device = dim, device
        self.arrays = None  # device arrays in SphereIndex.arrays order (``top`` a float)
        self.count = self.capacity = self.buckets = 0
        self.first = self.last = None
        self.buffer = None  # the owner of the host arrays indexed (see owner())

    def sync(self, centers: np.ndarray, radii: np.ndarray, d_centers, d_radii) -> list:
        """The device arrays of the index of ``centers`` (m, d) and ``radii`` (m,) float64, whose
        device copies are ``d_centers`` and ``d_radii`` (at least m rows); only new rows are
        inserted when the arrays extend the ones indexed before (:func:`extends`)."""
        count = len(radii)
        same_prefix = self.arrays is not None and extends(centers, self.count, self.buffer, self.first, self.last)
        self.buffer = owner(centers)
        if not same_prefix or count > self.capacity:
            self._reset(radii, max(64, 2 * count))
        if count > self.count:
            self.device.launch("index_insert_range", count - self.count, self.count, d_centers, d_radii,
                               *self.arrays)
            self.count = count
            self.first, self.last = centers[0].copy(), centers[count - 1].copy()
        return self.arrays

    def _reset(self, radii, capacity):
        """An empty index for ``capacity`` spheres, its coarsest cells four times the largest of
        ``radii`` (as :class:`SphereIndex`); the arrays are kept where they are large enough."""
        buckets = 1 << int(np.ceil(np.log2(max(2 * capacity, 64))))
        top = 4.0 * float(radii.max()) if len(radii) and radii.max() > 0 else 1.0
        if self.arrays is None or capacity > self.capacity or buckets > self.buckets:
            empty = self.device.empty
            self.arrays = [
                self.device.upload(np.zeros(self.dim), "float"),  # origin
                top,
                empty(buckets, "index"),   # heads
                empty(capacity, "index"),  # next
                empty(capacity, "index"),  # level_of
                empty(LEVELS, "index"),    # level_head
                empty(capacity, "index"),  # level_next
                empty(LEVELS, "index"),    # level_count
                empty(LEVELS, "float"),    # level_rmax
            ]
            self.capacity, self.buckets = capacity, buckets
        self.arrays[1] = top
        heads, level_head, level_count, level_rmax = (self.arrays[i] for i in (2, 5, 7, 8))
        self.device.launch("index_clear", max(self.buckets, LEVELS), heads, level_head, level_count, level_rmax)
        self.count = 0
