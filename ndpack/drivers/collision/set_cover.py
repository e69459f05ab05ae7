"""The cover problem under a covering: samples of a shape, candidate centres, and the set cover,
refinement and gap-closing steps that :func:`~ndpack.drivers.collision.covering.cover` runs
(the method is described in :mod:`~ndpack.drivers.collision.covering`). :class:`Problem` is also
what the sphere trees of :mod:`~ndpack.drivers.collision.sphere_tree` are fitted on."""

from __future__ import annotations

import heapq
import itertools
import math

import numpy as np
from scipy.spatial import cKDTree

from ...backends import get_backend
from ...geometry import ball_union
from ...geometry.ball_union import pieces
from ..greedy.protosphere import pack
from .boundary import exactly_sampled, project, sample_cells
from .boundary import samples as shape_samples

#: Boundary samples whose shrinking ball becomes a candidate centre, at most.
SHRINKING_BALLS = 8_000
#: Bisection steps of a shrinking ball (its radius to 2^-18 of the largest clearance).
SHRINK_STEPS = 18
#: Sets of fresh samples drawn to close the gaps between samples, at most (two in a row must be
#: covered).
FIX_PASSES = 12
#: Fresh samples of each such set, as a multiple of ``samples``.
FIX_SHARE = 3
#: Boundary samples of the largest such set.
FIX_LARGEST = 400_000
#: ... and at most this multiple of ``samples`` (fewer samples asked, less effort).
FIX_LARGEST_SHARE = 20
#: Entries of the candidates' coverage sets held at once; more and the samples are thinned.
SET_BUDGET = 2_000_000
#: Share of the tolerance kept for the seams between samples: the cover is made for the rest,
#: and every radius then grows by it, so that the points near a covered sample are covered too.
SEAM_SHARE = 0.25
#: Points drawn around each sample a fix pass finds outside the union (the gap is nearby).
AROUND = 8
#: Rounds of moving each ball to the centre that covers its samples reaching out least (counts).
RECENTRE_STEPS = 12
#: Samples of a ball's region its new centre is chosen on (the farthest among them).
REGION_SAMPLES = 256
#: Candidate centres a ball may move to in one round, at most (a random share of those near it).
RECENTRE_CANDIDATES = 1000
#: Samples and candidates per ball the bisection of a count works on, at most.
SEARCH_POINTS_PER_BALL = 200
SEARCH_CANDIDATES_PER_BALL = 60
#: Relative spread of the protrusion bisection at which a count's search stops.
SEARCH_PRECISION = 0.02
#: Points of a distance query asked at once, at first (:class:`_InPieces`; then sized by the time taken).
PIECE_POINTS = 8192


class Problem:
    """What a covering is made on: samples of a shape and candidate centres.

    Attributes
    ----------
    shape : Oracle
    points : (m, d) float64
        Boundary samples, then interior samples.
    normals : (m, d) float64
        Outward normals at the boundary samples, zero rows for the interior ones.
    candidates : (c, d) float64
        Candidate centres, inside the shape.
    clearances : (c,) float64
        Their distances to the boundary.
    spacing : float
        The boundary samples' median distance to their nearest neighbour.
    samples : int
        Boundary samples drawn (fresh sets are multiples of it).
    rng : numpy.random.Generator
    """

    def __init__(self, shape, points, normals, candidates, clearances, samples, rng, cells):
        self.shape, self.points, self.normals, self.cells = shape, points, normals, cells
        self.candidates, self.clearances = candidates, clearances
        self.spacing = _spacing(points[np.any(normals != 0, axis=1)])
        self.samples, self.rng = samples, rng
        self.diagonal = shape.diagonal
        self._tree = cKDTree(candidates)
        self.is_reference = False  # whether ``shape`` answers as the shape asked for (no compiled queries)

    @classmethod
    def make(cls, shape, samples, packing=None, seed=0, backend=None, device=None, compiled=False) -> Problem:
        """Samples and candidates of ``shape``; with ``compiled``, its distances and gradients run
        on the backend's compiled kernels where it has float64 ones (:class:`CompiledQueries`)."""
        rng = np.random.default_rng(seed)
        if packing is None:
            packing = pack(shape, n=1, mode="fast", seed=seed, backend=backend, device=device, progress=False)
        reference = shape
        if compiled:
            shape = CompiledQueries.where_it_pays(shape, backend, device)
        shape = _InPieces(shape)
        cells = sample_cells(shape)
        points, normals = shape_samples(shape, samples, rng, cells)
        candidates, clearances = _candidates(shape, packing, points[:samples], normals[:samples], rng)
        problem = cls(shape, points, normals, candidates, clearances, samples, rng, cells)
        problem.is_reference = shape.shape is reference
        return problem

    def fresh(self, count):
        """New samples: ``count`` on the boundary and a quarter as many inside; (points, normals)."""
        return shape_samples(self.shape, count, self.rng, self.cells)

    def near(self, ids):
        """Candidate ids whose centre lies within the bounding ball of the points ``ids``."""
        region = self.points[ids]
        middle = region.mean(axis=0)
        span = float(np.linalg.norm(region - middle, axis=1).max())
        near = np.asarray(self._tree.query_ball_point(middle, span), dtype=np.int64)
        if not len(near):
            near = np.asarray([self._tree.query(middle)[1]], dtype=np.int64)
        return near

    def cover_count(self, ids, k):
        """At most ``k`` balls covering the points ``ids``, reaching out as little as found: the
        bisection on the tolerance, :func:`_recentre`, then growth to cover every point and the
        shrink to the points served. Returns centres, radii, clearances and the tolerance."""
        points = self.points[ids]
        near = self.near(ids) if len(ids) < len(self.points) else np.arange(len(self.candidates))
        candidates, clearances = self.candidates[near], self.clearances[near]
        inner, chosen = _search_count(points, candidates, clearances, k, self.diagonal, self.rng)
        centers, clearance, inner = _recentre(points, candidates[chosen], clearances[chosen], candidates, clearances,
                                              self.rng)
        seam = 0.5 * self.spacing
        centers, radii, clearance = self.serve(ids, centers, clearance + inner + seam, clearance, inner, None, seam)
        radii, keep = _refine(points, centers, radii, clearance, seam)
        return centers[keep], radii[keep], clearance[keep], inner

    def serve(self, ids, centers, radii, clearance, inner, limit, seam, points=None, normals=None):
        """:func:`_serve` for the points ``ids`` (or the given ``points`` and ``normals``)."""
        if points is None:
            points, normals = self.points[ids], self.normals[ids]
        return _serve(self.shape, points, normals, centers, radii, clearance, inner, limit, seam,
                      (self.candidates, self.clearances))

    def close_gaps(self, centers, radii, clearance, inner, limit, seam):
        """Fresh sample sets, each twice as large as the last (up to :data:`FIX_LARGEST`, and
        :data:`FIX_LARGEST_SHARE` times ``samples``), until two in a row are covered, or
        :data:`FIX_PASSES` sets: each point outside the union, and points drawn around it, are
        served. Yields the centres, radii and clearances after each set (a whole covering to keep,
        should the run be interrupted)."""
        passes, clean, size = 0, 0, FIX_SHARE * self.samples
        while passes < FIX_PASSES and clean < 2:
            passes += 1
            fresh, normals = self.fresh(size)
            missed = ~ball_union.covered(fresh, centers, radii)
            # The gaps left are ever smaller: look harder.
            size = min(2 * size, FIX_LARGEST, FIX_LARGEST_SHARE * self.samples)
            if missed.any():
                clean = 0
                centers, radii, clearance = self.fix(fresh[missed], normals[missed], centers, radii, clearance,
                                                     inner, limit, seam)
            else:
                clean += 1
            yield centers, radii, clearance

    def fix(self, points, normals, centers, radii, clearance, inner, limit, seam):
        """Serve ``points`` found outside the union (normals: zero rows inside) and points drawn
        around them (the gap is nearby); returns the centres, radii and clearances."""
        on_boundary = np.any(normals != 0, axis=1)
        near, near_normals = _around(self.shape, points[on_boundary], points[~on_boundary], self.spacing, self.rng)
        return self.serve(None, centers, radii, clearance, inner, limit, seam, near, near_normals)


class CompiledQueries:
    """A shape whose distance and gradient run on a backend's compiled float64 kernels, the ones
    its packing loops evaluate (a CSG tree as a tape, a plug-in's kernel): a covering asks for
    millions of them, which the shape's own NumPy code answers several times slower. Every other
    attribute is the shape's."""

    def __init__(self, shape, backend):
        self.shape, self.backend = shape, backend

    @classmethod
    def where_it_pays(cls, shape, backend=None, device=None):
        """``shape`` on ``backend``'s kernels, or ``shape`` itself: for meshes and outlines (their own
        queries are compiled already), the NumPy backend, and float32 precision."""
        if exactly_sampled(shape):
            return shape
        engine = get_backend(backend, device, shape=shape)
        if engine.name == "numpy" or getattr(engine, "precision", "float64") != "float64":
            return shape
        return cls(shape, engine)

    def __getattr__(self, name):
        return getattr(self.shape, name)

    def __repr__(self) -> str:
        return repr(self.shape)

    def _distance(self, points):
        """(n,) float64 signed distances of ``points`` (n, d)."""
        points = np.ascontiguousarray(points, dtype=np.float64)
        return self.backend.distance(self.shape, points) if len(points) else np.zeros(0)

    def _distance_and_gradient(self, points):
        """(n,) signed distances and (n, d) gradients: the free space without spheres is the
        clearance ``-f`` and its direction ``-grad f``."""
        points = np.ascontiguousarray(points, dtype=np.float64)
        if not len(points):
            return np.zeros(0), np.zeros((0, self.shape.dim))
        dim = self.shape.dim
        clearance, away = self.backend.free_space(self.shape, points, np.zeros((0, dim)), np.zeros(0),
                                                  np.zeros((len(points), 0), dtype=np.int64))
        return -clearance, -away


class _InPieces:
    """A shape whose distances are asked for in pieces of about :data:`ndpack.geometry.ball_union.PIECE_SECONDS`
    each: a mesh answers some 200,000 points a second, a covering asks for millions at once, and
    Python (so Ctrl-C) gets a turn only between compiled calls. Every other attribute is the shape's."""

    def __init__(self, shape):
        self.shape = shape

    def __getattr__(self, name):
        return getattr(self.shape, name)

    def __repr__(self) -> str:
        return repr(self.shape)

    def _distance(self, points):
        points = np.asarray(points, dtype=np.float64)
        if len(points) <= PIECE_POINTS:
            return self.shape._distance(points)
        out = np.empty(len(points))
        for part in pieces(len(points), PIECE_POINTS):
            out[part] = self.shape._distance(points[part])
        return out

    def _distance_and_gradient(self, points):
        points = np.asarray(points, dtype=np.float64)
        if len(points) <= PIECE_POINTS:
            return self.shape._distance_and_gradient(points)
        distances, gradients = np.empty(len(points)), np.empty_like(points)
        for part in pieces(len(points), PIECE_POINTS):
            distances[part], gradients[part] = self.shape._distance_and_gradient(points[part])
        return distances, gradients


# ------------------------------------------------------------------------------------------------ candidates
def _candidates(shape, packing, boundary, normals, rng):
    """Candidate centres, (m, d), and their clearances (m,), all strictly inside the shape."""
    medial = [np.asarray(packing.medial_axis, dtype=np.float64).reshape(-1, shape.dim),
              np.asarray(packing.centers, dtype=np.float64).reshape(-1, shape.dim)]
    reach = float(np.max(packing.medial_radii, initial=0.0))
    if not reach > 0:
        reach = 0.5 * float(np.ptp(shape.bounds, axis=0).max())
    count = min(len(boundary), SHRINKING_BALLS)
    which = rng.choice(len(boundary), size=count, replace=False)
    centers = np.vstack([*medial, _shrinking_balls(shape, boundary[which], normals[which], 1.05 * reach)])
    clearances = -shape._distance(centers)
    inside = clearances > 0
    return np.ascontiguousarray(centers[inside]), clearances[inside]


def _shrinking_balls(shape, points, normals, reach, steps: int = SHRINK_STEPS):
    """Centres of the largest balls inside ``shape`` that touch its boundary at ``points``.

    A bisection on the radius ``t``: the ball of centre ``p - t n`` is inside while its clearance
    is at least ``t``. (n, d) float64.
    """
    low, high = np.zeros(len(points)), np.full(len(points), reach)
    slack = 1e-9 * shape.scale
    for _ in range(steps):
        middle = 0.5 * (low + high)
        fits = -shape._distance(points - middle[:, None] * normals) >= middle * (1 - 1e-6) - slack
        low, high = np.where(fits, middle, low), np.where(fits, high, middle)
    return points - low[:, None] * normals


def _spacing(points) -> float:
    """The median distance between a sample and its nearest neighbour."""
    if len(points) < 2:
        return 0.0
    distances, _ = cKDTree(points).query(points, k=2)
    return float(np.median(distances[:, 1]))


# ------------------------------------------------------------------------------------------------ set cover
def _coverage_sets(points, centers, radii, tree=None):
    """Which points each ball holds, as CSR (pointers (m + 1,), indices)."""
    tree = cKDTree(points) if tree is None else tree
    lists = tree.query_ball_point(centers, radii, return_sorted=False)
    lengths = np.fromiter(map(len, lists), dtype=np.int64, count=len(lists))
    pointers = np.zeros(len(lists) + 1, dtype=np.int64)
    np.cumsum(lengths, out=pointers[1:])
    indices = np.fromiter(itertools.chain.from_iterable(lists), dtype=np.int64, count=int(pointers[-1]))
    return pointers, indices


def _greedy(pointers, indices, count, covered=None) -> list[int]:
    """Greedy set cover: repeatedly the set holding the most points not yet covered.

    Lazy: a set's gain only falls, so a popped set whose fresh gain still tops the heap is the
    best. ``covered`` (count,) bool is updated in place.
    """
    covered = np.zeros(count, dtype=bool) if covered is None else covered
    heap = [(-int(size), i) for i, size in enumerate(np.diff(pointers)) if size]
    heapq.heapify(heap)
    chosen, left = [], count - int(covered.sum())
    while left and heap:
        _, i = heapq.heappop(heap)
        members = indices[pointers[i]:pointers[i + 1]]
        gain = int(np.count_nonzero(~covered[members]))
        if not gain:
            continue
        if heap and gain < -heap[0][0]:
            heapq.heappush(heap, (-gain, i))
            continue
        chosen.append(i)
        covered[members] = True
        left -= gain
    return chosen


def _prune(chosen, pointers, indices, count) -> list[int]:
    """Drop chosen sets whose every point another chosen set also holds (smallest first)."""
    times = np.zeros(count, dtype=np.int64)
    for i in chosen:
        times[indices[pointers[i]:pointers[i + 1]]] += 1
    kept = []
    for i in sorted(chosen, key=lambda i: pointers[i + 1] - pointers[i]):
        members = indices[pointers[i]:pointers[i + 1]]
        if members.size and times[members].min() >= 2:
            times[members] -= 1
        else:
            kept.append(i)
    return kept


def _cover_at(points, candidates, clearances, tolerance, tree=None) -> np.ndarray:
    """Indices of candidates whose balls of radius ``clearance + tolerance`` cover what they can
    of ``points``."""
    pointers, indices = _coverage_sets(points, candidates, clearances + tolerance, tree)
    chosen = _greedy(pointers, indices, len(points))
    return np.asarray(_prune(chosen, pointers, indices, len(points)), dtype=np.int64)


def _search_count(points, candidates, clearances, n, diagonal, rng):
    """The least tolerance (to :data:`SEARCH_PRECISION`) whose cover has at most ``n`` balls, and
    that cover's candidate indices. Where the balls are large, the sets are thinned to
    :data:`SET_BUDGET` entries: fewer samples and candidates, chosen at random."""
    # A few balls need few samples and candidates to be placed: thin both (recentring refines).
    keep = max(SEARCH_POINTS_PER_BALL * n, 3000)
    if len(points) > keep:
        points = points[rng.choice(len(points), size=keep, replace=False)]
    ids = np.arange(len(candidates))
    keep = max(SEARCH_CANDIDATES_PER_BALL * n, 1500)
    if len(ids) > keep:
        ids = np.sort(rng.choice(ids, size=keep, replace=False))
    candidates, clearances = candidates[ids], clearances[ids]
    tree = cKDTree(points)  # the same points at every step (unless thinned)
    low, high = 0.0, None
    tolerance = 0.05 * diagonal
    best = None
    for _ in range(40):
        sub_points, sub_ids, sub_tree = _thin(points, candidates, clearances, tolerance, rng, tree)
        chosen = sub_ids[_cover_at(sub_points, candidates[sub_ids], clearances[sub_ids], tolerance, sub_tree)]
        missed = _missed(sub_points, candidates[chosen], clearances[chosen] + tolerance)
        if len(chosen) + missed <= n:
            high, best = tolerance, chosen
        else:
            low = tolerance
        if high is None:
            tolerance *= 4
        elif low == 0.0:
            tolerance /= 4
        elif high / low - 1 <= SEARCH_PRECISION:
            break
        else:
            tolerance = math.sqrt(low * high)
    return high, ids[best]


def _recentre(points, centers, clearance, candidates, clearances, rng):
    """Lloyd-like rounds that lower the largest protrusion of a covering by a fixed count of balls.

    Each point goes to the ball that covers it reaching out least (``|p - c| - d``), then each
    ball moves to the candidate centre near its points whose ball covering them all reaches out
    least. Returns the best centres, their clearances and that protrusion.
    """
    tree = cKDTree(candidates)
    best = (np.inf, centers, clearance)
    for _ in range(RECENTRE_STEPS):
        _, _, owner, cost = ball_union.best_balls(points, centers, np.zeros(len(centers)), clearance)
        worst = float(cost.max())
        if worst >= best[0] * (1 - 1e-3):
            break
        best = (worst, centers, clearance)
        centers, clearance = centers.copy(), clearance.copy()
        order = np.argsort(owner, kind="stable")
        bounds = np.searchsorted(owner[order], np.arange(len(centers) + 1))
        for j in range(len(centers)):
            region = points[order[bounds[j]:bounds[j + 1]]]
            if not len(region):
                continue
            if len(region) > REGION_SAMPLES:  # the farthest points decide; keep them and a random rest
                far = np.argsort(np.linalg.norm(region - centers[j], axis=1))[-REGION_SAMPLES // 4:]
                region = np.vstack([region[far], region[rng.choice(len(region), REGION_SAMPLES, replace=False)]])
            middle = region.mean(axis=0)
            span = float(np.linalg.norm(region - middle, axis=1).max())
            near = np.asarray(tree.query_ball_point(middle, span), dtype=np.int64)
            if len(near) > RECENTRE_CANDIDATES:
                near = rng.choice(near, size=RECENTRE_CANDIDATES, replace=False)
            if not len(near):
                continue
            need = np.sqrt(((region[None, :, :] - candidates[near][:, None, :]) ** 2).sum(axis=2)).max(axis=1)
            need -= clearances[near]
            current = float(np.linalg.norm(region - centers[j], axis=1).max() - clearance[j])
            k = int(np.argmin(need))
            if need[k] < current:
                centers[j], clearance[j] = candidates[near[k]], clearances[near[k]]
    return best[1], best[2], best[0]


def _thin(points, candidates, clearances, tolerance, rng, tree=None):
    """A random share of ``points`` and of the candidates' ids, so that their sets hold about
    :data:`SET_BUDGET` entries; ``tree`` is ``points``'s k-d tree, if built. Returns the points, the
    ids and the points' k-d tree (None where thinned)."""
    tree = cKDTree(points) if tree is None else tree
    ids = np.arange(len(candidates))
    probe = rng.choice(ids, size=min(256, len(ids)), replace=False)
    mean = float(tree.query_ball_point(candidates[probe], clearances[probe] + tolerance, return_length=True).mean())
    total = mean * len(ids)
    if total <= SET_BUDGET:
        return points, ids, tree
    share = math.sqrt(SET_BUDGET / total)
    keep_points = max(int(share * len(points)), min(len(points), 2000))
    keep_ids = max(int(share * len(ids)), min(len(ids), 1000))
    return (points[rng.choice(len(points), size=keep_points, replace=False)],
            np.sort(rng.choice(ids, size=keep_ids, replace=False)), None)


def _missed(points, centers, radii) -> int:
    if not len(centers):
        return len(points)
    return int(np.count_nonzero(~ball_union.covered(points, centers, radii)))


# ------------------------------------------------------------------------------------------------ refinement
def _serve(shape, points, normals, centers, radii, clearance, inner, limit, seam, pool):
    """Cover the ``points`` that lie outside the union.

    Each grows the ball that would then reach out least, to its distance plus ``seam``, where that
    ball would reach out at most ``inner`` (or always, for ``limit`` None), within ``limit``;
    the rest get new balls from the candidates ``pool`` (centres, clearances) and fallbacks
    beside them, chosen by the greedy cover at ``inner`` and given the radius ``clearance + limit``.
    Returns the new ``centers``, ``radii`` and ``clearance``.
    """
    gap, _, cheapest, cost = ball_union.best_balls(points, centers, radii, clearance)
    missed = gap > 0
    if not missed.any():
        return centers, radii, clearance
    points, normals, cheapest, cost = points[missed], normals[missed], cheapest[missed], cost[missed]
    grow = np.ones(len(points), dtype=bool) if limit is None else cost <= inner
    radii = radii.copy()
    if grow.any():
        lengths = np.linalg.norm(points[grow] - centers[cheapest[grow]], axis=1)
        reach = np.inf if limit is None else clearance[cheapest[grow]] + limit
        np.maximum.at(radii, cheapest[grow], np.minimum(lengths + seam, reach))
    rest = ~grow
    if rest.any():
        extra_centers, extra_clearance = _fallback_candidates(shape, points[rest], normals[rest], inner)
        pool_centers = np.vstack([pool[0], extra_centers])
        pool_clearance = np.concatenate([pool[1], extra_clearance])
        chosen = _cover_at(points[rest], pool_centers, pool_clearance, inner)
        centers = np.vstack([centers, pool_centers[chosen]])
        clearance = np.concatenate([clearance, pool_clearance[chosen]])
        radii = np.concatenate([radii, pool_clearance[chosen] + limit])
    return centers, radii, clearance


def _around(shape, boundary, inside, spread, rng):
    """The given samples and :data:`AROUND` points near each (within about ``spread``): on the
    boundary, projected onto it along the gradient; inside, kept where inside. Returns the points
    (k, d) and their outward normals (zero inside)."""
    parts, normals = [boundary, inside], [np.zeros_like(boundary), np.zeros_like(inside)]
    if len(boundary):
        near = np.repeat(boundary, AROUND, axis=0) + spread * rng.standard_normal((AROUND * len(boundary), shape.dim))
        near, near_normals, on = project(shape, near)
        parts.append(near[on])
        normals.append(near_normals[on])
        _, normals[0] = shape._distance_and_gradient(boundary)
    if len(inside):
        near = np.repeat(inside, AROUND, axis=0) + spread * rng.standard_normal((AROUND * len(inside), shape.dim))
        near = near[shape._distance(near) < 0]
        parts.append(near)
        normals.append(np.zeros_like(near))
    return np.vstack(parts), np.vstack(normals)


def _fallback_candidates(shape, points, normals, tolerance):
    """A centre per point that a ball of radius ``clearance + tolerance`` there surely covers:
    ``tolerance`` inwards along the normal where that is inside, else the point itself."""
    centers = points - tolerance * normals
    clearances = -shape._distance(centers)
    at_point = clearances < 0
    centers[at_point] = points[at_point]
    clearances[at_point] = np.maximum(-shape._distance(points[at_point]), 0.0)
    return centers, clearances


def _refine(points, centers, radii, clearance, slack):
    """Shrink each ball to the points it serves best (those it covers reaching out least), plus
    ``slack``; balls that serve none are dropped. Returns the radii and the kept mask."""
    _, covering, _, _ = ball_union.best_balls(points, centers, radii, clearance)
    served = covering >= 0
    lengths = np.linalg.norm(points[served] - centers[covering[served]], axis=1)
    needed = np.full(len(centers), -np.inf)
    np.maximum.at(needed, covering[served], lengths)
    keep = np.isfinite(needed)
    return np.minimum(radii, needed + slack), keep


def _protrusions(shape, centers, radii) -> np.ndarray:
    if not len(centers):
        return np.zeros(0)
    return np.maximum(radii + shape._distance(centers), 0.0)
