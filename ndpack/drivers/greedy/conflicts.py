"""Which of a round's candidate spheres meet, and which to keep: the driver's host-side geometry
among spheres, through SciPy's k-d tree, or in the common case (no period, 1-D to 3-D, not
crowded) a grid of cells (:mod:`ndpack.geometry.close_pairs`, hand-written as the k-d tree measured
too slow there: see :func:`_greedy_on_grid`).

A fast-mode round places thousands of spheres whose radii may span a factor of two or more, with
a few far larger (gaps found late). Searching each sphere's neighbours within the largest radius
would make every search as wide as the largest sphere, so the few largest are searched for apart
(:func:`few_largest`).
"""

from __future__ import annotations

import numpy as np

#: The conflict check searches for this many largest spheres apart (see :func:`few_largest`).
FEW_LARGE = 64

#: :func:`disjoint_greedy` decides this many candidates first, over all their pairs.
FIRST_BLOCK = 64

#: Spheres that find more than ``CROWDED`` neighbours each (the mean of a sample of ``SAMPLE``)
#: are crowded: :func:`disjoint_greedy` decides them in blocks rather than over all their pairs.
CROWDED = 16
SAMPLE = 64


def few_largest(radii):
    """The few largest of ``radii`` (k,): their positions (at most ``FEW_LARGE``, none among
    few spheres) and the largest radius of the rest.

    A fast-mode round can hold a few spheres far larger than the rest (gaps found late): searched
    for apart, they do not widen every other sphere's search to their size.
    """
    if len(radii) <= 4 * FEW_LARGE:
        return np.empty(0, dtype=np.int64), float(radii.max())
    rest = len(radii) - FEW_LARGE - 1
    cut = float(np.partition(radii, rest)[rest])
    return np.flatnonzero(radii > cut), cut


def widened(reach):
    """A search radius widened past the rounding of the k-d tree's distances."""
    return reach + 1e-9 * np.abs(reach)


def disjoint_greedy(centers, radii, margin, period=None):
    """Positions of a greedy disjoint subset: each sphere is kept unless it comes within
    ``margin`` of one kept before it. ``centers`` (k, d), ``radii`` (k,) in priority order; in a
    periodic domain (``period``, a :class:`~ndpack.geometry.period.Period`) between their nearest images.

    Returns (j,) int64 positions, ascending.

    Where a sample of the candidates finds few neighbours each (``CROWDED``; a fast-mode round of
    thousands of candidates, most of them kept), every pair that may meet is listed at once
    (:func:`_greedy_by_pairs`, or :func:`_greedy_on_grid` without a period in 1-D to 3-D).
    Elsewhere the candidates are decided in blocks of priority, ``FIRST_BLOCK`` first and each
    block twice the last: a block's candidates that a sphere kept before it excludes are dropped,
    the rest are decided among themselves over their pairs, and each sphere the block keeps then
    searches once for the later candidates it excludes. The work so follows the kept spheres and
    their true neighbours, never the pairs among candidates that a kept one excludes: many
    candidates in one gap (4,096 prototypes of a 12-D ball on a grid of 2 finding its centre;
    32,761 in a small periodic box, all capped at the largest radius) are excluded by the first few
    kept, where listing their pairs had made 8.4 million (5.5 s) and hundreds of millions (a minute
    for 5 spheres). A block whose survivors are still crowded is cut back to ``FIRST_BLOCK``. The
    few largest candidates (:func:`few_largest`), where far larger than the rest, are left out of
    the kept spheres' searches, which would otherwise all be as wide as they are: each of them that
    survives to its block looks for the kept spheres before it instead. Every pair is decided by
    :func:`_meet`, the earlier sphere first, so that every path decides as the sequential rule
    does, to the bit.
    """
    count = len(radii)
    if count <= FIRST_BLOCK:
        return _greedy_among_all(centers, radii, margin, period)
    if period is None and centers.shape[1] <= 3:
        kept = _greedy_on_grid(centers, radii, margin)
        if kept is not None:
            return kept
    frame, boxsize = _frame(centers, widened(2 * radii.max() + margin), period)
    tree = _kdtree(frame, boxsize)
    if not _crowded(tree, frame, radii, margin):
        return _greedy_by_pairs(tree, frame, centers, radii, margin, period)
    large, cut = few_largest(radii)
    if radii.max() <= 2 * cut:
        large = large[:0]  # no far larger ones: the kept spheres' searches may reach them all
    small = radii.copy()
    small[large] = 0.0
    later_small = np.maximum.accumulate(small[::-1])[::-1]  # the largest small radius from each on
    is_large = np.zeros(count, dtype=bool)
    is_large[large] = True
    excluded, kept = np.zeros(count, dtype=bool), np.zeros(count, dtype=bool)
    live = _Live(tree, None)  # the tree the kept spheres search: the undecided, once most are dropped
    start, size = 0, FIRST_BLOCK
    while start < count:
        stop = min(count, start + size)
        block = start + np.flatnonzero(~excluded[start:stop])
        among = is_large[block]
        if among.any():
            rivals = _excluded_by_kept(frame, boxsize, centers, radii, margin, period, block[among], kept, start)
            excluded[rivals] = True
            block = block[~excluded[block]]
        if len(block) > FIRST_BLOCK:
            block_tree = _kdtree(frame[block], boxsize)
            if size > FIRST_BLOCK and _crowded(block_tree, frame[block], radii[block], margin):
                size = FIRST_BLOCK  # decide its first few alone: their kept spheres exclude the rest
                continue
            chosen = block[_greedy_by_pairs(block_tree, frame[block], centers[block], radii[block], margin, period)]
        else:
            chosen = block[_greedy_among_all(centers[block], radii[block], margin, period)]
        kept[chosen] = True
        if stop < count and len(chosen):
            live = live.refreshed(excluded, stop, frame, boxsize)
            reach = widened(radii[chosen] + later_small[stop] + margin)
            first, second = _near(live.tree, frame[chosen], reach, chosen)
            if live.ids is not None:
                second = live.ids[second]
            beyond = second >= stop
            first, second = first[beyond], second[beyond]
            beyond = ~excluded[second]
            first, second = first[beyond], second[beyond]
            excluded[second[_meet(centers, radii, first, second, margin, period)]] = True
        start, size = stop, 2 * size
    return np.flatnonzero(kept)


def _greedy_on_grid(centers, radii, margin):
    """:func:`_greedy_by_pairs` with the pairs found in a grid of cells
    (:mod:`ndpack.geometry.close_pairs`) rather than a k-d tree, and :func:`_crowded`'s rule
    counted in it: the common path (no period, 1-D to 3-D). None where the grid does not apply
    (see :func:`~ndpack.geometry.close_pairs.grid`) or the spheres are crowded: the k-d tree path
    decides them. The pairs listed are a superset of those that meet, as the k-d tree's are, and
    :func:`_meet` decides them alike, so both paths keep the same spheres, to the bit.

    Hand-written, as SciPy's ``cKDTree`` measured too slow for this hot path (two or three calls a
    round: on an H200 host, 1.05 s of a million-sphere packing, most of it building trees and
    listing their pairs). On 2 cores, all calls of a fast-mode packing of 200,000 spheres, medians
    of 3, interleaved (bench/conflicts.py, bench/results/conflicts_2core_issue48.json): the unit
    cube 0.460 s through the k-d tree, 0.090 s here; the armadillo 0.428 s and 0.087 s; their
    largest calls, 65,536 candidates, 35 and 39 ms through the k-d tree, 5.4 and 7.4 ms here."""
    from ndpack.geometry.close_pairs import grid

    count = len(radii)
    large, largest = few_largest(radii)
    spheres = grid(centers, radii, margin, largest)
    if spheres is None:
        return None
    sample = np.linspace(0, count - 1, min(count, SAMPLE)).astype(np.int64)
    room = (CROWDED + 1) * len(sample)
    if spheres.count_near(sample, widened(2 * largest + margin), room) > room:
        return None
    first, second = spheres.pairs()
    if len(large):
        with_large = spheres.pairs_with(large)
        first, second = np.concatenate([first, with_large[0]]), np.concatenate([second, with_large[1]])
    if len(first) == 0:
        return np.arange(count)
    meet = _meet(centers, radii, first, second, margin)
    return greedy_over_pairs(count, first[meet], second[meet])


def _greedy_among_all(centers, radii, margin, period):
    """:func:`disjoint_greedy` of a few spheres, over all their pairs."""
    count = len(radii)
    if count <= 1:
        return np.arange(count)
    first, second = np.triu_indices(count, 1)
    meet = _meet(centers, radii, first, second, margin, period)
    return greedy_over_pairs(count, first[meet], second[meet])


def _crowded(tree, frame, radii, margin):
    """Whether the spheres of a k-d ``tree`` (points ``frame``) would list many pairs in
    :func:`_greedy_by_pairs`: a sample of ``SAMPLE`` of them finds more than ``CROWDED``
    neighbours each. Searched an eighth of the sample at a time, each spread over the order, and
    no further once the count is reached (a search of a crowded 12-D round counts thousands)."""
    _, largest = few_largest(radii)
    reach = widened(2 * largest + margin)
    sample = np.linspace(0, len(radii) - 1, min(len(radii), SAMPLE)).astype(np.int64)
    enough, found = (CROWDED + 1) * len(sample), 0
    for part in range(8):
        found += tree.query_ball_point(frame[sample[part::8]], reach, return_length=True).sum()
        if found > enough:
            return True
    return False


def _excluded_by_kept(frame, boxsize, centers, radii, margin, period, ids, kept, start):
    """Which of candidates ``ids`` meet a sphere kept before position ``start``: searched among
    the kept spheres alone, which are disjoint, so that a search finds few however wide."""
    before = np.flatnonzero(kept[:start])
    if len(before) == 0:
        return before
    reach = widened(radii[ids] + radii[before].max() + margin)
    first, second = _near(_kdtree(frame[before], boxsize), frame[ids], reach, ids)
    first, second = before[second], first  # the kept one first, as everywhere
    return second[_meet(centers, radii, first, second, margin, period)]


def _near(tree, points, reach, ids):
    """The points of ``tree`` within ``reach`` (m,) of each of ``points`` (m, d): pairs (ids[q],
    position in the tree), two (p,) int64."""
    found = tree.query_ball_point(points, reach, return_sorted=False)
    lengths = np.fromiter(map(len, found), dtype=np.int64, count=len(found))
    if lengths.sum() == 0:
        return np.empty(0, dtype=np.int64), np.empty(0, dtype=np.int64)
    return np.repeat(ids, lengths), np.concatenate(found).astype(np.int64, copy=False)


class _Live:
    """The k-d tree the kept spheres of :func:`disjoint_greedy` search, and which candidates its
    points are (``ids``, None: all): rebuilt over the undecided ones once most of its points are
    decided or dropped, so that a search finds few it has no use for."""

    def __init__(self, tree, ids):
        self.tree, self.ids = tree, ids

    def refreshed(self, excluded, stop, frame, boxsize):
        ids = np.arange(len(excluded)) if self.ids is None else self.ids
        useful = ~excluded[ids] & (ids >= stop)
        if len(ids) < 4 * FIRST_BLOCK or 2 * useful.sum() >= len(ids):
            return self
        ids = ids[useful]
        return _Live(_kdtree(frame[ids], boxsize), ids)


def _frame(centers, reach, period):
    """The points (k, d) of a k-d tree of ``centers`` (k, d) for searches within ``reach``, and
    its box size (None where nothing wraps): in a periodic domain a frame that wraps."""
    if period is None:
        return centers, None
    return period.frame(centers, reach)


def _kdtree(frame, boxsize):
    from scipy.spatial import cKDTree

    return cKDTree(frame, boxsize=boxsize)


def _meet(centers, radii, first, second, margin, period=None):
    """(p,) bool: whether spheres ``first[p]`` and ``second[p]`` come within ``margin`` (one
    formula for every path of :func:`disjoint_greedy`, so that they decide alike to the bit)."""
    if period is None:
        delta = centers[first] - centers[second]
    else:
        delta = period.difference(centers[first], centers[second])
    gap = np.linalg.norm(delta, axis=1) - radii[first] - radii[second]
    return (gap < margin) & (first != second)


def _greedy_by_pairs(tree, frame, centers, radii, margin, period=None):
    """:func:`disjoint_greedy` over every pair that may meet, found in the k-d ``tree`` of
    ``centers`` (whose points are ``frame``, see :func:`_frame`)."""
    count = len(radii)
    # Pairs that may meet: two of the rest within twice their largest radius, each of the few
    # largest with any of the rest within its radius and theirs, and the few largest together.
    large, largest = few_largest(radii)
    pairs = [tree.query_pairs(widened(2 * largest + margin), output_type="ndarray")]
    if len(large):
        pairs.append(np.stack(_near(tree, frame[large], widened(radii[large] + largest + margin), large), axis=1))
        among = np.triu_indices(len(large), 1)
        pairs.append(np.stack([large[among[0]], large[among[1]]], axis=1))
    pairs = np.concatenate(pairs)
    if len(pairs) == 0:
        return np.arange(count)
    first, second = pairs.min(axis=1), pairs.max(axis=1)
    meet = _meet(centers, radii, first, second, margin, period)
    return greedy_over_pairs(count, first[meet], second[meet])


def greedy_over_pairs(count, first, second):
    """The greedy rule over conflict pairs, decided in parallel: positions (j,) int64 ascending of
    the kept among ``count`` items in priority order, where item ``second[p]`` may not be kept
    with ``first[p]`` (``first < second``).

    Each pass keeps every undecided item whose higher-priority rivals are all decided and none
    kept, and drops every undecided item with a kept rival: the same set as deciding one item
    after another, in as many passes as the longest chain of rivals (a priority-based
    independent set, as a device would compute it). Measured: 2-7 passes a round, 3 in most
    (the armadillo and the unit cube at 100,000 spheres).
    """
    undecided, kept = np.ones(count, dtype=bool), np.zeros(count, dtype=bool)
    while len(first):
        waiting = np.zeros(count, dtype=bool)
        waiting[second[undecided[first]]] = True
        blocked = np.zeros(count, dtype=bool)
        blocked[second[kept[first]]] = True
        kept |= undecided & ~waiting & ~blocked
        undecided &= waiting & ~blocked
        live = undecided[second]  # pairs still deciding something
        first, second = first[live], second[live]
    return np.flatnonzero(kept | undecided)
