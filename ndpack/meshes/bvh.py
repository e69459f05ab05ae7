"""A bounding-volume hierarchy over triangles (3-D) or segments (2-D), built once as flat arrays.

The traversal has to compile inside ndpack's scalar kernels (Numba CPU, Numba CUDA and Warp,
:mod:`ndpack.meshes.queries`), which read plain parameter arrays; no mesh library exposes its tree
in that form, so the tree is built here (binned surface-area heuristic, Numba, O(n log n)).

Layout
------
Nodes are in depth-first order: the left child of an inner node ``k`` is ``k + 1``.
``first[k], count[k]``: a leaf holds the triangles ``order[first : first + count]`` (count > 0);
an inner node has ``count == 0`` and its right child in ``first[k]``.
"""

from __future__ import annotations

import functools

import numpy as np

from .. import compile_ahead as ahead

#: Most triangles in a leaf: 8 and 16 measured fastest, within noise, among 1, 2, 4, 8, 12, 16 and 24
#: (signed queries on the armadillo, 2 cores).
LEAF_SIZE = 8
#: Bins of the surface-area heuristic along the widest axis of the triangles' centroids.
BINS = 16
#: Deepest a node may sit; deeper ranges become (large) leaves, so a traversal stack of 64 never
#: overflows (a depth-first walk holds at most depth + 1 entries).
MAX_DEPTH = 60


class Tree:
    """A built hierarchy (see the module docstring for the layout).

    Attributes
    ----------
    order : (n,) int64
        Triangle ids in leaf order.
    lower, upper : (m, d) float64
        Each node's box.
    first, count : (m,) int64
    """

    def __init__(self, order, lower, upper, first, count):
        self.order, self.lower, self.upper, self.first, self.count = order, lower, upper, first, count

    @property
    def n_nodes(self) -> int:
        return len(self.first)

    @property
    def depth(self) -> int:
        """Depth of the deepest leaf (the root is at depth 0)."""
        depth = np.zeros(self.n_nodes, dtype=np.int64)
        for k in range(self.n_nodes):
            if self.count[k] == 0:
                depth[k + 1] = depth[self.first[k]] = depth[k] + 1
        return int(depth.max())


def build(elements: np.ndarray) -> Tree:
    """Build the hierarchy of ``elements``: (n, 3, 3) triangles or (n, 2, 2) segments, float64."""
    elements = np.ascontiguousarray(elements, dtype=np.float64)
    if len(elements) == 0:
        raise ValueError("cannot build a hierarchy over no elements")
    return Tree(*_compiled()(elements.min(axis=1), elements.max(axis=1), elements.mean(axis=1),
                        LEAF_SIZE, BINS, MAX_DEPTH))


#: ``_build``'s argument types as :func:`build` passes them (Numba's words), and the job of the compile
#: helper that compiles it for them (:func:`ndpack.meshes.queries.compile_ahead`).
SIGNATURE = "(float64[:, ::1], float64[:, ::1], float64[:, ::1], int64, int64, int64)"
AHEAD_JOB = "numba: the mesh tree's build"


@functools.cache
def _compiled():
    """``_build`` compiled by Numba (imported only when a tree is built: ``import ndpack`` stays light),
    or loaded from disk where a compile helper compiled it."""
    ahead.wait(AHEAD_JOB)
    import numba

    global _stable_order
    _stable_order = numba.njit(cache=True)(_stable_order)  # compiled first: _build calls it
    return numba.njit(cache=True)(_build)


def _stable_order(keys):
    """The order that sorts ``keys`` (k,) float64, ties in their order: ``np.argsort(keys,
    kind="mergesort")``, by a heap sort of (key, position) pairs.

    Hand-written for the compile: with the mergesort argsort and arrays indexed by arrays, Numba
    compiled ``_build`` in 4.4 s, a fresh machine's first mesh waiting; with this and loops, 2.0 s
    (2 cores). The order is the same, so is the tree.
    """
    def before(a, b):  # position a's key sorts before position b's
        return keys[a] < keys[b] or (keys[a] == keys[b] and a < b)

    count = len(keys)
    index = np.arange(count)
    heapify = count // 2
    for turn in range(heapify + count - 1):
        if turn < heapify:  # build the heap: sift down each inner node, the last first
            root, size = heapify - 1 - turn, count
        else:  # move the largest to the end of the heap, which shrinks by one
            size = count - 1 - (turn - heapify)
            index[0], index[size] = index[size], index[0]
            root = 0
        while 2 * root + 1 < size:
            child = 2 * root + 1
            if child + 1 < size and before(index[child], index[child + 1]):
                child += 1
            if not before(index[root], index[child]):
                break
            index[root], index[child] = index[child], index[root]
            root = child
    return index


def _build(box_lower, box_upper, centroids, leaf_size, bins, max_depth):
    n, dim = centroids.shape
    order = np.arange(n)
    capacity = 2 * n
    lower = np.empty((capacity, dim))
    upper = np.empty((capacity, dim))
    first = np.zeros(capacity, dtype=np.int64)
    count = np.zeros(capacity, dtype=np.int64)
    # Pending ranges: begin, end, parent node (-1 for the root), depth. The right child is
    # pushed before the left, so the left is numbered next (depth-first layout).
    pending = np.empty((2 * max_depth + 4, 4), dtype=np.int64)
    pending[0, 0], pending[0, 1], pending[0, 2], pending[0, 3] = 0, n, -1, 0
    top = 1
    nodes = 0
    bin_count = np.zeros(bins, dtype=np.int64)
    bin_lower = np.empty((bins, dim))
    bin_upper = np.empty((bins, dim))
    while top > 0:
        top -= 1
        begin, end, parent, depth = pending[top, 0], pending[top, 1], pending[top, 2], pending[top, 3]
        node = nodes
        nodes += 1
        if parent >= 0 and parent + 1 != node:
            first[parent] = node  # a right child
        for i in range(dim):
            lower[node, i] = np.inf
            upper[node, i] = -np.inf
        c_lower = np.full(dim, np.inf)
        c_upper = np.full(dim, -np.inf)
        for j in range(begin, end):
            t = order[j]
            for i in range(dim):
                lower[node, i] = min(lower[node, i], box_lower[t, i])
                upper[node, i] = max(upper[node, i], box_upper[t, i])
                c_lower[i] = min(c_lower[i], centroids[t, i])
                c_upper[i] = max(c_upper[i], centroids[t, i])
        size = end - begin
        axis = np.argmax(c_upper - c_lower)
        extent = c_upper[axis] - c_lower[axis]
        if size <= leaf_size or depth >= max_depth or extent <= 0.0:
            first[node] = begin
            count[node] = size
            continue
        # Binned surface-area heuristic along the widest centroid axis.
        bin_count[:] = 0
        bin_lower[:] = np.inf
        bin_upper[:] = -np.inf
        scale = bins / extent
        for j in range(begin, end):
            t = order[j]
            b = min(int((centroids[t, axis] - c_lower[axis]) * scale), bins - 1)
            bin_count[b] += 1
            for i in range(dim):
                bin_lower[b, i] = min(bin_lower[b, i], box_lower[t, i])
                bin_upper[b, i] = max(bin_upper[b, i], box_upper[t, i])
        best_cost = np.inf
        best_split = 1
        for split in range(1, bins):
            cost = 0.0
            for side in range(2):
                lo = np.full(dim, np.inf)
                hi = np.full(dim, -np.inf)
                members = 0
                start, stop = (0, split) if side == 0 else (split, bins)
                for b in range(start, stop):
                    if bin_count[b] > 0:
                        members += bin_count[b]
                        for i in range(dim):
                            lo[i] = min(lo[i], bin_lower[b, i])
                            hi[i] = max(hi[i], bin_upper[b, i])
                if members > 0:
                    e = hi - lo
                    # Surface area in 3-D, perimeter in 2-D: how likely a query meets the box.
                    size = e[0] + e[1] if dim == 2 else e[0] * e[1] + e[1] * e[2] + e[2] * e[0]
                    cost += members * size
            if cost < best_cost:
                best_cost = cost
                best_split = split
        # Partition the range in place: bins below the split to the left.
        i, j = begin, end - 1
        while i <= j:
            b = min(int((centroids[order[i], axis] - c_lower[axis]) * scale), bins - 1)
            if b < best_split:
                i += 1
            else:
                order[i], order[j] = order[j], order[i]
                j -= 1
        middle = i
        if middle == begin or middle == end:  # every centroid in one bin's side: split by count
            middle = (begin + end) // 2
            # In loops: Numba compiles an array indexed by an array for seconds.
            keys = np.empty(end - begin)
            ids = np.empty(end - begin, dtype=np.int64)
            for j in range(end - begin):
                ids[j] = order[begin + j]
                keys[j] = centroids[ids[j], axis]
            sorted_positions = _stable_order(keys)
            for j in range(end - begin):
                order[begin + j] = ids[sorted_positions[j]]
        count[node] = 0
        pending[top, 0], pending[top, 1], pending[top, 2], pending[top, 3] = middle, end, node, depth + 1
        (pending[top + 1, 0], pending[top + 1, 1], pending[top + 1, 2],
         pending[top + 1, 3]) = begin, middle, node, depth + 1
        top += 2
    return order, lower[:nodes].copy(), upper[:nodes].copy(), first[:nodes].copy(), count[:nodes].copy()
