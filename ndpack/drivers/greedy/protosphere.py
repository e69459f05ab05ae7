"""The ProtoSphere driver (Weller & Zachmann): greedy sphere packing guided by prototypes.

A uniform grid covers the shape's bounds; every cell that can hold interior points gets one
prototype. Each prototype moves ``p <- p + eps * (p - q)`` away from its nearest obstacle point
``q`` (the shape's boundary or an inserted sphere), confined to its cell, with ``eps`` cooling
from ``EPS_START`` to ``EPS_END`` over ``iterations`` steps (:func:`cooling_schedule`); it ends near a
Voronoi node of (boundary + spheres), a local maximum of the clearance. Each round the prototype
with the largest clearance becomes a sphere of that radius (minus a safety margin), up to
``batch`` mutually disjoint ones largest first, and the prototypes whose nearest obstacle may
have changed converge again. The first round's converged prototypes sample the medial axis.

Only prototypes *touched* by a new sphere (their clearance ball meets it) move again: the others
keep their nearest obstacle, so their clearance and local maximum are unchanged. This gives the
same packing as moving every prototype every round, at a fraction of the cost.

Written once for every backend: the hot loops are :class:`~ndpack.backends.Backend` calls, and
the prototypes live in the backend's store (:mod:`ndpack.backends.prototypes`), on the GPU for
the GPU backends, so that a round copies only its answers between host and device.
"""

from __future__ import annotations

import sys
import time
import warnings
from dataclasses import dataclass

import numpy as np
from tqdm.auto import tqdm

from ...backends import get_backend
from ...backends.prototypes import best_starts, cell_bounds, top_order
from ...backends.restarts import Restarts, run_key, stream
from ...consistency import ensure_possible
from ...errors import KEPT_IN_ERROR, GridWarning, InvalidPackingError, ParameterError, RepairWarning, ShapeError
from ... import compile_ahead
from ...geometry import close_pairs, overlaps
from ...geometry.period import period_of
from ...oracle import Oracle, ball_volume, check_compatible, check_packable
from ...packing import Packing, RoundStats
from ...reproducible import geometric_schedule, root
from ...shapes.adapters import as_oracle
from ...shapes.mesh import recorded_holes
from ...shapes.plugin import check_plugin_slopes
from ...verify import DEFAULT_TOLERANCE, overlapping_pairs, verify, verify_with
from ..sizes import SizeDistribution
from .centre_distances import CentreDistances, during_rounds
from .rounds import (
    AHEAD_EPS_START,
    FAST_WINDOW,
    MAX_PROTOTYPES,
    POLISH_AHEAD,
    POLISH_WINDOW,
    SIZE_BAND,
    SPLIT_RATIO,
    Faithful,
    Fast,
    Sized,
    split_ratio,
)

#: Grid cells over the bounds when ``grid`` is not given (32^3 in 3D, 181^2 in 2D).
DEFAULT_CELLS = 32_768
#: A shape thinner than a cell, whose cells' starts all lie outside: this many of them, the
#: nearest, step across its boundary, at most this many times each (RunState._find_interior).
FIND_POINTS, FIND_STEPS = 4096, 100
#: A kept cell (one within half its diagonal of the inside) whose centre and random starts all
#: lie outside gets its prototype by stepping its best start across the boundary, confined to the
#: cell, at most ``STEP_IN_STEPS`` times (RunState._step_in); before, such cells had none, and a
#: coarse faithful grid could run out of room (a 4-D simplex on a grid of 4: 15 of 51 spheres).
#: ``STEP_IN = False`` turns it off, for comparisons (bench/step_in.py).
STEP_IN, STEP_IN_STEPS = True, 20
#: Refuse grids larger than this: memory grows with the cell count.
MAX_CELLS = 8_000_000
#: First and last ``eps`` of the cooling schedule. Large first steps cross the cell; the last ones
#: are small enough that the zig-zag around a Voronoi node is below 1e-5 of the radius.
EPS_START, EPS_END, COOLING_POWER = 0.5, 2e-6, 2.0
#: The leading candidates of each round converge further, with a finer schedule, before one
#: becomes a sphere: the paper's 50 steps leave errors up to 1e-2 in 4D and above, because a
#: zig-zag towards a Voronoi node advances only a fraction of each step.
POLISH_ITERATIONS, POLISH_EPS_START, POLISH_EPS_END, POLISH_POWER = 100, 0.05, 1e-7, 1.0
#: The fast mode stops both schedules where ``eps`` falls below these (moves after 41 of 50
#: steps, the polish after 60 of 100). A prototype zig-zagging towards a Voronoi node falls short
#: of it by about ``eps`` times its clearance, so a cut polish gives up a median 4e-6 of the
#: clearance (99% within 2e-5, at most 1.4e-4; armadillo, 30,000 spheres), far below what the fast
#: window gives away, for about 20% fewer move steps and 40% fewer polish steps (docs/benchmarks.md).
FAST_EPS_END, FAST_POLISH_EPS_END = 1e-4, 2e-5
#: ``mode="auto"`` takes the fast mode above this many spheres, in every dimension: in 2-D and
#: 3-D it filled within 0.14% of the faithful mode at equal counts, 1.3-6.6x sooner (200-5,000
#: spheres; bench/auto_mode.py); from 4-D up, with its narrower window and its ties taken one
#: layer at a time (:func:`~ndpack.drivers.greedy.rounds.fast_window`), within the seeds'
#: spread of the faithful mode's mean fill at 1,000 spheres (bench/fast_fill.py). The faithful
#: mode keeps small counts: the exact greedy order, for little time.
AUTO_FAST_ABOVE = 100
#: A prototype swallowed by a new sphere may restart this factor of its radius from its centre.
PUSH_OUT = 1.001
#: Random starts per cell when dead prototypes are revived, before the driver gives up for room.
REVIVE_TRIES, REVIVE_CHUNK = 32, 2048
#: Prototypes restart in chunks whose start points hold at most this many floats (64 MB): few
#: launches on a GPU, bounded memory for any grid.
START_FLOATS = 1 << 23
#: Under a time budget, prototypes move in pieces that take about this share of the budget (from
#: the rate measured so far), so that a long refinement stops within a few percent of it (2 cores:
#: a 6-D CSG shape's last round ended at 4.03 s of a 4 s budget and 10.04 of 10; moves slowed to
#: 2 ms each at 1.51 of 1.5 s); the first piece, before any rate is known, is ``FIRST_PIECE``.
PIECE_SHARE, FIRST_PIECE = 0.01, 256
#: Radii are shrunk by this fraction of the shape's scale, so that float64 rounding in the
#: distances (about 1e-16 of the scale) can never make touching spheres overlap or poke out.
SAFETY_MARGIN = 1e-10
#: A sphere capped at ``max_radius`` moves toward its nearest obstacle (RunState.snug) at most this
#: many times, until the gap left is below this fraction of its radius.
SNUG_STEPS, SNUG_TOLERANCE = 8, 1e-9
#: The cells' walls (lower bounds of the boundary's distance, which let deep prototypes skip
#: the shape's distance) are lowered by this many safety margins: far above the rounding of a
#: distance, so a skipped evaluation never changes a result.
WALL_SLACK = 10.0
#: In a periodic domain the images of a round's spheres are kept as obstacles where they come
#: within this many times the round's largest radius of the cell (and no sphere after it is
#: larger: :attr:`RunState.image_reach`). The greedy radii only shrink, so twice leaves room for
#: the late finds of the fast mode; the images kept cost a layer of that width along each face.
IMAGE_REACH = 2.0
#: When no prototype has room left (after the dead ones restarted), a final search refines the
#: cells that may still hold room before the run stops (RunState.search): level after level, each
#: such cell splits in two across its longest side and both halves converge from fresh starts,
#: and once room is found, on where more may hide. A search makes at most ``SEARCH_HALVINGS``
#: halvings of every side (``SEARCH_HALVINGS * d`` levels), splits no cell shorter than the smallest
#: radius that counts, and makes at most as many new cells as there were, or ``SEARCH_CELLS`` on a
#: coarser grid, those of the largest bounds first: it costs about what placing the grid did (a 12-D
#: ball on a grid of 2, full after one sphere: 1 s with 4,096 new cells, 69 s with 131,072).
SEARCH_HALVINGS, SEARCH_CELLS = 6, 4096


def cooling_schedule(
    iterations: int, start: float = EPS_START, end: float = EPS_END, power: float = COOLING_POWER
) -> np.ndarray:
    """Cooling ``eps_t = start * (end / start) ** ((t / (T - 1)) ** power)``, (T,) float64.

    ``power = 1`` is plain geometric cooling; ``power = 2`` keeps the steps large for longer
    (the prototypes travel about 3x farther in 50 steps) and still ends at ``end``.
    """
    if iterations == 1:
        return np.array([start])
    # Not np.power: its last bit depends on the CPU, and these steps steer every prototype.
    return np.array(geometric_schedule(iterations, start, end, power))


def schedules(mode: str, iterations: int) -> tuple[np.ndarray, np.ndarray]:
    """The cooling schedules of a run's moves, (T,) float64, and of its polish, (P,) float64:
    :func:`cooling_schedule`'s, cut in the fast mode where ``eps`` falls below ``FAST_EPS_END``
    and ``FAST_POLISH_EPS_END`` (both start far above them)."""
    steps = cooling_schedule(iterations)
    polish = cooling_schedule(POLISH_ITERATIONS, POLISH_EPS_START, POLISH_EPS_END, POLISH_POWER)
    if mode == "fast":
        steps, polish = steps[steps >= FAST_EPS_END], polish[polish >= FAST_POLISH_EPS_END]
    return steps, polish


def grid_counts(bounds: np.ndarray, grid=None) -> np.ndarray:
    """Cells per axis, (d,) int64, for nearly cubic cells.

    ``grid`` is the cell count along the longest side, a per-axis sequence, or None for about
    ``DEFAULT_CELLS`` cells in all.
    """
    extent = bounds[1] - bounds[0]
    dim = len(extent)
    if grid is None:
        side = root(float(np.prod(extent)) / DEFAULT_CELLS, dim)  # the same cells on every machine
        return np.maximum(1, np.round(extent / side)).astype(np.int64)
    counts = np.asarray(grid)
    # Whole, finite, at least 1, and numbers (a bool is not a cell count).
    whole = (counts.dtype.kind in "iuf" and counts.ndim <= 1 and np.all(np.isfinite(counts))
             and np.all(counts >= 1) and np.all(counts == np.round(counts)))
    if counts.ndim == 0:
        if not whole:
            raise ParameterError(f"grid must be a positive integer (cells along the longest side), got {grid!r}")
        side = extent.max() / int(counts)
        return np.maximum(1, np.round(extent / side)).astype(np.int64)
    if counts.shape != (dim,) or not whole:
        raise ParameterError(f"grid must be a positive integer or {dim} of them (cells per axis), got {grid!r}")
    return counts.astype(np.int64)


def _number(value) -> bool:
    """Whether ``value`` is a plain number (a bool is not one)."""
    return isinstance(value, (int, float, np.number)) and not isinstance(value, bool)


def _check_parameters(n, min_radius, fill, time_budget, iterations, batch, restarts, seed=None, max_radius=None):
    def positive_int(value, name):
        try:
            whole = not isinstance(value, bool) and float(value).is_integer() and value >= 1
        except (TypeError, ValueError):
            whole = False
        if not whole:
            raise ParameterError(f"{name} must be a positive integer, got {value!r}")

    positive_int(n, "n (the number of spheres)")
    positive_int(iterations, "iterations")
    positive_int(batch, "batch")
    if not (isinstance(restarts, int) and restarts >= 0):
        raise ParameterError(f"restarts must be a non-negative integer, got {restarts!r}")
    if not (isinstance(min_radius, (int, float, np.number)) and np.isfinite(min_radius) and min_radius >= 0):
        raise ParameterError(f"min_radius must be a non-negative number, got {min_radius!r}")
    if max_radius is not None:
        if not (_number(max_radius) and max_radius > 0):  # NaN fails the comparison
            raise ParameterError(f"max_radius must be a positive number or None, got {max_radius!r}")
        if max_radius < min_radius:
            raise ParameterError(f"max_radius ({max_radius!r}) is below min_radius ({min_radius!r}): no sphere "
                                 "could be placed; make max_radius >= min_radius (equal for equal spheres)")
    if fill is not None and not (_number(fill) and 0 < fill < 1):
        raise ParameterError(f"fill (the target fill fraction) must lie in (0, 1), got {fill!r}")
    if time_budget is not None and not (_number(time_budget) and 0 < time_budget < np.inf):
        raise ParameterError(f"time_budget must be a positive number of seconds (finite), got {time_budget!r}")
    try:  # what numpy takes as a seed, less a bool or a float (which it would take or misread)
        usable = not isinstance(seed, (bool, float, str)) and (np.random.default_rng(seed) is not None)
    except (TypeError, ValueError):
        usable = False
    if not usable:
        raise ParameterError(f"seed must be None, an integer >= 0 or a numpy Generator, got {seed!r}")


@dataclass(frozen=True)
class Touched:
    """Prototypes a round's new spheres touched, before they converge again.

    Attributes
    ----------
    ids : (t,) int64
    pushed : (t, d) float64
        Each one's restart point: its point pushed just outside the nearest new sphere.
    gap : (t,) float64
        The gap from its current point to the nearest new sphere: the clearance there now is the
        smaller of this and the stored one.
    """

    ids: np.ndarray
    pushed: np.ndarray
    gap: np.ndarray


class RunState:
    """The state of one packing run: prototypes, their cells, and the spheres so far.

    What both round strategies (:mod:`ndpack.drivers.greedy.rounds`) work on: the prototype store
    (``prototypes``), the spheres (:attr:`spheres`), and the moves the algorithm makes
    (:meth:`reconverge`, :meth:`polish`, :meth:`touched`, :meth:`settle`, :meth:`revive`,
    :meth:`insert`).
    """

    def __init__(self, shape, backend, counts, steps, polish_steps, restarts, key, deadline=None, budget=None,
                 centers_in=None, obstacles=None):
        self.shape = shape
        # time.perf_counter() at which the run's time budget (seconds, for sizing pieces) runs out
        self.deadline, self.budget = deadline, budget
        self._seconds_each = None  # a prototype move's measured time, under a deadline
        self.backend = backend
        self.dim = shape.dim
        self.steps, self.polish_steps = steps, polish_steps  # the cooling schedules (:func:`schedules`)
        self.restarts = restarts
        # Random restarts come from a hash of (key, serial, prototype, try, axis): the same points on
        # every backend, drawn on a GPU where its prototypes are (ndpack.backends.restarts).
        self.key, self.serial = key, 0
        # A float32 backend's clearances are good to about 1e-7 of the scale: it asks for more.
        self.margin = max(SAFETY_MARGIN, getattr(backend, "margin", SAFETY_MARGIN)) * shape.scale
        self.wall_slack = WALL_SLACK * self.margin  # the cells' walls' allowance for rounding (cell_bounds)
        self.count = 0
        self.centers = np.empty((64, self.dim))
        self.radii = np.empty(64)
        self.rounds = np.empty(64, dtype=np.int64)
        # Centres only (pack's centers_only): ``shape`` is the one grown by the largest radius, and
        # a sphere counts (and is returned) only where its centre lies in ``centers_in``; the
        # others stay obstacles, as in a larger packing cut by centre.
        self.centers_in = centers_in
        self.inside = np.empty(64, dtype=bool)
        self.inside_count = 0
        # A periodic domain (ndpack.Periodic): the spheres' images near the cell are obstacles too
        # (ndpack.geometry.period), kept within ``image_reach`` of it, which is also the largest radius allowed
        # (infinite without a period; below half the shortest period with one: IMAGE_REACH).
        self.period = period_of(shape)
        self.image_reach = np.inf
        self._obstacles = None  # (centres, radii, count) of the spheres and their images, when periodic
        if self.period is not None:
            self.image_reach = 0.5 * self.period.shortest - self.margin
            self._obstacles = (np.empty((64, self.dim)), np.empty(64), 0)
        self.searched = None  # how the last final search ended (:meth:`search`), once one ran
        # The final check's distances at the centres, computed as the spheres arrive (on a GPU,
        # while the device moves the prototypes: _run_rounds).
        self.centre_distances = CentreDistances(shape if centers_in is None else centers_in, during_rounds(backend))
        if obstacles is not None and len(obstacles[1]):
            # Spheres in place from the start (pack's obstacles): neither counted nor returned.
            self.insert(*obstacles, -1, counted=False)
        self._place_prototypes(counts, self.obstacles if self.count else None)

    # ------------------------------------------------------------------ prototypes
    def _place_prototypes(self, counts, obstacles=None):
        lower = self.shape.bounds[0]
        cell_size = (self.shape.bounds[1] - lower) / counts
        total = int(np.prod(counts))
        if total > MAX_CELLS:
            raise ParameterError(
                f"a grid of {total:,} cells ({' x '.join(map(str, counts))}) is too large; "
                f"ask for at most {MAX_CELLS:,} with a smaller grid="
            )
        index = np.stack(np.unravel_index(np.arange(total), tuple(counts)), axis=1)
        cell_lower = lower + index * cell_size
        centers, reach, wall = cell_bounds(cell_lower, cell_lower + cell_size, self._distance, self.wall_slack)
        # A cell whose centre is farther out than half its diagonal (no positive clearance
        # bound) holds no interior point.
        keep = reach > 0
        cells = {"lower": cell_lower[keep], "upper": cell_lower[keep] + cell_size, "reach": reach[keep],
                 "wall": wall[keep]}
        starts = self._restarts(centers[keep]).points(np.arange(len(cells["lower"])), cells["lower"], cells["upper"],
                                                      centers[keep])
        no_spheres = np.zeros((len(cells["lower"]), 0), dtype=np.int64)
        points, clearance = best_starts(self.backend, self.shape, starts, *self.spheres, no_spheres)
        alive = clearance > 0
        thin = not alive.any()  # no cell centre or random start lies inside
        if STEP_IN and not alive.all():  # cells near the boundary whose starts all lie outside
            out = np.flatnonzero(~alive)
            moved, depth = self._step_in(points[out], cells["lower"][out], cells["upper"][out])
            got = depth > 0
            points[out[got]], clearance[out[got]] = moved[got], depth[got]
            alive = clearance > 0
        if not alive.any():
            points, clearance = self._find_interior(points, clearance, np.flatnonzero(keep), lower, cell_size,
                                                    counts)
            alive = clearance > 0
            if not alive.any():
                raise ShapeError(
                    f"found no interior point of {self.shape!r}: not at the centres of the {int(keep.sum()):,} grid "
                    f"cells near it (of {total:,}), nor at {self.restarts} random points in each, nor by "
                    f"{FIND_STEPS} steps across its boundary from the "
                    f"{min(FIND_POINTS, int(keep.sum())):,} nearest; the "
                    "shape is empty (check the CSG) or much thinner than a cell (pass a finer grid=)")
        if thin:
            warnings.warn(
                f"the shape is thinner than the grid's cells ({float(cell_size.max()):.3g} wide; the deepest point "
                f"found is {float(clearance.max()):.3g} inside): no cell centre or random start lay inside, so the "
                f"first points were found by a search, in {int(alive.sum()):,} cells; spheres may come out well "
                "below the largest that fit: pass a finer grid= if it fits in memory", GridWarning, stacklevel=4)
        # Kept cells with no start inside wait for the final search (RunState.search), if any.
        self._set_aside = {name: value[~alive] for name, value in cells.items()} if not alive.all() else None
        cells = {name: value[alive] for name, value in cells.items()}
        centers, radii, table = self.centers[:0], self.radii[:0], no_spheres[alive]
        points = points[alive]
        if obstacles is not None and len(obstacles[1]):
            # Spheres in place from the start: each cell starts at its best point among them (its
            # starts and the point found so far) and converges once, clear of them.
            centers, radii = obstacles
            table, cells["reach"] = self.backend.near_spheres(cells["lower"], cells["upper"], cells["reach"], centers,
                                                              radii, return_bound=True)
            candidates = np.concatenate([starts[:, alive], points[None]])
            points, _ = best_starts(self.backend, self.shape, candidates, centers, radii, table)
        points, clearance = self.backend.converge(
            self.shape, points, cells["lower"], cells["upper"], centers, radii, table, self.steps, cells["wall"],
        )
        # From here on the prototypes and their cells live in the store, maybe on a GPU.
        self.prototypes = self.backend.prototypes(
            self.shape, cells["lower"], cells["upper"], cells["reach"], points, clearance, cells["wall"]
        )

    def _step_in(self, points, lower, upper, steps=None):
        """Points (k, d) outside the shape stepped across its boundary, each confined to its box
        ``lower``, ``upper`` (k, d), and their depths (k,) (positive where a point got in).

        A prototype's move cannot enter a shape (its steps shrink with the distance), so a point
        outside steps 1.5 times its distance (plus the safety margin) along the gradient, up to
        ``steps`` times (default ``STEP_IN_STEPS``): a relaxed projection, which for a convex
        part with an interior ends inside. On the host, in float64 (the shape's ``_step_inside``: its
        own ``_distance_and_gradient``, or a mesh's compiled loop): it runs once, for the cells whose
        starts all lie outside.
        """
        return self.shape._step_inside(points, lower, upper, STEP_IN_STEPS if steps is None else steps, self.margin)

    def _find_interior(self, points, clearance, kept, lower, cell_size, counts):
        """Starts inside a shape thinner than a cell, which held none of ``points`` (k, d) (the
        best start of each kept cell, clearances (k,) all <= 0; ``kept`` (k,) their flat grid
        indices, ascending).

        The ``FIND_POINTS`` starts nearest the shape step across its boundary (:meth:`_step_in`),
        free in the shape's bounds, up to ``FIND_STEPS`` times. A kept cell that holds a point
        that got in starts there (the deepest of several). Returns points (k, d) and clearances
        (k,), positive where a point is inside.
        """
        order = np.argsort(-clearance, kind="stable")[:FIND_POINTS]
        bounds = np.broadcast_to(self.shape.bounds[:, None], (2, len(order), self.dim))
        trial, depth = self._step_in(points[order], bounds[0], bounds[1], FIND_STEPS)
        inside = depth > 0
        # Each point that got in starts in the kept cell that holds it (one that holds an interior
        # point is within half its diagonal of the inside, so it was kept).
        index = np.clip(np.floor((trial[inside] - lower) / cell_size).astype(np.int64), 0, counts - 1)
        flat = np.ravel_multi_index(index.T, tuple(counts))
        rows = np.minimum(np.searchsorted(kept, flat), len(kept) - 1)
        found = kept[rows] == flat
        points, clearance = points.copy(), clearance.copy()
        for row, point, value in sorted(zip(rows[found], trial[inside][found], depth[inside][found]),
                                        key=lambda item: item[2]):
            points[row], clearance[row] = point, value  # ascending: the deepest of a cell is written last
        return points, clearance

    def _distance(self, points):
        """The shape's signed distance at ``points`` (k, d): (k,) float64, on the backend where it
        computes in float64 (a GPU evaluates a mesh's many times faster than the host)."""
        if getattr(self.backend, "precision", "float64") == "float64":
            return self.backend.distance(self.shape, points)
        return self.shape._distance(points)

    def _restarts(self, first=None, tries=None) -> Restarts:
        """The next restart of the run: ``first`` (k, d) (or None) and ``tries`` random points
        per prototype (default ``restarts``), from a new stream."""
        self.serial += 1
        return Restarts(stream(self.key, self.serial), self.restarts if tries is None else tries, first)

    @property
    def spheres(self):
        """The inserted spheres: centres (m, d) and radii (m,)."""
        return self.centers[: self.count], self.radii[: self.count]

    @property
    def obstacles(self):
        """What the prototypes keep clear of: the spheres, and in a periodic domain their images
        near the cell too; centres (m, d) and radii (m,), a list that only grows."""
        if self._obstacles is None:
            return self.spheres
        centers, radii, count = self._obstacles
        return centers[:count], radii[:count]

    def with_images(self, centers, radii):
        """Spheres ``centers`` (k, d), ``radii`` (k,) and, in a periodic domain, their images
        within :attr:`image_reach` of the cell: centres (m, d), radii (m,)."""
        if self.period is None:
            return centers, radii
        image_centers, image_radii, _ = self.period.images(centers, radii, self.image_reach)
        return np.concatenate([centers, image_centers]), np.concatenate([radii, image_radii])

    def reconverge(self, ids, first=None, tries=None, chunk=None, ahead=None):
        """Restart the prototypes ``ids`` (k,) at their best start and let them converge again.

        The starts are the current point, ``first`` (k, d) if given (clipped to the cells), and
        ``tries`` random points of each cell (default ``restarts``). Long lists go in chunks
        (of ``chunk``, by default as many as ``START_FLOATS`` allows), bounding the memory of the
        starts a host store makes; the chunks draw the same points as one piece would.
        ``ahead`` (a :class:`~ndpack.backends.prototypes.PolishAhead`) polishes in the same
        launches those that reach ``ahead.low``, and ``ahead.ids`` with the first.
        """
        restarts = self._restarts(first, tries)
        chunk = chunk or max(1024, START_FLOATS // ((restarts.tries + 2) * self.dim))
        if len(ids) == 0 and ahead is not None:
            self.prototypes.move(ids, *self.obstacles, self.steps, ahead=ahead)
        for start in range(0, len(ids), chunk):
            part = slice(start, start + chunk)
            self._move_in_time(ids[part], restarts.part(part), ahead)
            ahead = None if ahead is None else ahead.later()

    def out_of_time(self) -> bool:
        """Whether the time budget is spent; the driver stops after the round in progress."""
        return self.deadline is not None and time.perf_counter() >= self.deadline

    def _move_in_time(self, ids, restarts, ahead=None):
        """Move prototypes ``ids`` (k,) with ``restarts`` (a :class:`Restarts`), and ``ahead`` with
        the first piece (see :meth:`reconverge`). Under a deadline, in pieces sized to a small
        share of the budget, none begun once it has passed (the run ends after this round, so
        prototypes left unmoved are never chosen). Each prototype's move is independent of the
        others', so the pieces change no result, only when it stops."""
        done = 0
        while done < len(ids) and not self.out_of_time():
            if self.deadline is None:
                size = len(ids)
            else:
                size = FIRST_PIECE if self._seconds_each is None else PIECE_SHARE * self.budget / self._seconds_each
            piece = slice(done, done + max(1, int(size)))
            started = time.perf_counter()
            self.prototypes.move(ids[piece], *self.obstacles, self.steps, restarts=restarts.part(piece), ahead=ahead)
            self._seconds_each = (time.perf_counter() - started) / len(ids[piece])
            done = piece.stop
            ahead = None if ahead is None else ahead.later()

    def polish(self, ids):
        """Move prototypes ``ids`` further with the finer polish schedule, keeping each one's
        new place only where its clearance grew."""
        self.prototypes.move(ids, *self.obstacles, self.polish_steps, polish=True)

    def snug(self, points, clearance, radii):
        """Spheres of ``radii`` (k,) that are smaller than the free space at their ``points``
        (k, d) (whose clearances (k,) were measured there with the spheres so far), each moved
        toward its nearest obstacle until only the safety margin is left between them: the rest
        of the gap stays whole for the next spheres (equal spheres pack far denser so than at
        the gaps' centres). Returns centres (k, d).

        A step by ``clearance - margin - radius`` toward the nearest obstacle keeps the margin
        from everything, since moving a point by ``s`` lowers its clearance by at most ``s`` (a
        distance, or a lower bound of one, is 1-Lipschitz). Where the direction is off (a
        difference quotient across a crease of the shape's distance, as at a gap's centre) the
        sphere stops short and steps again, up to ``SNUG_STEPS`` times, never farther than
        ``sqrt(d)`` times the first step from where it started (the way into a corner), so that
        one table of the spheres near each start serves every step. A step that came out closer
        than half the margin (only rounding could do that) is taken back.
        """
        centers, sphere_radii = self.obstacles
        start = np.array(points, dtype=np.float64)
        most = np.maximum(clearance - self.margin - radii, 0.0) * np.sqrt(self.dim)  # how far each may go
        # Any point within ``most`` of a start has clearance below clearance + most: within reach.
        reach = clearance + most * np.sqrt(self.dim) + np.abs(clearance) * 1e-9 + self.margin
        table = self.backend.near_spheres(start - most[:, None], start + most[:, None], reach, centers, sphere_radii)
        points, before, moving = start.copy(), start.copy(), np.arange(len(start))
        for step in range(SNUG_STEPS + 1):
            measured, away = self.backend.free_space(self.shape, points[moving], centers, sphere_radii, table[moving])
            # A step aims at the margin exactly, so rounding may leave it a hair short of it; only a
            # step that ate half of it is taken back.
            short = measured - 0.5 * self.margin < radii[moving]
            points[moving[short]] = before[moving[short]]
            shift = measured - self.margin - radii[moving]
            length = np.linalg.norm(away, axis=1)
            go = ~short & (shift > SNUG_TOLERANCE * radii[moving]) & (length > 0)  # no direction known: it stays
            moving, shift, away, length = moving[go], shift[go], away[go], length[go]
            if len(moving) == 0 or step == SNUG_STEPS:
                break
            before[moving] = points[moving]
            offset = points[moving] - (shift / length)[:, None] * away - start[moving]
            far = np.linalg.norm(offset, axis=1)
            points[moving] = start[moving] + np.minimum(1.0, most[moving] / np.maximum(far, 1e-300))[:, None] * offset
            if self.period is not None:
                # Kept in the cell: the nearest point of a box is no farther than the step (the
                # step's bound holds), and the images kept reach only so far from the cell.
                points[moving] = np.clip(points[moving], self.period.lower, self.period.upper)
        return points

    def touched(self, new_centers, new_radii):
        """The prototypes whose clearance ball the new spheres (k, d), (k,) meet: a
        :class:`Touched`, with each one's restart point just outside the nearest new sphere (or
        image, in a periodic domain)."""
        new_centers, new_radii = self.with_images(new_centers, new_radii)
        ids, points, nearest = self.prototypes.touched(new_centers, new_radii)
        centers, radii = new_centers[nearest], new_radii[nearest]
        offsets = points - centers
        lengths = np.linalg.norm(offsets, axis=1)
        # The point pushed radially just outside the sphere it fell into: the new gaps lie along it.
        direction = offsets / np.maximum(lengths, 1e-300)[:, None]
        pushed = centers + direction * (PUSH_OUT * radii)[:, None]
        return Touched(ids, pushed, lengths - radii)

    def settle(self, new_centers, new_radii):
        """After new spheres (k, d), (k,): the prototypes whose clearance ball they meet
        converge again (the others keep their nearest obstacle, so nothing changes for them)."""
        touched = self.touched(new_centers, new_radii)
        self.reconverge(touched.ids, touched.pushed)

    def revive(self):
        """Restart the dead prototypes (no free start found) with fresh random points; how many live."""
        dead, _ = self.prototypes.select(high=self.margin)
        if len(dead) == 0 or self.count == 0:
            return 0
        self.reconverge(dead, tries=REVIVE_TRIES, chunk=REVIVE_CHUNK)
        return int(np.count_nonzero(self.prototypes.gather(dead)[1] > self.margin))

    def search(self, min_radius: float) -> bool:
        """The final search, before a run stops for want of room: whether it found room for a
        sphere of at least ``min_radius`` (and the safety margin, as the choice asks).

        A prototype finds one local maximum of the clearance in its cell, and a cell much wider
        than the gaps left can hide them from its starts: the paper's fixed grid ran out of room
        with room left (a square on a grid of 2 stopped at 169 circles with a free disc 80 times
        the last one's radius). So the cells that may hold room (their bound of the clearance
        inside, :meth:`~ndpack.backends.prototypes.Prototypes.split_candidates`, reaches it)
        split in two across their longest side, level after level, and both halves converge from
        fresh random starts. Once a prototype has room, the levels go on with the cells that may
        hold more than it found and are longer than ``SPLIT_RATIO`` times that (the fast mode's
        rule), so that the next sphere is the largest gap at that resolution, not the first one
        seen (a 6-D simplex on a grid of 3: the next sphere 0.0116 with a gap of 0.0557 left,
        then radii up and down; with these levels, 0.0569 there and descending). The cells set
        aside at the start (none of their starts lay inside) join first.

        Bounded: at most ``SEARCH_HALVINGS`` halvings of every side (``SEARCH_HALVINGS * d``
        levels), no cell shorter than the smallest radius that counts, at most as many new cells
        as there were or ``SEARCH_CELLS``, whichever is more (the largest bounds split first),
        and not past the time budget. :attr:`searched` records what it did and, where it found
        no room, what ended it. The split cells stay: the run goes on with them, and a later
        search from them.
        """
        store = self.prototypes
        need = max(min_radius, self.margin) + self.margin  # rounds._usable: radius = clearance - margin
        shortest = max(min_radius, 1e3 * self.margin)  # no cell this short splits (as in the fast mode)
        most = max(SEARCH_CELLS, len(store))
        searched = self.searched = {"levels": 0, "cells": 0, "ended": "no cell may hold room"}
        if self._set_aside is not None:
            aside, self._set_aside = self._set_aside, None
            self.reconverge(store.add_cells(aside["lower"], aside["upper"], aside["reach"], aside["wall"]))
            searched["cells"] = len(aside["reach"])
        low, longest = need, shortest
        for level in range(SEARCH_HALVINGS * self.dim + 1):
            top = store.top()
            if top >= need:  # room: refine on where more may hide, in cells long against it
                low, longest = top, max(shortest, SPLIT_RATIO * top)
            if level == SEARCH_HALVINGS * self.dim:
                searched["ended"] = f"{SEARCH_HALVINGS} halvings of every side"
                break
            if self.out_of_time():
                searched["ended"] = "time"
                break
            memory = MAX_PROTOTYPES - len(store)
            allowed = max(0, min(most - searched["cells"], memory))
            ids, bound = store.split_candidates(low, longest, most=allowed + 1)  # one more: whether cells wait
            if len(ids) > allowed:
                ids = np.sort(ids[top_order(ids, bound, allowed)])
                searched["ended"] = f"{most:,} new cells" if allowed < memory else f"{MAX_PROTOTYPES:,} prototypes"
            if len(ids) == 0:
                break
            both = np.concatenate([ids, store.split_cells(ids, self.wall_slack)])
            store.tighten_reach(both, *self.obstacles)
            self.reconverge(both)
            searched["levels"], searched["cells"] = level + 1, searched["cells"] + len(ids)
        return top >= need

    def insert(self, centers, radii, round_index, counted=True):
        """Add a round's spheres ``centers`` (k, d), ``radii`` (k,); in a periodic domain their
        centres wrapped into the cell, the reach of the images narrowed to the round's size
        (:data:`IMAGE_REACH`) and their images within it added to the obstacles. Returns which
        count (k,) bool: all, but with ``centers_in`` those whose centre lies in it, and none
        where ``counted`` is False (pack's ``obstacles``)."""
        if self.period is not None and len(radii):
            centers = self.period.wrap(centers)
            if counted:  # spheres given (obstacles) say nothing of the sizes to come
                self.image_reach = min(self.image_reach, IMAGE_REACH * float(np.max(radii)))
            self._add_obstacles(*self.with_images(centers, radii))
        needed = self.count + len(radii)
        if needed > len(self.radii):
            capacity = max(needed, 2 * len(self.radii))
            self.centers = np.resize(self.centers, (capacity, self.dim))
            self.radii = np.resize(self.radii, capacity)
            self.rounds = np.resize(self.rounds, capacity)
            self.inside = np.resize(self.inside, capacity)
        inside, known = np.full(len(radii), counted), None
        if not counted:  # never returned, never checked
            known = np.full(len(radii), np.nan)
        elif self.centers_in is not None and len(radii):
            known = self.centers_in._distance(np.asarray(centers, dtype=np.float64))  # the check's, too
            inside = known < 0
        self.centers[self.count:needed] = centers
        self.radii[self.count:needed] = radii
        self.rounds[self.count:needed] = round_index
        self.inside[self.count:needed] = inside
        self.centre_distances.add(self.centers[self.count:needed], known)
        self.inside_count += int(inside.sum())
        self.count = needed  # last, so an interrupt never leaves half a sphere
        return inside

    def _add_obstacles(self, centers, radii):
        stored_centers, stored_radii, count = self._obstacles
        needed = count + len(radii)
        if needed > len(stored_radii):
            capacity = max(needed, 2 * len(stored_radii))
            stored_centers = np.resize(stored_centers, (capacity, self.dim))
            stored_radii = np.resize(stored_radii, capacity)
        stored_centers[count:needed] = centers
        stored_radii[count:needed] = radii
        self._obstacles = (stored_centers, stored_radii, needed)


def pack(
    shape: Oracle,
    n: int = 1000,
    *,
    min_radius: float = 0.0,
    max_radius: float | None = None,
    fill: float | None = None,
    time_budget: float | None = None,
    grid=None,
    iterations: int = 50,
    batch: int = 1,
    mode: str = "auto",
    restarts: int = 8,
    seed: int | None = 0,
    backend=None,
    device=None,
    progress: bool | None = None,
    on_invalid: str | None = None,
    on_round=None,
    centers_only: bool = False,
    obstacles=None,
) -> Packing:
    """Fill ``shape`` with non-overlapping spheres, largest first (ProtoSphere).

    Parameters
    ----------
    shape : Oracle
        Any ndpack shape or plug-in, bounded, of any dimension.
    n : int
        Stop after this many spheres.
    min_radius : float
        No sphere is smaller than this: the run stops when none fits (``stop_reason ==
        "min_radius"``).
    max_radius : float, optional
        No sphere is larger than this: where the free space is larger, a sphere of
        ``max_radius`` goes there, moved from the prototype's point until it touches the
        nearest obstacle (:meth:`RunState.snug`); the fast mode fills the tightest of such gaps
        first. ``min_radius == max_radius`` packs equal spheres.
    fill : float, optional
        Stop when this fraction of the volume is covered.
    time_budget : float, optional
        Stop after about this many seconds, counted from the grid's placement: checked between
        rounds and, inside a round, between pieces of its prototype moves (each about 1% of the
        budget), so a long refinement ends within a few percent of it. Not counted: checking
        the shape before, and the final float64 check after.
    grid : int or sequence of int, optional
        Cells along the longest side of the bounds, or per axis; default about 32,768 cells.
    iterations : int
        Steps of each prototype's convergence (the paper uses 50; the fast mode stops once the
        step has cooled below ``FAST_EPS_END``, after 41 of the default 50).
    batch : int
        Faithful mode: up to this many mutually disjoint spheres per round; 1 is the paper's
        exact greedy order.
    mode : "auto", "faithful" or "fast"
        ``"faithful"``: the paper's rounds on a fixed grid (with ``batch``), refined only where
        no prototype has room left, before the run would stop for it. ``"fast"``: every
        candidate within a window of the largest clearance (20% up to 3-D, narrower above:
        ``rounds.fast_window``) becomes a sphere in one round where it is disjoint from the
        larger ones, and cells split where their gaps have
        become small against them; for large counts (see docs/benchmarks.md for its fill
        against the faithful mode's). ``"auto"`` (the default): fast for more than
        ``AUTO_FAST_ABOVE`` (100) spheres, else faithful (and faithful whenever
        ``batch`` is given); ``params["mode"]`` records the mode run and ``params["mode_why"]``
        why auto chose it.
    restarts : int
        Random points tried per cell when a prototype restarts; the best one starts.
    seed : int or None
        Seed of the random prototype placement; equal seeds give equal packings.
    backend : str or Backend, optional
        Which backend runs the hot loops: ``"numpy"``, ``"numba"``, ``"numba-cuda"``, ``"warp"``
        or an instance. Default: the ``ndpack.backends.use`` block, ``$NDPACK_BACKEND``, else
        the fastest that works here (see :mod:`ndpack.backends`).
    device : str, optional
        ``"cpu"`` or ``"cuda:N"`` for the backends that run on both (warp, numba-cuda).
    progress : bool, optional
        Show a progress bar; by default only when stderr is a terminal.
    on_invalid : {"repair", "raise"}, optional
        What to do should the final float64 check find a sphere outside or two overlapping
        (a plug-in that is not 1-Lipschitz, float32 rounding beyond its margin, a faulty
        backend), or a plug-in's distance rise faster than a distance across a sphere
        (:mod:`ndpack.consistency`): ``"repair"`` shrinks or drops those spheres, warns
        (:class:`RepairWarning`) and records it in :attr:`Packing.repair`; ``"raise"`` raises
        :class:`InvalidPackingError` (the packing as made in its ``packing``). Default:
        ``$NDPACK_ON_INVALID``, else ``"repair"``.
    on_round : callable, optional
        Called after each round with a :class:`Round` (the new spheres, count, fill, time): to
        watch a run, plot it as it goes, or stop it (return True: ``stop_reason == "callback"``).
    centers_only : bool
        Only the centres must lie inside ``shape`` (as DEM codes cut a bed by centre, the walls
        pushing back what pokes through): the shape grown by ``max_radius`` (required) is packed,
        and the spheres whose centres lie in ``shape`` count and are returned (the others were
        obstacles, as in a larger packing cut by centre). ``params["centers_only"]`` says so,
        and verification checks the centres.
    obstacles : Packing or (centers (m, d), radii (m,)), optional
        Spheres already in place (fixed particles, a packing to go on from, the neighbours of a
        tile: :func:`ndpack.pack_tiled`): the new spheres keep clear of them and fill the gaps
        they leave; they are neither counted in ``n`` nor returned, and may reach outside the
        shape. ``params["obstacles"]`` records how many there were, and the final check finds
        any new sphere that overlaps one.

    Returns
    -------
    Packing
        Verified in float64: every sphere inside ``shape`` and no two overlapping. An interrupted
        run (Ctrl-C) returns what it packed so far, with ``stop_reason == "interrupted"``.
        ``packing.repair`` is None unless the final check had to repair it.

    Raises
    ------
    NdpackError
        Before packing, with a one-line reason: a bad parameter (``ParameterError``), bounds
        that cut the shape (``BoundsError``), or a plug-in found steeper than a distance on
        random pairs of points (``OracleError``, see ``Function.check_lipschitz``). After
        packing, ``InvalidPackingError`` when the spheres' volume exceeds the shape's (a
        distance steeper than it says, or a wrong volume), whatever ``on_invalid`` says.
    """
    shape = as_oracle(shape)
    check_compatible(shape)
    _check_parameters(n, min_radius, fill, time_budget, iterations, batch, restarts, seed, max_radius)
    max_radius = np.inf if max_radius is None else float(max_radius)
    mode, mode_why = choose_mode(mode, n, shape.dim, batch)
    if mode == "fast" and batch != 1:
        raise ParameterError(
            f"batch={batch!r} applies to the faithful mode only: the fast mode takes every candidate "
            f"within a window of the largest a round ({FAST_WINDOW:.0%} up to 3-D); drop batch or use mode='faithful'"
        )
    on_invalid = _check_run(shape, on_invalid, on_round)
    obstacles = _check_obstacles(obstacles, shape.dim)
    packed = _centers_only(shape, max_radius, "max_radius") if centers_only else shape
    backend = get_backend(backend, device=device, shape=packed)
    counts = grid_counts(packed.bounds, grid)
    polish_ahead = POLISH_AHEAD if backend.launch_bound and mode == "fast" else None
    ratio = split_ratio(backend.launch_bound)
    params = dict(
        n=int(n), min_radius=float(min_radius), max_radius=None if max_radius == np.inf else max_radius,
        fill=fill, time_budget=time_budget, batch=int(batch), mode=mode, polish_window=POLISH_WINDOW,
        **_run_params(shape, backend, counts, iterations, restarts, seed, centers_only),
    )
    if mode == "fast":
        params["split_ratio"] = ratio
    if mode_why:
        params["mode_why"] = mode_why
    if obstacles is not None:
        params["obstacles"] = len(obstacles[1])
    if mode == "fast":
        params.update(fast_eps_end=FAST_EPS_END, fast_polish_eps_end=FAST_POLISH_EPS_END, polish_ahead=polish_ahead,
                      polish_ahead_eps_start=None if polish_ahead is None else AHEAD_EPS_START)

    def strategy(state):
        return Fast(state, ratio=ratio, polish_ahead=polish_ahead) if mode == "fast" else Faithful(int(batch))

    return run(packed, backend, strategy, counts=counts, mode=mode, iterations=iterations, restarts=restarts,
               seed=seed, n=n, radius_range=(float(min_radius), max_radius), fill=fill, time_budget=time_budget,
               progress=progress, on_invalid=on_invalid, on_round=on_round, params=params,
               centers_in=shape if centers_only else None, obstacles=obstacles)[0]


def _check_obstacles(obstacles, dim: int):
    """``pack``'s ``obstacles`` as centres (m, d) and radii (m,) float64, or None for none."""
    if obstacles is None:
        return None
    if hasattr(obstacles, "centers") and hasattr(obstacles, "radii"):
        obstacles = (obstacles.centers, obstacles.radii)
    try:
        centers, radii = obstacles
        centers = np.asarray(centers, dtype=np.float64) if len(radii) else np.empty((0, dim))
        radii = np.asarray(radii, dtype=np.float64)
    except (TypeError, ValueError):
        raise ParameterError(f"obstacles must be a Packing or (centers (m, {dim}), radii (m,)), got "
                             f"{type(obstacles).__name__}") from None
    if centers.ndim != 2 or centers.shape[1] != dim:
        raise ParameterError(f"obstacles: centres of shape {centers.shape}, but the shape is {dim}-D: give them as "
                             f"(m, {dim})")
    if radii.ndim != 1 or len(centers) != len(radii):
        raise ParameterError(f"obstacles: {len(centers)} centres but radii of shape {radii.shape}; give one radius "
                             "per centre")
    if not (np.all(np.isfinite(centers)) and np.all(np.isfinite(radii)) and np.all(radii > 0)):
        raise ParameterError("obstacles: every centre must be finite and every radius positive and finite")
    return centers, radii


def choose_mode(mode: str, n, dim: int, batch) -> tuple[str, str | None]:
    """The mode a run takes, and why when ``mode == "auto"`` chose it (else None).

    ``"auto"``: fast for more than ``AUTO_FAST_ABOVE`` spheres, where its fill matches the
    faithful mode's sooner; faithful for few spheres and when ``batch`` (a faithful-mode option)
    is not 1.
    """
    if mode not in ("auto", "faithful", "fast"):
        raise ParameterError(f"mode must be 'auto', 'faithful' or 'fast', got {mode!r}")
    if mode != "auto":
        return mode, None
    if batch != 1:
        return "faithful", f"auto: batch={batch} is a faithful-mode option"
    if n <= AUTO_FAST_ABOVE:
        return "faithful", f"auto: n={n} is at most {AUTO_FAST_ABOVE}"
    return "fast", f"auto: n={n} is more than {AUTO_FAST_ABOVE} in {dim}-D"


def _centers_only(shape, reach: float, name: str):
    """The shape a ``centers_only`` run packs: ``shape`` grown by ``reach`` (the largest radius,
    given as ``name``), checked."""
    if not np.isfinite(reach):
        raise ParameterError(f"centers_only=True needs {name}: how far a sphere may reach past the walls (the shape "
                             "is grown by it, and the spheres are kept by their centres)")
    if period_of(shape) is not None:
        raise ParameterError("centers_only=True applies to walls, and a periodic domain's cell wraps: not both yet; "
                             "leave out centers_only or Periodic")
    return shape.offset(reach)


def _check_run(shape, on_invalid, on_round) -> str:
    """The checks every driver makes of the shape and of ``on_round``; returns ``on_invalid``,
    checked (see :func:`_on_invalid`)."""
    on_invalid = _on_invalid(on_invalid)
    if on_round is not None and not callable(on_round):
        raise ParameterError(f"on_round must be a function of one argument (an ndpack.Round), got {on_round!r}")
    check_packable(shape)
    check_plugin_slopes(shape)
    return on_invalid


def _run_params(shape, backend, counts, iterations, restarts, seed, centers_only=False) -> dict:
    """The parameters every driver records: the grid, the schedules, the backend, the holes, and
    what inside means (centres only; a periodic cell)."""
    params = dict(
        grid=counts.tolist(), iterations=int(iterations), restarts=int(restarts), seed=seed, backend=backend.name,
        device=str(getattr(backend, "device", "cpu")), eps_start=EPS_START, eps_end=EPS_END,
        cooling_power=COOLING_POWER, polish_iterations=POLISH_ITERATIONS, safety_margin=SAFETY_MARGIN,
        fast_window=FAST_WINDOW, split_ratio=SPLIT_RATIO,
    )
    holes = recorded_holes(shape)
    if holes is not None:  # what inside means at a mesh's holes: verify and render reload it so
        params["holes"] = holes
    if centers_only:  # verify() checks the centres only
        params["centers_only"] = True
    period = period_of(shape)
    if period is not None:  # the cell and its periods, which the DEM files write as a periodic box
        params["bounds"], params["period"] = shape.bounds.tolist(), period.periods
    return params


#: pack_sizes refuses lists of more radii than this (memory of the prototypes and spheres).
MAX_SIZED = 50_000_000


def pack_sizes(
    shape: Oracle,
    distribution,
    *,
    n: int | None = None,
    solid_fraction: float | None = None,
    time_budget: float | None = None,
    grid=None,
    iterations: int = 50,
    restarts: int = 8,
    seed: int | None = 0,
    backend=None,
    device=None,
    progress: bool | None = None,
    on_invalid: str | None = None,
    on_round=None,
    centers_only: bool = False,
) -> Packing:
    """Fill ``shape`` with spheres whose radii follow a size distribution (granular and DEM beds).

    The distribution gives the list of radii (:meth:`~ndpack.drivers.sizes.SizeDistribution.radii`),
    ``n`` of them or as many as make up ``solid_fraction`` of the shape's volume; the largest
    go first, each where the prototypes' clearance field finds room for it, in fast-mode
    rounds (:class:`~ndpack.drivers.greedy.rounds.Sized`). Radii for which no room is left are given up and
    counted in ``packing.params["unplaced"]``; ``distribution.report(packing)`` measures what
    was achieved (Kolmogorov-Smirnov distance, class shares, solid fraction).

    Parameters
    ----------
    shape : Oracle
        Any ndpack shape or plug-in, bounded, of any dimension.
    distribution : SizeDistribution
        See :class:`ndpack.drivers.sizes.SizeDistribution` (``discrete``, ``cumulative``, ``lognormal``;
        by count or by mass).
    n : int, optional
        How many spheres.
    solid_fraction : float, optional
        Instead of ``n``: the share of the shape's volume the spheres should fill (the count
        follows from the distribution's mean volume). A fraction the shape cannot take ends
        with radii unplaced, the smallest ones last.
    centers_only : bool
        Only the centres must lie inside (see :func:`pack`), the shape grown by the largest
        radius; a radius whose sphere came out with its centre outside goes back to the list.
    Others
        As in :func:`pack` (its fast mode).

    Returns
    -------
    Packing
        Verified in float64, like every packing; ``stop_reason`` is ``"count"`` when every radius
        was placed, ``"no_room"`` when some were given up.
    """
    shape = as_oracle(shape)
    check_compatible(shape)
    if not isinstance(distribution, SizeDistribution):
        raise ParameterError("distribution must be an ndpack.SizeDistribution (SizeDistribution.discrete, "
                             f".cumulative or .lognormal), got {distribution!r}")
    if (n is None) == (solid_fraction is None):
        raise ParameterError("give either n (the number of spheres) or solid_fraction (the share of the volume), "
                             "not both and not neither")
    if solid_fraction is not None and not (_number(solid_fraction) and 0 < solid_fraction < 1):
        raise ParameterError(f"solid_fraction must lie in (0, 1), got {solid_fraction!r}")
    _check_parameters(1 if n is None else n, 0.0, None, time_budget, iterations, 1, restarts, seed)
    on_invalid = _check_run(shape, on_invalid, on_round)
    if solid_fraction is not None:
        volume = shape.volume().value
        count = max(1, int(round(solid_fraction * volume / distribution.mean_volume(shape.dim))))
    else:
        assert n is not None  # one of the two, checked above
        count = int(n)
    if count > MAX_SIZED:
        raise ParameterError(f"the distribution asks for {count:,} spheres, more than {MAX_SIZED:,}: ask for a lower "
                             "solid_fraction or n, or larger radii")
    radii = distribution.radii(shape.dim, int(count))
    if radii[0] > 0.5 * float(np.max(shape.bounds[1] - shape.bounds[0])):
        raise ParameterError(f"the distribution's largest radius, {radii[0]:.4g}, is more than half the shape's "
                             "largest extent: no such sphere fits; scale the distribution to the shape")
    period = period_of(shape)
    if period is not None and radii[0] >= 0.5 * period.shortest:
        raise ParameterError(f"the distribution's largest radius, {radii[0]:.4g}, is at least half the shortest "
                             f"period, {period.shortest:.4g}: such a sphere meets its own image; scale the "
                             "distribution to the cell")
    packed = _centers_only(shape, float(radii[0]), "a distribution") if centers_only else shape
    backend = get_backend(backend, device=device, shape=packed)
    counts = grid_counts(packed.bounds, grid)
    polish_ahead = POLISH_AHEAD if backend.launch_bound else None
    ratio = split_ratio(backend.launch_bound)
    params = dict(
        n=int(count), distribution=distribution.description, solid_fraction=solid_fraction, time_budget=time_budget,
        mode="sized", size_band=SIZE_BAND, fast_eps_end=FAST_EPS_END, fast_polish_eps_end=FAST_POLISH_EPS_END,
        polish_ahead=polish_ahead, polish_ahead_eps_start=None if polish_ahead is None else AHEAD_EPS_START,
        **_run_params(shape, backend, counts, iterations, restarts, seed, centers_only),
    )
    params["split_ratio"] = ratio

    def strategy(state):
        return Sized(state, radii, polish_ahead=polish_ahead, ratio=ratio)

    packing, sized = run(packed, backend, strategy, counts=counts, mode="fast", iterations=iterations,
                         restarts=restarts, seed=seed, n=len(radii), radius_range=(0.0, np.inf), fill=None,
                         time_budget=time_budget, progress=progress, on_invalid=on_invalid, on_round=on_round,
                         params=params, centers_in=shape if centers_only else None)
    # Given up for want of room (radii not reached by a time limit or an interrupt are not counted).
    packing.params["unplaced"] = int(len(sized.unplaced))
    packing.params["unplaced_largest"] = float(sized.unplaced.max()) if len(sized.unplaced) else None
    return packing


def run(shape, backend, strategy, *, counts, mode, iterations, restarts, seed, n, radius_range, fill, time_budget,
        progress, on_invalid, on_round, params, centers_in=None, obstacles=None):
    """One packing run of a driver whose parameters are checked: places the prototypes, runs
    the rounds of ``strategy(state)`` (a round strategy of :mod:`ndpack.drivers.greedy.rounds`, made over
    the run's :class:`RunState`) until a limit, and returns the packing, verified in float64,
    and the strategy (what it kept of the run). ``radius_range`` is ``(min_radius,
    max_radius)``; ``params`` are recorded in the packing. With ``centers_in`` (the user's shape,
    ``shape`` being it grown by the largest radius: :func:`_centers_only`) only the spheres whose
    centres lie in it count and are returned, verified by their centres. ``obstacles`` (centres
    (m, d), radii (m,), or None) are spheres in place from the start."""
    started = time.perf_counter()
    steps, polish_steps = schedules(mode, int(iterations))
    deadline = None if time_budget is None else started + time_budget
    if shape.dim <= 3:  # the checks' grids, where this machine has not compiled them: by a helper meanwhile
        compile_ahead.start(close_pairs.ahead_jobs() + overlaps.ahead_jobs())
    state = RunState(shape, backend, counts, steps, polish_steps, int(restarts), run_key(np.random.default_rng(seed)),
                     deadline, time_budget, centers_in, obstacles)
    shape = shape if centers_in is None else centers_in
    volume = shape.volume()
    if not volume.value > 0:
        raise ShapeError(
            f"the volume of {shape!r} came out as {volume.value:g}: the shape is too thin for a "
            "Monte Carlo estimate over its bounds; tighten the bounds or give the shape an exact volume"
        )
    strategy = strategy(state)
    medial_axis, medial_radii = state.prototypes.all()
    stats = []  # (seconds, count, fill) after each round
    show = sys.stderr.isatty() if progress is None else progress
    bar = tqdm(total=int(n), unit="sphere", disable=not show, dynamic_ncols=True)
    try:
        stop_reason = _run_rounds(state, strategy, int(n), radius_range, fill, volume.value,
                                  started, stats, bar, on_round)
    except KeyboardInterrupt:
        stop_reason = "interrupted"
    finally:
        bar.close()
    if stop_reason in ("no_room", "min_radius") and state.searched is not None:
        params["final_search"] = dict(state.searched, halvings=SEARCH_HALVINGS)
    table = np.array(stats, dtype=np.float64).reshape(-1, 3)  # seconds, count, fill
    inside = state.inside[: state.count]
    packing = Packing(
        centers=state.centers[: state.count][inside],
        radii=state.radii[: state.count][inside],
        rounds=state.rounds[: state.count][inside],
        volume=volume.value,
        volume_error=volume.error,
        stats=RoundStats(table[:, 0], table[:, 1].astype(np.int64), table[:, 2]),
        medial_axis=medial_axis,
        medial_radii=medial_radii,
        params=params,
        stop_reason=stop_reason,
        shape=shape,
    )
    precision = getattr(backend, "precision", "float64")
    distances = state.centre_distances.collect(state.count)
    packing = _ensure_valid(packing, shape, state.margin, precision, on_invalid,
                            None if distances is None else distances[inside])
    if obstacles is not None:
        packing = _clear_of(packing, obstacles, state.margin, precision, on_invalid)
    return packing, strategy


@dataclass(frozen=True)
class Round:
    """What :func:`pack` tells its ``on_round`` function after each round.

    Attributes
    ----------
    index : int
        The round, from 0.
    centers : (k, d) float64 and radii : (k,) float64
        The spheres this round placed, largest first.
    count : int
        Spheres placed so far.
    fill : float
        Fraction of the shape's volume they cover.
    seconds : float
        Since the run started (prototype placement included).
    state : RunState
        The run itself (prototypes, cells, spheres), to look at, not to change.
    """

    index: int
    centers: np.ndarray
    radii: np.ndarray
    count: int
    fill: float
    seconds: float
    state: RunState


def _run_rounds(state, strategy, n, radius_range, fill, volume, started, stats, bar, on_round):
    """The rounds of one run, until a limit; returns why it stopped. ``radius_range`` is
    ``(min_radius, max_radius)``. Appends each round's (seconds, count, fill) to ``stats``,
    whole, so that an interrupt leaves whole rows."""
    min_radius, max_radius = radius_range
    covered = 0.0
    while True:
        if state.inside_count >= n:
            return "count"
        if fill is not None and covered / volume >= fill:
            return "fill"
        if state.out_of_time():
            return "time"
        cap = min(max_radius, state.image_reach)  # a periodic domain's images reach only so far
        centers, radii = strategy.choose(state, min_radius, n - state.inside_count, cap)
        if len(radii) == 0 and state.revive():
            centers, radii = strategy.choose(state, min_radius, n - state.inside_count, cap)
        if len(radii) == 0 and strategy.searches and state.search(min_radius):
            centers, radii = strategy.choose(state, min_radius, n - state.inside_count, cap)
        if len(radii) == 0:
            if state.out_of_time():  # a revival cut short proves nothing about room
                return "time"
            return "min_radius" if min_radius > 0 else "no_room"
        inside = state.insert(centers, radii, len(stats))
        covered += float(ball_volume(state.dim, radii[inside]).sum())
        if state.inside_count < n:  # nothing to prepare for a round that will not come
            strategy.after_round(state, centers, radii, n - state.inside_count)
            # A GPU moves the prototypes now, the host waiting: the final check's distances meanwhile.
            state.centre_distances.catch_up()
        stats.append((time.perf_counter() - started, state.inside_count, covered / volume))
        bar.update(int(inside.sum()))
        bar.set_postfix(fill=f"{covered / volume:.4f}", refresh=False)
        if on_round is not None and on_round(Round(len(stats) - 1, centers[inside], radii[inside], state.inside_count,
                                                   covered / volume, stats[-1][0], state)):
            return "callback"


def _on_invalid(value: str | None) -> str:
    """``pack``'s ``on_invalid``, or ``$NDPACK_ON_INVALID``, or ``"repair"``, checked."""
    import os

    where = "on_invalid"
    if value is None:
        value, where = os.environ.get("NDPACK_ON_INVALID") or "repair", "NDPACK_ON_INVALID"
    if value not in ("repair", "raise"):
        raise ParameterError(f"{where} must be 'repair' or 'raise', got {value!r}")
    return value


def _clear_of(packing: Packing, obstacles, margin: float, precision: str, on_invalid: str) -> Packing:
    """The packing, checked in float64 against ``obstacles`` (centres (m, d), radii (m,)): a new
    sphere that overlaps one is shrunk to clear it by ``margin`` (or dropped), as
    :func:`_ensure_valid` repairs, or raises with ``on_invalid="raise"``."""
    centers, radii = obstacles
    if len(packing) == 0 or len(radii) == 0:
        return packing
    count, period = len(radii), period_of(packing.shape)
    tol = DEFAULT_TOLERANCE * packing.shape.scale if packing.shape is not None else 0.0
    pairs, _ = overlapping_pairs(np.concatenate([centers, packing.centers]), np.concatenate([radii, packing.radii]),
                                 tol, period)
    pairs = pairs[(pairs[:, 0] < count) & (pairs[:, 1] >= count)]  # obstacle, new sphere
    if len(pairs) == 0:
        return packing
    found = f"{len(np.unique(pairs[:, 1]))} new sphere(s) overlapped the obstacles given"
    cause = (f"the {precision} backend's rounding exceeded its safety margin" if precision != "float64"
             else "the backend computed clearances wrongly")
    if on_invalid == "raise":
        raise InvalidPackingError(f"the packing failed its final check: {found}; {cause}. {KEPT_IN_ERROR}",
                                  packing=packing)
    new_radii = packing.radii.copy()
    for obstacle, index in pairs:
        new = index - count
        delta = packing.centers[new] - centers[obstacle]
        if period is not None:
            delta = period.difference(packing.centers[new][None], centers[obstacle][None])[0]
        new_radii[new] = min(new_radii[new], np.linalg.norm(delta) - radii[obstacle] - margin)
    keep = new_radii > 0
    warnings.warn(f"{found}; they were shrunk or dropped: {cause}", RepairWarning, stacklevel=3)
    repaired = packing.replace_spheres(packing.centers[keep], new_radii[keep], packing.rounds[keep])
    repaired.repair = {**(packing.repair or {}), "obstacle_overlaps": int(len(pairs)), "cause": cause}
    return repaired


def _ensure_valid(packing: Packing, shape: Oracle, margin: float, precision: str = "float64",
                  on_invalid: str = "repair", centre_distances: np.ndarray | None = None) -> Packing:
    """Verify in float64; repair (shrink or drop) any sphere that fails, or raise.

    With a conservative oracle and a float64 backend this never triggers; it guards against
    plug-ins that are not conservative, against float32 rounding on the GPU, and against a
    faulty backend. A repaired packing is no longer the greedy packing the driver made, so the
    repair is recorded in ``packing.repair`` and announced with a :class:`RepairWarning`.
    Then :func:`~ndpack.consistency.ensure_possible` checks what verification cannot see: a
    plug-in's slope across each sphere, and the spheres' volume against the shape's.
    ``centre_distances`` (n,) float64: ``shape``'s signed distance at the packing's centres, where
    the run computed it already (:class:`~ndpack.drivers.greedy.centre_distances.CentreDistances`).
    """
    report = verify_with(packing, shape, centre_distances=centre_distances)
    if report.ok:
        return ensure_possible(packing, shape, on_invalid, margin)
    if precision != "float64":
        cause = f"the {precision} backend's rounding exceeded its safety margin"
    else:
        cause = ("the shape's distance is probably not conservative (1-Lipschitz; see "
                 "ndpack.Function.check_lipschitz), or the backend computed clearances wrongly")
    found = (f"{len(report.outside)} sphere(s) poked out and {len(report.overlapping)} pair(s) overlapped "
             f"({report.summary()})")
    if on_invalid == "raise":
        raise InvalidPackingError(f"the packing failed its final check: {found}; {cause}. "
                                  f"Pass on_invalid='repair' to shrink or drop those spheres instead. {KEPT_IN_ERROR}",
                                  packing=packing)
    radii = packing.radii.copy()
    for index in report.outside:
        radii[index] = -shape._distance(packing.centers[index : index + 1])[0] - margin
    for i, j in report.overlapping:
        later = max(i, j)
        other = min(i, j)
        gap = np.linalg.norm(packing.centers[later] - packing.centers[other]) - radii[other]
        radii[later] = min(radii[later], gap - margin)
    keep = radii > 0
    changed = radii != packing.radii
    repair = {
        "outside": int(len(report.outside)),
        "overlapping_pairs": int(len(report.overlapping)),
        "shrunk": int((changed & keep).sum()),
        "dropped": int((~keep).sum()),
        "worst_poke_out": float(report.worst_containment),
        "worst_overlap": float(report.worst_overlap),
        "cause": cause,
    }
    warnings.warn(
        f"{found}; {repair['shrunk']} were shrunk and {repair['dropped']} dropped: {cause}. "
        "The repair is recorded in packing.repair; on_invalid='raise' raises instead",
        RepairWarning,
        stacklevel=3,
    )
    packing = packing.replace_spheres(packing.centers[keep], radii[keep], packing.rounds[keep])
    packing.repair = repair
    report = verify(packing, shape)
    if not report.ok:  # shrinking can only help; this is a last line of defence
        raise ShapeError(f"could not repair the packing: {report.summary()}")
    return ensure_possible(packing, shape, on_invalid, margin)
