"""Pairs of spheres that may come within a margin of each other, found in a sorted uniform grid.

This is the common path of the fast mode's conflict check
(:func:`ndpack.drivers.greedy.conflicts.disjoint_greedy`: no period, 1-D to 3-D, not crowded). The
spheres are numbered by the cell of side ``(2 * cut + margin) * SIDE`` that holds their centre
(``cut``: the largest radius but a few), along the first axis, then the second, then the third,
and sorted by that number (a radix sort), so that a cell is a run of spheres, a row of cells
along the first axis a run of cells, and memory follows the spheres however far apart they lie.
Each sphere meets those after it in its own cell and the next, and those of the 3 cells around
its own along the first axis in each of the rows after its own (4 in 3-D: the next row, and the 3
of the next layer around its own; 1 in 2-D; none in 1-D), so each pair is examined once; as the
spheres go in order the place of each of those rows only moves on, and is found by walking there.
A sphere larger than ``cut`` is left to :meth:`Grid.pairs_with`, which visits the rows within its
reach (a binary search in each), or every sphere where those rows are more.

A pair ``(i, j)`` is listed where ``|c_i - c_j|**2 <= ((r_i + r_j + margin) * WIDEN)**2``: a
superset of the pairs that come within ``margin`` (``|c_i - c_j| - r_i - r_j < margin``, the
driver's ``_meet``, in float64), as ``WIDEN`` is far above the rounding of either side
(``margin >= 0``, radii >= 0). The driver's own formula then decides each listed pair. No pair
is lost to the cells: a cell's place along an axis is ``floor((x - lower) / side)``, monotone in
``x`` and off by at most 2**-21 cells where coordinates are at most 2**30 cells from 0
(:func:`grid` refuses the rest); two spheres of radii at most ``cut`` that are listed are at most
``side / SIDE * WIDEN`` apart along an axis, 2**-17 of a cell short of a side, so their cells
differ by at most one along each axis; the cells a larger sphere visits cover its reach widened
by 2**-20 of itself and 2**-20 of a cell.

Hand-written, as SciPy's ``cKDTree`` measured too slow for this hot path (the figures are in
:func:`ndpack.drivers.greedy.conflicts._greedy_on_grid`): on 2 cores the largest call of a
200,000-sphere packing of the cube, 65,536 candidates, took 35 ms through the k-d tree, 5.4 ms
here. Serial: a parallel scan gained little on 2 cores for more to compile. Compiling takes
2.3 s, once a machine; a new process loads the code from
Numba's disk cache in 0.16 s (and imports Numba in 0.12 s).
"""

from __future__ import annotations

import functools
import math

import numpy as np

from .. import compile_ahead as ahead

#: A pair is listed within this factor of the distance at which it meets: far above the rounding
#: of a distance or a sum of radii (2**-52 of themselves), so no pair that meets is left out.
WIDEN = 1.0 + 2.0**-30
#: A cell's side over the farthest two listed spheres of radii at most ``cut`` may be apart:
#: 2**-16 longer, so that rounding never puts such a pair two cells apart.
SIDE = 1.0 + 2.0**-16
#: Coordinates at most this many cells from 0, so that a place in cells rounds by under 2**-21.
FARTHEST = 2.0**30
#: Most bits of a cell's number (its place along each axis, in as many bits as that axis needs),
#: so that it and the sums of the scans fit an int64, under the end mark ``2**62``.
MAX_BITS = 60
#: Relative and absolute (in cells) widening of a visiting sphere's reach over the rows it visits.
SLACK = 2.0**-20
#: Bits of a cell's number the radix sort takes a pass: 8,192 counters.
DIGIT = 13
#: The rows :func:`_scan` visits from a cell: its own, then those after it (steps along the second
#: and third axes).
FORWARD = ((0, 0), (1, 0), (-1, 1), (0, 1), (1, 1))


def grid(centers, radii, margin, cut):
    """The grid of the spheres ``centers`` (k, d) float64, ``radii`` (k,) float64 (kept, not
    copied), for the pairs that come within ``margin`` (>= 0) among those of radii at most
    ``cut``. None where the grid does not apply: another dimension or dtype, a negative or
    non-finite value, no reach (``2 * cut + margin == 0``), or cells too small for the spread of
    the centres (more than 2**21 along an axis or 2**60 in all, or coordinates more than 2**30 cells
    from 0)."""
    if centers.ndim != 2 or not 1 <= centers.shape[1] <= 3 or centers.dtype != np.float64 \
            or radii.dtype != np.float64 or len(radii) == 0 or len(radii) != len(centers):
        return None
    margin, cut = float(margin), float(cut)
    side = (2 * cut + margin) * SIDE
    if not (math.isfinite(side) and side > 0 and margin >= 0):
        return None  # NaN fails each comparison
    centers, radii = np.ascontiguousarray(centers), np.ascontiguousarray(radii)
    build, _, _ = _kernels()
    keys, order, lower, shape, shifts = build(centers, radii, side)
    if keys is None:
        return None
    return Grid(centers, radii, keys, order, lower, shape, shifts, side, margin, cut)


class Grid:
    """Spheres sorted by their cells (:func:`grid`): ``keys`` (k + 1,) int64 the cells' numbers,
    ascending (each axis's place from bit ``shifts[axis]`` up), then one past them all; ``order``
    (k,) int64 the spheres' positions among ``centers`` and ``radii``, in that order; the grid's
    corner ``lower`` (d,), its cells ``shape`` (3,) an axis, their ``side``."""

    def __init__(self, centers, radii, keys, order, lower, shape, shifts, side, margin, cut):
        self.centers, self.radii, self.keys, self.order = centers, radii, keys, order
        self.lower, self.shape, self.shifts, self.side, self.margin, self.cut = lower, shape, shifts, side, margin, cut

    def count_near(self, ids, reach, limit):
        """How many centres lie within ``reach`` of those of spheres ``ids`` (p,) int64 (``|c_i -
        c_j|**2 <= reach**2``, a sphere itself included), summed, counted no further once above
        ``limit``."""
        _, _, around = _kernels()
        none = np.empty(0, dtype=np.int64)
        return int(around(*self._table(), ids, float(reach), True, int(limit), none, none))

    def pairs(self):
        """The pairs of spheres of radii at most ``cut`` that may meet: (first, second) (p,) int64,
        first < second."""
        _, scan, _ = _kernels()
        return _listed(lambda first, second: scan(self.centers, self.radii, self.keys, self.order, self.shape,
                                                  self.shifts, self.margin, self.cut, first, second),
                       2 * len(self.order) + 64)

    def pairs_with(self, ids):
        """The pairs of spheres ``ids`` (q,) int64 and spheres of radii at most ``cut``, and of two
        of ``ids``, that may meet: (first, second) (p,) int64, the smaller position first (a
        sphere among ``ids`` of radius at most ``cut`` pairs with itself)."""
        _, _, around = _kernels()
        return _listed(lambda first, second: around(*self._table(), ids, self.cut + self.margin, False, 0, first,
                                                    second), 4 * len(ids) + 64)

    def _table(self):
        return (self.centers, self.radii, self.keys, self.order, self.lower, self.shape, self.shifts, self.side,
                self.margin)


def _listed(run, room):
    """The pairs ``run(first, second)`` writes (it returns how many it found, writing the first
    ``len(first)``): run again with room for all where ``room`` was short."""
    first, second = np.empty(room, dtype=np.int64), np.empty(room, dtype=np.int64)
    found = run(first, second)
    if found > room:
        first, second = np.empty(found, dtype=np.int64), np.empty(found, dtype=np.int64)
        run(first, second)
    return first[:found], second[:found]


#: The compile helper's job that compiles the grid's kernels (:func:`compile_ahead`).
AHEAD_JOB = "numba: the conflict check's grid"


def ahead_jobs() -> list:
    """The compile helper's job for the grid's kernels (:mod:`ndpack.compile_ahead`), where Numba's
    disk cache lacks them (else none): a first packing's check then waits for the helper, if at
    all, instead of compiling them."""
    return ahead.job_unless_on_disk(_around, AHEAD_JOB, 2.5, f"{__name__}:warm_up", [])


def warm_up() -> None:
    """Compile (or load) the grid's kernels by running them on a few spheres, with the argument
    types a packing's conflict check passes: the compile helper's job."""
    rng = np.random.default_rng(0)
    found = grid(rng.random((50, 3)), np.full(50, 0.04), 0.0, 0.04)
    ids = np.arange(3, dtype=np.int64)
    found.pairs()
    found.pairs_with(ids)
    found.count_near(ids, 0.1, 10)


@functools.cache
def _kernels():
    """``_build``, ``_scan`` and ``_around`` compiled by Numba (imported at the first check, so
    ``import ndpack`` stays light), or loaded from disk where a compile helper compiled them."""
    ahead.wait(AHEAD_JOB)
    import numba

    from ..log import numba_functions

    # 2.4-2.6 s on 2 cores, the first time: said, like every compile a user waits for.
    numba_functions(__name__, "the conflict check's grid", 2.5)
    global _meets, _first_at
    _meets = numba.njit(cache=True, inline="always")(_meets)  # compiled first: the kernels call them
    _first_at = numba.njit(cache=True)(_first_at)
    return numba.njit(cache=True)(_build), numba.njit(cache=True)(_scan), numba.njit(cache=True)(_around)


def _build(centers, radii, side):
    """The spheres sorted by their cells' numbers (a radix sort): ``keys``, ``order``, ``lower``,
    ``shape``, ``shifts`` (see :class:`Grid`); ``keys`` None where the grid does not apply
    (:func:`grid`)."""
    count, dim = centers.shape
    lower, upper = centers[0].copy(), centers[0].copy()
    check = 0.0  # NaN where a value is not finite
    least = radii[0]
    for i in range(count):
        for k in range(dim):
            lower[k] = min(lower[k], centers[i, k])
            upper[k] = max(upper[k], centers[i, k])
            check += centers[i, k] * 0.0
        check += radii[i] * 0.0
        least = min(least, radii[i])
    shape = np.ones(3, dtype=np.int64)
    shifts = np.zeros(3, dtype=np.int64)
    fits = math.isfinite(check) and least >= 0.0
    for k in range(dim):
        cells = np.floor((upper[k] - lower[k]) / side) + 1.0
        fits = fits and max(-lower[k], upper[k]) <= FARTHEST * side and cells <= 2.0**21
        if fits:
            shape[k] = int(cells)
    for k in range(3):  # each axis's place in as many bits as it needs
        bits = 0
        while (shape[k] - 1) >> bits:
            bits += 1
        if k < 2:
            shifts[k + 1] = shifts[k] + bits
    bits += shifts[2]
    if not fits or bits > MAX_BITS:
        return None, None, lower, shape, shifts
    keys = np.empty(count + 1, dtype=np.int64)
    for i in range(count):
        key = 0
        for k in range(dim):
            key |= min(int((centers[i, k] - lower[k]) / side), shape[k] - 1) << shifts[k]
        keys[i] = key
    keys[count] = 1 << 62  # past every cell: the scans stop there
    order = np.arange(count)
    spare_keys, spare_order = keys.copy(), np.empty(count, dtype=np.int64)
    passes = (bits + DIGIT - 1) // DIGIT
    digit = (bits + passes - 1) // passes if passes else 1
    mask = (1 << digit) - 1
    for shift in range(0, passes * digit, digit):
        starts = np.zeros((1 << digit) + 1, dtype=np.int64)
        for i in range(count):
            starts[((keys[i] >> shift) & mask) + 1] += 1
        for b in range(1 << digit):
            starts[b + 1] += starts[b]
        for i in range(count):
            b = (keys[i] >> shift) & mask
            spare_keys[starts[b]] = keys[i]
            spare_order[starts[b]] = order[i]
            starts[b] += 1
        keys, spare_keys = spare_keys, keys
        order, spare_order = spare_order, order
    return keys, order, lower, shape, shifts


def _first_at(keys, key):
    """The first place in ``keys`` (ascending) whose number is at least ``key``."""
    begin, end = 0, len(keys)
    while begin < end:
        middle = (begin + end) // 2
        if keys[middle] < key:
            begin = middle + 1
        else:
            end = middle
    return begin


def _meets(centers, radii, i, j, margin):
    """Whether spheres ``i`` and ``j`` may meet (listed)."""
    squared = 0.0
    for k in range(centers.shape[1]):
        delta = centers[j, k] - centers[i, k]
        squared += delta * delta
    near = (radii[i] + radii[j] + margin) * WIDEN
    return squared <= near * near


def _scan(centers, radii, keys, order, shape, shifts, margin, cut, first, second):
    """List the pairs of spheres of radii at most ``cut`` that may meet, each pair once (the module
    docstring). Returns how many (the first ``len(first)`` written)."""
    count = len(order)
    along, across = (1 << shifts[1]) - 1, (1 << (shifts[2] - shifts[1])) - 1
    rows = np.zeros(len(FORWARD), dtype=np.int64)  # where each row visited begins, or before
    found = 0
    for p in range(count):
        i = order[p]
        if radii[i] > cut:
            continue
        key = keys[p]
        c0, c1, c2 = key & along, (key >> shifts[1]) & across, key >> shifts[2]
        for r in range(len(FORWARD)):
            if r == 0:  # its own row: the spheres after it in its cell and the next
                q, high = p + 1, key + 1 if c0 + 1 < shape[0] else key
            else:
                n1, n2 = c1 + FORWARD[r][0], c2 + FORWARD[r][1]
                if n1 < 0 or n1 >= shape[1] or n2 >= shape[2]:
                    continue
                base = (n1 << shifts[1]) | (n2 << shifts[2])
                low, high = base + max(c0 - 1, 0), base + min(c0 + 1, shape[0] - 1)
                q = rows[r]  # as the spheres go in order, the row's place only moves on
                q += keys[q] < low  # most often a step or two: without a branch
                q += keys[q] < low
                while keys[q] < low:
                    q += 1
                rows[r] = q
            while keys[q] <= high:
                j = order[q]
                if radii[j] <= cut and _meets(centers, radii, i, j, margin):
                    if found < len(first):
                        first[found], second[found] = min(i, j), max(i, j)
                    found += 1
                q += 1
    return found


def _around(centers, radii, keys, order, lower, shape, shifts, side, margin, ids, extra, count_only, limit, first,
            second):
    """For each of spheres ``ids`` (p,), the spheres within its reach: with ``count_only``, how many
    centres lie within ``extra`` of its own (``|c_i - c_j|**2 <= extra**2``), summed and counted
    no further once above ``limit``; else, within ``radii[i] + extra``, the pairs that may meet,
    and the pairs of two of ``ids`` that may meet, the smaller position first. Returns how many
    (the first ``len(first)`` pairs written)."""
    count, dim = centers.shape
    low = np.zeros(3, dtype=np.int64)
    high = np.zeros(3, dtype=np.int64)
    found = 0
    for i in ids:
        reach = extra if count_only else radii[i] + extra
        within = reach * (1.0 + SLACK) / side + SLACK  # in cells
        rows = 1.0
        for k in range(dim):
            u = (centers[i, k] - lower[k]) / side
            a, b = max(0.0, np.floor(u - within)), min(shape[k] - 1.0, np.floor(u + within))
            if a > b:
                rows = 0.0
                break
            low[k], high[k] = int(a), int(b)
            if k:
                rows *= b - a + 1.0
        if rows == 0.0:
            continue
        every = rows > count  # more rows than spheres: every sphere, once
        if every:
            low[1:], high[1:] = 0, 0
        for c2 in range(low[2], high[2] + 1):
            for c1 in range(low[1], high[1] + 1):
                begin, end = 0, count
                if not every:
                    base = (c1 << shifts[1]) | (c2 << shifts[2])
                    begin = end = _first_at(keys, base + low[0])
                    while keys[end] <= base + high[0]:
                        end += 1
                for q in range(begin, end):
                    j = order[q]
                    if count_only:
                        squared = 0.0
                        for k in range(dim):
                            delta = centers[j, k] - centers[i, k]
                            squared += delta * delta
                        found += squared <= reach * reach
                    elif _meets(centers, radii, i, j, margin):
                        if found < len(first):
                            first[found], second[found] = min(i, j), max(i, j)
                        found += 1
        if count_only and found > limit:
            return found
    for a in range(0 if count_only else len(ids)):
        for b in range(a + 1, len(ids)):
            i, j = ids[a], ids[b]
            if _meets(centers, radii, i, j, margin):
                if found < len(first):
                    first[found], second[found] = min(i, j), max(i, j)
                found += 1
    return found
