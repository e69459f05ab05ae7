"""Which of a round's new spheres meet, and which is nearest to a point: the driver's host-side
geometry among spheres, through SciPy's k-d tree.

A fast-mode round places thousands of spheres whose radii may span a factor of two or more, with
a few far larger (gaps found late). Searching each sphere's neighbours within the largest radius
would make every search as wide as the largest sphere, so the few largest are searched for apart
(:func:`few_largest`).
"""

from __future__ import annotations

import numpy as np

#: More new spheres than this: :func:`nearest_sphere` searches a k-d tree (among each point's
#: ``NEAREST_CANDIDATES`` nearest centres first) instead of testing all.
NEAREST_BY_SEARCH, NEAREST_CANDIDATES = 64, 16
#: The conflict check and the nearest new sphere search for this many largest spheres apart
#: (see :func:`few_largest`).
FEW_LARGE = 64


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


def nearest_sphere(points, centers, radii):
    """Per point (n, d), the sphere (``centers`` (k, d), ``radii`` (k,)) with the smallest gap
    ``|p - c| - r``, the first of equals: (n,) int64.

    Many spheres (a fast-mode round): among each point's 16 nearest centres, and where a farther
    sphere could still be nearer (its radius larger), among all that could; the few largest
    spheres are tested for every point.
    """
    if len(radii) <= NEAREST_BY_SEARCH:
        offsets = points[:, None, :] - centers  # (n, k, d)
        return np.argmin(np.linalg.norm(offsets, axis=2) - radii, axis=1)
    from scipy.spatial import cKDTree

    large, largest = few_largest(radii)
    rest = np.setdiff1d(np.arange(len(radii)), large)
    tree = cKDTree(centers[rest])
    distance, near = tree.query(points, k=NEAREST_CANDIDATES)
    near = rest[near]
    gaps = distance - radii[near]
    # Smallest gap, the lowest id among equals (as argmin over all spheres in id order).
    best_gap = gaps.min(axis=1)
    best = np.where(gaps == best_gap[:, None], near, len(radii)).min(axis=1)
    # A sphere farther than the k-th nearest centre has a gap of at least that less the largest
    # radius: where that could beat the best found, search the ball that holds every rival.
    unsure = np.flatnonzero(distance[:, -1] - largest <= best_gap)
    reach = widened(best_gap[unsure] + largest) + 1e-9 * largest
    for i, rivals in zip(unsure, tree.query_ball_point(points[unsure], reach)):
        rivals = np.unique(np.append(rest[np.asarray(rivals, dtype=np.int64)], best[i]))
        best[i] = rivals[np.argmin(np.linalg.norm(points[i] - centers[rivals], axis=1) - radii[rivals])]
    for start in range(0, len(points) if len(large) else 0, 4096):  # the few largest, against every point
        rows = slice(start, start + 4096)
        candidates = np.concatenate([best[rows, None], np.broadcast_to(large, (len(best[rows]), len(large)))], axis=1)
        candidates.sort(axis=1)  # argmin takes the first of equals: the lowest id
        gap = np.linalg.norm(points[rows, None] - centers[candidates], axis=2) - radii[candidates]
        best[rows] = candidates[np.arange(len(candidates)), np.argmin(gap, axis=1)]
    return best


def disjoint_greedy(centers, radii, margin):
    """Positions of a greedy disjoint subset: each sphere is kept unless it comes within
    ``margin`` of one kept before it. ``centers`` (k, d), ``radii`` (k,) in priority order.

    Returns (j,) int64 positions, ascending.
    """
    from scipy.spatial import cKDTree

    count = len(radii)
    if count <= 1:
        return np.arange(count)
    tree = cKDTree(centers)
    # Pairs that may meet: two of the rest within twice their largest radius, and each of the
    # few largest with any sphere within its radius and the largest.
    large, largest = few_largest(radii)
    pairs = [tree.query_pairs(widened(2 * largest + margin), output_type="ndarray")]
    if len(large):
        partners = tree.query_ball_point(centers[large], widened(radii[large] + radii.max() + margin))
        lengths = [len(found) for found in partners]
        pairs.append(np.stack([np.repeat(large, lengths), np.concatenate(partners).astype(np.int64)], axis=1))
    pairs = np.concatenate(pairs)
    if len(pairs) == 0:
        return np.arange(count)
    first, second = pairs.min(axis=1), pairs.max(axis=1)
    gap = np.linalg.norm(centers[first] - centers[second], axis=1) - radii[first] - radii[second]
    meet = (gap < margin) & (first != second)
    first, second = first[meet], second[meet]
    order = np.argsort(first, kind="stable")
    first, second = first[order], second[order]
    starts = np.searchsorted(first, np.arange(count + 1))
    blocked = np.zeros(count, dtype=bool)
    kept = []
    for i in range(count):  # the sequential greedy rule; pairs are few and sorted by the larger
        if not blocked[i]:
            kept.append(i)
            blocked[second[starts[i] : starts[i + 1]]] = True
    return np.array(kept, dtype=np.int64)
