"""Pairs of spheres near enough to overlap, found in sorted rows of one grid per octave of radius.

This is :func:`ndpack.verify.overlapping_pairs`'s path for the common case (no period, 1-D to
3-D). The spheres of each octave ``floor(log2(r))`` are cut into rows by a grid of side
``2 * largest + tol`` (``largest``: the octave's largest radius) across the first axis (a row is a
cell of the other axes; in 1-D the octave is one row), and each row is sorted along the first
axis. A table maps a row to its run of spheres: indexed by the row where the octave's box holds
few rows, hashed (open addressing) where tiny spheres are spread far.

Each pair is examined once. In one octave, from the sphere whose row comes first (the rows
around its own, at most 3 an axis, as the reach is a row's side), and within a row from the sphere
first along the axis. Across two octaves, from the small spheres' side (each visits the few rows
of the larger octave's grid around it) or from the large spheres' side (each visits the rows of
the smaller octave's grid within its reach, as the k-d tree path does), whichever visits fewer
rows. In each row a binary search finds the run within reach along the first axis: over the chord
of the ball of reach across that row. The rows share nothing with the driver's sphere index
(:mod:`ndpack.backends.sphere_index`): the check stays independent of the code it checks.

Exact, no pair missed: a pair is examined where the k-d trees of the other path examine it, within
``2 * largest + tol`` in one octave, ``r_i + largest_j + tol`` across octaves (``i`` the larger,
``largest_j`` the largest radius of ``j``'s octave), by the same float64 comparison of squared
distances. The rows and runs visited cover that reach widened by :data:`MARGIN`, far above the
rounding of a distance: each step from a coordinate to a row or a run (subtract, divide, floor,
compare) is monotone, so rounding there cannot lose a partner, and the chords are taken over
bounds with room for their own rounding (:data:`SLACK`). The overlap ``r_i + r_j - |c_i - c_j|``
is computed as NumPy computes it (squares summed in axis order), so the same pairs pass ``> tol``.

Hand-written, as SciPy's ``cKDTree`` measured too slow for this hot path (the last check of every
packing). On a 100,000-sphere packing of the armadillo, 2 cores, median of 5: the k-d tree path
0.23 s (0.18 to 0.24; most of it ``query_ball_point``'s Python lists and the single-threaded
``query_pairs``), this path 0.041 s (0.066 s on one thread), and :func:`ndpack.verify` 0.33 s before,
0.13 s after. Compiling takes 4.2 s, once a machine; a new process loads the code from Numba's
disk cache in 0.27 s (Numba's import included).
"""

from __future__ import annotations

import functools
import math

import numpy as np

from .. import compile_ahead as ahead
from ..parallel import run_in_slices

#: Most rows along an axis of one octave's grid: a row's coordinates are packed into one int64
#: key of :data:`BITS` bits an axis. A finer grid (tiny spheres spread far) returns None, and the
#: caller uses its k-d trees.
MAX_CELLS = 2**20
BITS = 21
#: Relative widening of each reach when choosing rows and runs: far above the rounding of a
#: distance, so no pair the float64 comparison accepts lies where the scan does not look.
MARGIN = 2.0**-30
#: An octave's rows are indexed densely (no hashing) where the box of them holds at most this
#: many per sphere of the octave.
DENSE = 4
#: Slack of a chord (of the ball within reach, across a row), relative to the reach: far above the
#: rounding of a place in rows (2**-31 of the reach or of a row) and of the chord's square root of
#: a difference of squares (2**-25 of the reach).
SLACK = 2.0**-20
#: Below this many spheres the scan runs on one thread.
BLOCK = 64
#: Fibonacci hashing's multiplier, 2**64 / golden ratio, as an int64 (products wrap).
GOLDEN = -7046029254386353131


def overlapping_pairs(centers: np.ndarray, radii: np.ndarray, tol: float = 0.0):
    """Pairs of spheres that overlap by more than ``tol``, and the worst overlap of the near pairs.

    Parameters
    ----------
    centers : (n, d) float64, 1 <= d <= 3, finite
    radii : (n,) float64, positive and finite
    tol : float, >= 0 and finite

    Returns
    -------
    (pairs, worst) or None
        ``pairs`` : (k, 2) int64, ``i < j``, sorted; ``worst`` : the largest
        ``r_i + r_j - |c_i - c_j|`` over the pairs examined (every pair within
        ``r_i + r_j + tol``, and those the module docstring names), ``-inf`` if none. None where
        the grid does not apply (input out of these bounds, or an octave's grid would need more
        than :data:`MAX_CELLS` rows an axis): the caller's k-d trees take it.
    """
    centers = np.ascontiguousarray(centers, dtype=np.float64)
    radii = np.ascontiguousarray(radii, dtype=np.float64)
    count, dim = centers.shape if centers.ndim == 2 else (len(centers), 0)
    tol = float(tol)
    if not 1 <= dim <= 3 or radii.shape != (count,) or not 0.0 <= tol < math.inf \
            or not np.isfinite(centers).all() or not (np.isfinite(radii) & (radii > 0)).all():
        return None
    if count < 2:
        return np.zeros((0, 2), dtype=np.int64), -np.inf
    octave = np.floor(np.log2(radii)).astype(np.int64)  # as the k-d tree path numbers them
    low = int(octave.min())
    present = np.bincount(octave - low) > 0  # octaves numbered from 0 up, the empty ones left out
    level = (np.cumsum(present) - 1)[octave - low]
    levels = int(present.sum())
    boxes, build, scan = _kernels()
    lower, upper, largest, members = boxes(centers, radii, level, levels)
    side = 2 * largest + tol
    with np.errstate(over="ignore", invalid="ignore"):
        cells = np.floor((upper - lower) / side[:, None]) + 1
    if not (np.isfinite(side).all() and (cells[:, 1:] <= MAX_CELLS).all()):
        return None
    cells = cells.astype(np.int64)
    # The farthest a partner in octave m may be from a sphere of octave l <= m (the module
    # docstring), computed as the comparison computes it, then widened.
    reach = np.where(np.eye(levels, dtype=bool), side[:, None], (largest[None, :] + largest[:, None]) + tol)
    reach = reach * (1 + MARGIN)
    # Which side examines the pairs of octaves l < m: the small spheres, each visiting grid m, or
    # the large ones, each visiting grid l (as the k-d tree path does): the one of fewer rows.
    rows = np.minimum(cells[None, :, 1:], 1 + 2 * reach[:, :, None] / side[None, :, None]).prod(axis=2)
    from_small = members[:, None] * rows
    from_large = members[None, :] * rows.T  # rows of grid l within reach of a sphere of octave m
    large_side = np.triu(from_large < from_small, 1)
    # A row's slot: its index in the box of the octave's rows where they are few (a dense table),
    # else its hash in a table of at least twice its spheres (tiny spheres spread far).
    possible = cells[:, 1:].prod(axis=1)
    bits = np.where(possible <= DENSE * members, -1, np.ceil(np.log2(2 * members)).astype(np.int64))
    table_start = np.concatenate([[0], np.cumsum(np.where(bits < 0, possible, 1 << np.maximum(bits, 0)))])
    table, ids = build(centers, level, lower, side, cells, table_start, bits, np.argsort(centers[:, 0]))
    sorted_centers, sorted_radii = centers[ids], radii[ids]
    grid = (ids, sorted_centers, sorted_radii, level, lower, side, cells, reach, large_side, largest, tol, table,
            table_start, bits)
    found = np.zeros(count, dtype=np.int64)
    worst = np.full(count, -np.inf)
    pairs = np.zeros((0, 2), dtype=np.int64)
    # Many slices a thread: the large spheres' take longer.
    run_in_slices(scan, count, *grid, False, found, pairs, found, worst, serial_below=BLOCK, slices_per_thread=16)
    if found.any():  # a second pass writes the pairs (a valid packing has none)
        offsets = np.concatenate([[0], np.cumsum(found)[:-1]])
        pairs = np.zeros((int(found.sum()), 2), dtype=np.int64)
        run_in_slices(scan, count, *grid, True, offsets, pairs, found, worst, serial_below=BLOCK,
                      slices_per_thread=16)
    return pairs[np.lexsort((pairs[:, 1], pairs[:, 0]))], float(worst.max())


#: The compile helper's job that compiles the grid's kernels (:func:`compile_ahead`).
AHEAD_JOB = "numba: the overlap check's grid"


def ahead_jobs() -> list:
    """The compile helper's job for the grid's kernels (:mod:`ndpack.compile_ahead`), where Numba's
    disk cache lacks them (else none): a first packing's check then waits for the helper, if at
    all, instead of compiling them."""
    return ahead.job_unless_on_disk(_scan, AHEAD_JOB, 3.0, f"{__name__}:warm_up", [])


def warm_up() -> None:
    """Compile (or load) the grid's kernels by checking a few spheres, two of them overlapping (so
    that the second pass runs), with the argument types a packing's check passes: the compile
    helper's job."""
    rng = np.random.default_rng(0)
    centers, radii = rng.random((40, 3)), np.full(40, 0.01)
    centers[1] = centers[0]
    overlapping_pairs(centers, radii, 0.0)


@functools.cache
def _kernels():
    """``_boxes``, ``_build`` and ``_scan`` compiled by Numba, the last releasing the GIL (run in
    slices by threads: :func:`ndpack.parallel.run_in_slices`), imported at the first check, so
    ``import ndpack`` stays light; or loaded from disk where a compile helper compiled them."""
    ahead.wait(AHEAD_JOB)
    import numba

    from ..log import numba_functions

    # 2.1-2.4 s on 2 cores, the first time: said, like every compile a user waits for.
    numba_functions(__name__, "the overlap check's grid", 3)
    global _slot, _row, _chord
    _slot = numba.njit(cache=True)(_slot)  # compiled first: the kernels call them
    _row = numba.njit(cache=True)(_row)
    _chord = numba.njit(cache=True)(_chord)
    return numba.njit(cache=True)(_boxes), numba.njit(cache=True)(_build), numba.njit(nogil=True, cache=True)(_scan)


def _slot(table, start, bits, width, c1, c2):
    """Where row ``(c1, c2)`` is, or would go, in an octave's table from ``start``: its index in the
    box of rows ``width`` wide (``bits < 0``), else its hash in a table of ``2**bits`` slots
    (Fibonacci hashing: the product's top bits; linear probing)."""
    if bits < 0:
        return start + c1 + width * c2
    key = c1 | (c2 << BITS)
    mask = (1 << bits) - 1
    s = ((key * GOLDEN) >> (64 - bits)) & mask
    while table[start + s, 0] != key and table[start + s, 0] != -1:
        s = (s + 1) & mask
    return start + s


def _row(x, lower, side, cells):
    """Along one axis, the row holding coordinate ``x`` (clamped to the grid)."""
    u = (x - lower) / side
    if u < 0.0:
        return 0
    if u >= cells - 1:
        return cells - 1
    return int(u)


def _chord(u1, u2, within_rows, slack):
    """Half the chord along the first axis, in rows, of the ball of ``within_rows`` about a point
    at ``(u1, u2)`` rows from a row's corner, over the row; -1 where the ball misses the row.

    The gaps across the other axes are taken ``slack`` rows short, far more than a place's
    rounding (``(x - lower) / side`` is off by 2**-51 of itself: under 2**-31 rows, or of the
    reach in rows, wherever a partner can be), so the chord is an upper bound."""
    g1 = max(0.0, max(-u1, u1 - 1.0) - slack)
    g2 = max(0.0, max(-u2, u2 - 1.0) - slack)
    left = within_rows * within_rows - (g1 * g1 + g2 * g2)
    return math.sqrt(left) if left >= 0.0 else -1.0


def _boxes(centers, radii, level, levels):
    """Per octave: the box of the centres ``lower, upper`` (m, d), the largest radius and the
    number of spheres (m,)."""
    count, dim = centers.shape
    lower = np.full((levels, dim), np.inf)
    upper = np.full((levels, dim), -np.inf)
    largest = np.zeros(levels)
    members = np.zeros(levels, dtype=np.int64)
    for j in range(count):
        m = level[j]
        members[m] += 1
        largest[m] = max(largest[m], radii[j])
        for k in range(dim):
            lower[m, k] = min(lower[m, k], centers[j, k])
            upper[m, k] = max(upper[m, k], centers[j, k])
    return lower, upper, largest, members


def _build(centers, level, lower, side, cells, table_start, bits, by_x):
    """Each octave's rows: ``table`` (slots, 3) holds a row's key (-1: an empty slot), first position
    and length in the sorted order; ``ids`` (n,) the spheres grouped by octave and row, each row
    sorted along the first axis (taken in the order ``by_x``, a counting sort keeps it)."""
    count, dim = centers.shape
    table = np.full((table_start[-1], 3), -1, dtype=np.int64)
    table[:, 2] = 0
    slot_of = np.empty(count, dtype=np.int64)
    for j in range(count):
        m = level[j]
        c1 = _row(centers[j, 1], lower[m, 1], side[m], cells[m, 1]) if dim > 1 else 0
        c2 = _row(centers[j, 2], lower[m, 2], side[m], cells[m, 2]) if dim > 2 else 0
        s = _slot(table, table_start[m], bits[m], cells[m, 1] if dim > 1 else 1, c1, c2)
        table[s, 0] = c1 | (c2 << BITS)
        table[s, 2] += 1
        slot_of[j] = s
    total = 0
    for s in range(len(table)):
        table[s, 1] = total
        total += table[s, 2]
    filled = table[:, 1].copy()
    ids = np.empty(count, dtype=np.int64)
    for j in by_x:
        ids[filled[slot_of[j]]] = j
        filled[slot_of[j]] += 1
    return table, ids


def _scan(first, last, ids, centers, radii, level, lower, side, cells, reach, large_side, largest, tol, table,
          table_start, bits, write, offsets, pairs, found, worst):
    """Examine the pairs of each sphere at positions ``first`` to ``last`` (exclusive) in the sorted
    order (the module docstring): ``found[p]`` how many overlap by more than ``tol``, ``worst[p]``
    the largest overlap; with ``write``, the pairs go to ``pairs`` from ``offsets[p]`` on."""
    dim = centers.shape[1]
    levels = len(side)
    low = np.zeros(3, dtype=np.int64)  # rows within reach along axes 1 and 2 (0 and 0 if absent)
    high = np.zeros(3, dtype=np.int64)
    own_row = np.zeros(3, dtype=np.int64)
    where = np.zeros(3)  # the sphere's place in grid m, in rows, along axes 1 and 2
    for p in range(first, last):
        j = ids[p]
        own = level[j]
        x = centers[p, 0]
        best = -np.inf
        bad = 0
        for k in range(1, dim):
            own_row[k] = _row(centers[p, k], lower[own, k], side[own], cells[own, k])
        for m in range(levels):
            if m < own:
                if not large_side[m, own]:
                    continue
                # As the k-d tree path's query: this sphere's radius, the smaller octave's largest.
                within = ((radii[p] + largest[m]) + tol) * (1 + MARGIN)
            else:
                if m > own and large_side[own, m]:
                    continue
                within = reach[own, m]
            width = cells[m, 1] if dim > 1 else 1
            within_rows = within / side[m]
            # Rounding moves a place by far less than this many rows (_chord).
            slack = SLACK * (1.0 + within_rows)
            skip = False
            for k in range(1, dim):
                where[k] = (centers[p, k] - lower[m, k]) / side[m]
                u_low = (centers[p, k] - within - lower[m, k]) / side[m]
                u_high = (centers[p, k] + within - lower[m, k]) / side[m]
                if u_high < 0.0 or u_low >= cells[m, k]:
                    skip = True
                    break
                low[k] = 0 if u_low < 0.0 else int(u_low)
                high[k] = cells[m, k] - 1 if u_high >= cells[m, k] - 1 else int(u_high)
            if skip:
                continue
            for c2 in range(low[2], high[2] + 1):
                for c1 in range(low[1], high[1] + 1):
                    if m == own and (c2 < own_row[2] or (c2 == own_row[2] and c1 < own_row[1])):
                        continue  # a row before one's own: that sphere examines the pair
                    chord = _chord(where[1] - c1, where[2] - c2, within_rows, slack)
                    if chord < 0.0:
                        continue
                    half = chord * side[m] + within * SLACK
                    x_low, x_high = x - half, x + half
                    s = _slot(table, table_start[m], bits[m], width, c1, c2)
                    if table[s, 0] == -1:
                        continue
                    start, end = table[s, 1], table[s, 1] + table[s, 2]
                    if m == own and c1 == own_row[1] and c2 == own_row[2]:
                        start = p + 1  # one's own row: the spheres after oneself
                    else:
                        stop = end
                        while start < stop:  # the first sphere at or past x_low
                            middle = (start + stop) // 2
                            if centers[middle, 0] < x_low:
                                start = middle + 1
                            else:
                                stop = middle
                    for q in range(start, end):
                        if centers[q, 0] > x_high:
                            break
                        # Squares summed in axis order, as np.linalg.norm sums them.
                        squared = 0.0
                        for k in range(dim):
                            delta = centers[q, k] - centers[p, k]
                            squared += delta * delta
                        if m == own:
                            near = side[own]
                        elif m > own:
                            near = (radii[q] + largest[own]) + tol
                        else:
                            near = (radii[p] + largest[m]) + tol
                        if squared > near * near:
                            continue
                        overlap = (radii[q] + radii[p]) - math.sqrt(squared)
                        best = max(best, overlap)
                        if overlap > tol:
                            if write:
                                pairs[offsets[p] + bad, 0] = min(ids[q], j)
                                pairs[offsets[p] + bad, 1] = max(ids[q], j)
                            bad += 1
        found[p] = bad
        worst[p] = best
