"""One large domain in tiles, packed by several workers at once: :func:`pack_tiled` (issue 25).

A greedy packing's large spheres are few, and each one's place depends on all the others; its
small spheres are many, and each one's place depends only on its neighbours. So:

1. **The global phase**: one run of :func:`ndpack.pack` over the whole shape places every sphere
   down to the halo's width (a quarter of the shortest tile side).
2. **Bands**: the rest goes in bands of radius, each band's smallest radius ``band`` times its
   largest. In a band, each tile packs the shape inside its box grown by the halo, around the
   spheres already there (``pack``'s ``obstacles``: the global spheres and its neighbours'),
   down to the band's smallest radius.
3. **Phases**: a band runs in 2^d phases, one per colour: a tile's colour is the parity of its
   index along each axis, so two tiles of one colour lie a whole tile apart and their grown
   boxes (a quarter tile each way) never meet. The tiles of a phase run at once, on any workers,
   and their spheres cannot overlap; the next phase's tiles take them as obstacles.

The result is the same kind of greedy packing as ``pack``'s fast mode, which takes spheres
within 20% of the largest a round: here, within a band. Every sphere is checked at the end in
float64 against the whole shape and all the others (:func:`ndpack.verify`), whatever tile made
it. The tiles run where :class:`~ndpack.scale.workers.Workers` puts them: this process, a local pool of
processes (one per GPU, or several sharing one), or a Dask cluster of any number of hosts.
"""

from __future__ import annotations

import itertools
import math
import sys
import time
import warnings
from dataclasses import dataclass

import numpy as np
from tqdm.auto import tqdm

from ..drivers.greedy.protosphere import SAFETY_MARGIN, _check_parameters, _ensure_valid, _on_invalid, pack
from ..drivers.greedy.rounds import SPLIT_RATIO
from ..errors import GridWarning, ParameterError, ShapeError
from ..geometry.period import period_of
from ..oracle import ball_volume, check_compatible
from ..packing import Packing, RoundStats
from ..shapes.adapters import as_oracle
from ..shapes.periodic import Periodic
from ..shapes.primitives import Box
from .workers import Workers

#: The halo (how far a tile's box is grown each way) as a share of the shortest tile side. Below
#: half, two tiles of one colour (a tile apart) never meet; a quarter leaves each tile's grown box
#: a quarter tile clear of the other's, and spheres up to a quarter tile to the global phase.
HALO_SHARE = 0.25
#: Each band's smallest radius as a share of its largest (``band=``): the spheres of a band come
#: in any order, as the fast mode's within its window (0.8).
BAND = 0.6
#: The last band stops this far below the radius estimated to reach ``n`` (trimmed to ``n``
#: after): an estimate a little high costs a band more.
LAST_BAND_SLACK = 0.97
#: Default tiles: slabs across the longest axis, this many per worker. Slabs take 2 phases a
#: band (blocks take 2^d, each a wait for its slowest tile), and two tiles per worker a phase
#: even out tiles of unequal work. (2 cores, unit cube, 50,000 spheres, 2 workers: 8 slabs took
#: 8.7 s; 4 slabs 14.9 s; 4 x 2 x 2 blocks 14.9 s: thinner tiles also leave more to the global
#: phase, and fewer bands.)
SLABS_PER_WORKER = 4
#: A tile's grid (cells along its grown box's longest side) when ``grid`` is not given: cells
#: ``SPLIT_RATIO`` times the band's largest radius (as the fast mode splits them), at most this.
MAX_TILE_GRID = 128
#: Bands in a row that place nothing before the run stops for want of room.
EMPTY_BANDS = 3


@dataclass(frozen=True)
class Tiling:
    """The tiles over a shape's bounds.

    Attributes
    ----------
    lower : (d,) float64
        The bounds' lower corner (the cell's, for a periodic domain).
    size : (d,) float64
        A tile's sides.
    counts : (d,) int64
        Tiles along each axis.
    halo : float
        How far each tile's box is grown each way.
    periods : (d,) float64
        The period along each periodic axis, 0 along the others.
    """

    lower: np.ndarray
    size: np.ndarray
    counts: np.ndarray
    halo: float
    periods: np.ndarray

    @property
    def total(self) -> int:
        return int(np.prod(self.counts))

    def index(self, tile: int) -> np.ndarray:
        """A tile's index along each axis, (d,) int64."""
        return np.array(np.unravel_index(tile, tuple(self.counts)), dtype=np.int64)

    def colour(self, tile: int) -> int:
        """A tile's phase in a band: the parity of its index along each axis, as bits."""
        return int(sum(int(bit) << axis for axis, bit in enumerate(self.index(tile) % 2)))

    def grown_box(self, tile: int) -> tuple[np.ndarray, np.ndarray]:
        """A tile's box grown by the halo (not along an axis of one tile, which has no neighbour
        there): lower (d,), upper (d,)."""
        lower = self.lower + self.index(tile) * self.size
        halo = np.where(self.counts > 1, self.halo, 0.0)
        return lower - halo, lower + self.size + halo

    def neighbours(self, tile: int):
        """The tiles whose grown boxes may meet this one's (itself included), each with the shift
        (d,) that brings its spheres next to this tile across a periodic face: (tile, shift)."""
        index = self.index(tile)
        for step in itertools.product(*[(-1, 0, 1) if count > 1 else (0,) for count in self.counts]):
            other = index + np.array(step)
            shift = np.zeros(len(index))
            wrapped = (other < 0) | (other >= self.counts)
            if np.any(wrapped & (self.periods == 0)):
                continue
            shift[other < 0] = -self.periods[other < 0]
            shift[other >= self.counts] = self.periods[other >= self.counts]
            other = np.mod(other, self.counts)
            yield int(np.ravel_multi_index(tuple(other), tuple(self.counts))), shift


def make_tiling(bounds: np.ndarray, tiles, workers: int, period=None) -> Tiling:
    """The tiles of ``bounds`` (2, d): ``tiles`` per axis (an int or one per axis), or by default
    ``SLABS_PER_WORKER`` slabs per worker across the longest axis (see there). A periodic axis
    needs an even count (its first and last tiles meet, so they must differ in colour)."""
    dim = bounds.shape[1]
    if tiles is None:
        counts = np.ones(dim, dtype=np.int64)
        counts[int(np.argmax(bounds[1] - bounds[0]))] = SLABS_PER_WORKER * workers
    else:
        counts = np.broadcast_to(np.asarray(tiles), (dim,)) if np.ndim(tiles) == 0 else np.asarray(tiles)
        if (counts.shape != (dim,) or counts.dtype.kind not in "iu" or np.any(counts < 1)):
            raise ParameterError(f"tiles must be a positive integer or {dim} of them (tiles per axis), got {tiles!r}")
        counts = counts.astype(np.int64)
    periods = np.zeros(dim)
    if period is not None:
        periods = np.where(period.axes, period.lengths, 0.0)
        odd = np.flatnonzero(period.axes & (counts % 2 == 1) & (counts > 1))  # one tile wraps onto itself
        if len(odd):
            raise ParameterError(f"a periodic axis needs an even number of tiles (its first and last tiles meet); "
                                 f"axis {int(odd[0])} has {int(counts[odd[0]])}: give tiles= even along it")
    size = (bounds[1] - bounds[0]) / counts
    return Tiling(bounds[0].astype(np.float64), size, counts, HALO_SHARE * float(size.min()), periods)


@dataclass
class _TileTask:
    """One tile's work in one phase, as it travels to a worker."""

    tile: int
    lower: np.ndarray
    upper: np.ndarray
    obstacle_centers: np.ndarray
    obstacle_radii: np.ndarray
    min_radius: float
    room: int
    seed: int
    options: dict
    wraps: np.ndarray  # (d,) bool: the periodic axes of one tile, along which the tile wraps


def _tile_domain(shape, lower, upper, wraps):
    """What a tile packs: ``shape`` inside the box ``lower``, ``upper`` (d,). A periodic box is
    all space along its periodic axes, so its tile's box may reach past the cell; along the axes
    ``wraps`` (d,) bool, periodic and of one tile, the tile is the cell and wraps as it does."""
    if isinstance(shape, Periodic):
        bounds = shape.child.bounds
        periodic = shape.period.axes
        box = Box(np.where(periodic, lower, np.maximum(lower, bounds[0])),
                  np.where(periodic, upper, np.minimum(upper, bounds[1])))
        return Periodic(box, wraps) if wraps.any() else box
    if type(shape) is Box:  # a box again, whose volume is exact (an intersection's is sampled)
        return Box(np.maximum(lower, shape.lower), np.minimum(upper, shape.upper))
    return shape & Box(lower, upper)


def _pack_tile(shape, task: _TileTask) -> dict:
    """Pack one tile (in a worker): its new spheres' centres (k, d) and radii (k,), and seconds."""
    started = time.perf_counter()
    domain = _tile_domain(shape, task.lower, task.upper, task.wraps)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", GridWarning)  # a sliver of the shape in a corner tile
        try:
            packing = pack(domain, n=task.room, min_radius=task.min_radius, seed=task.seed, progress=False,
                           obstacles=(task.obstacle_centers, task.obstacle_radii),
                           **task.options)
        except ShapeError:  # no interior point found: a tile the shape barely touches
            packing = None
    if packing is not None and packing.stop_reason == "interrupted":  # Ctrl-C here (one worker): stop
        raise KeyboardInterrupt
    dim = len(task.lower)
    return dict(tile=task.tile, seconds=time.perf_counter() - started,
                centers=packing.centers if packing is not None else np.empty((0, dim)),
                radii=packing.radii if packing is not None else np.empty(0))


class _Spheres:
    """The spheres so far: the global phase's, and each tile's (in the unwrapped frame of the
    tile that made them, inside its grown box), to find a tile's obstacles fast."""

    def __init__(self, tiling: Tiling, centers, radii):
        self.tiling = tiling
        self.global_centers, self.global_radii = centers, radii
        self.by_tile: list[list[tuple]] = [[] for _ in range(tiling.total)]  # (centers, radii, phase) each
        self.count = len(radii)

    def add(self, tile: int, centers, radii, phase: int) -> None:
        if len(radii):
            self.by_tile[tile].append((centers, radii, phase))
            self.count += len(radii)

    def near(self, tile: int):
        """The spheres that reach into a tile's grown box: centres (m, d), radii (m,)."""
        lower, upper = self.tiling.grown_box(tile)
        parts = []
        for shift in self._shifts():  # the global spheres and their periodic images
            parts.append((self.global_centers + shift, self.global_radii))
        for other, shift in self.tiling.neighbours(tile):
            parts.extend((centers + shift, radii) for centers, radii, _ in self.by_tile[other])
        centers = np.concatenate([c for c, _ in parts]) if parts else np.empty((0, len(lower)))
        radii = np.concatenate([r for _, r in parts]) if parts else np.empty(0)
        gap = np.linalg.norm(centers - np.clip(centers, lower, upper), axis=1)
        reach = gap < radii
        return centers[reach], radii[reach]

    def _shifts(self):
        periods = self.tiling.periods  # along an axis of one tile, the tile's own run makes the images
        for step in itertools.product(*[(-1, 0, 1) if period > 0 and count > 1 else (0,)
                                        for period, count in zip(periods, self.tiling.counts)]):
            yield np.array(step) * periods

    def all(self, period=None):
        """Every sphere, the global ones first, then by the phase that made them: centres
        (n, d) (wrapped into a periodic cell), radii (n,), and the phase of each (n,), -1 for the
        global phase."""
        chunks = sorted((phase, tile, centers, radii) for tile, parts in enumerate(self.by_tile)
                        for centers, radii, phase in parts)
        centers = np.concatenate([self.global_centers] + [c for _, _, c, _ in chunks])
        radii = np.concatenate([self.global_radii] + [r for _, _, _, r in chunks])
        phases = np.concatenate([np.full(len(self.global_radii), -1)] + [np.full(len(r), p)
                                                                         for p, _, _, r in chunks])
        if period is not None:
            centers = period.wrap(centers)
        return centers, radii, phases


def pack_tiled(shape, n: int = 100_000, *, tiles=None, workers: int | None = None, client=None,
               gpus=None, band: float = BAND, min_radius: float = 0.0, seed: int = 0, progress: bool | None = None,
               on_invalid: str | None = None, **pack_options) -> Packing:
    """Fill ``shape`` with ``n`` spheres, largest first, the small ones tile by tile on several workers.

    See the module's text for the method. ``n`` spheres are packed with the spheres above the
    last band's radius; the smallest of the last band beyond ``n`` are left out.

    Parameters
    ----------
    shape : Oracle
        Any bounded ndpack shape or plug-in (picklable: it travels to the workers once), or a
        periodic box (``nd.Periodic(nd.Box(...))``).
    n : int
        Spheres in all.
    tiles : int or sequence of int, optional
        Tiles along each axis (even along a periodic axis); default 4 slabs per worker across
        the longest axis. The halo is a quarter of the shortest tile side, and the global phase
        packs every sphere larger than it.
    workers : int, optional
        Local processes (default ``os.cpu_count()``; 1 runs the tiles here, one by one).
        Ignored with ``client``.
    client : dask.distributed.Client, optional
        Run the tiles on this Dask cluster (dask-cuda's ``LocalCUDACluster`` for a worker per
        GPU, with ``device="cuda:0"``: each worker sees its own GPU as the first).
    gpus : sequence of int, optional
        Spread the local workers over these GPUs in turn, each seeing one as ``cuda:0`` (pass
        ``device="cuda:0"``); several workers may share a GPU (``workers=8, gpus=[0]``: on an
        H100, 8 processes packed 10M spheres 2.2x sooner than one run; docs/tiled.md).
    band : float
        Each band's smallest radius as a share of its largest, in (0, 1).
    min_radius : float
        Stop when no sphere this large fits, before ``n`` if need be.
    seed : int
        Seeds the global phase and each tile's run.
    progress : bool, optional
        A progress bar over the spheres; by default only when stderr is a terminal.
    on_invalid : {"repair", "raise"}, optional
        As for :func:`ndpack.pack`, for the final float64 check of all the spheres.
    **pack_options
        Passed to :func:`ndpack.pack` for the global phase and every tile (``mode``, ``grid``
        (cells per tile and of the global phase; by default each band's tiles get cells of
        about 4 times its largest radius), ``iterations``, ``restarts``, ``backend``, ``device``).

    Returns
    -------
    Packing
        Verified in float64 as a whole. ``rounds`` holds each sphere's global round, or for a
        tile's sphere the number of global rounds plus its phase. ``params["tiled"]`` records
        the tiles, the halo, the bands (smallest radius, spheres, seconds), the workers, the time
        in the global phase, in the tiles (summed) and in all, and how busy the workers were.
        Ctrl-C returns the spheres of the phases that finished (``stop_reason == "interrupted"``).
    """
    shape = as_oracle(shape)
    check_compatible(shape)
    for name in ("progress", "on_round", "obstacles", "n", "min_radius", "max_radius", "fill", "time_budget",
                 "centers_only", "batch"):
        if name in pack_options:
            raise ParameterError(f"pack_tiled does not take {name}= (a tile's run is set by the tiling): leave it out")
    _check_parameters(n, min_radius, None, None, 1, 1, 0, seed)  # pack's own checks of n, min_radius and seed
    if not (isinstance(band, float | int) and 0 < band < 1):
        raise ParameterError(f"band must lie in (0, 1) (each band's smallest radius over its largest), got {band!r}")
    on_invalid = _on_invalid(on_invalid)
    period = period_of(shape)
    if period is not None and not (isinstance(shape, Periodic) and isinstance(shape.child, Box)):
        raise ParameterError("pack_tiled takes a periodic box (nd.Periodic(nd.Box(...))) but no other periodic shape "
                             "yet; pack it with nd.pack")
    started = time.perf_counter()
    show = sys.stderr.isatty() if progress is None else progress
    bar = tqdm(total=int(n), unit="sphere", disable=not show, dynamic_ncols=True)
    try:
        with Workers(workers, client, shared=shape, gpus=gpus) as pool:
            tiling = make_tiling(shape.bounds, tiles, pool.count, period)
            first = pack(shape, n=n, min_radius=max(min_radius, tiling.halo), seed=seed, progress=False,
                         on_invalid=on_invalid, on_round=lambda step: bar.update(len(step.radii)), **pack_options)
            run = _TiledRun(shape, first, tiling, pool, n, band, min_radius, seed,
                            dict(pack_options, on_invalid=on_invalid), bar)
            if first.stop_reason == "min_radius" and first.params["min_radius"] > min_radius:
                run.bands(started)
                if run.stop_reason == "interrupted":
                    pool.stop()  # the tiles in flight are dropped (their phase had not finished), not waited for
    finally:
        bar.close()
    return run.packing(started, on_invalid)


class _TiledRun:
    """The bands of one :func:`pack_tiled` run after its global phase ``first``."""

    def __init__(self, shape, first, tiling, pool, n, band, min_radius, seed, options, bar):
        self.shape, self.first, self.tiling, self.pool = shape, first, tiling, pool
        self.n, self.band, self.min_radius, self.seed, self.options, self.bar = n, band, min_radius, seed, options, bar
        self.spheres = _Spheres(tiling, first.centers, first.radii)
        self.stop_reason = first.stop_reason
        self.global_seconds = float(first.stats.time[-1]) if len(first.stats.time) else 0.0
        self.records = []  # per band: smallest radius, spheres, seconds, tile seconds
        self.stats = []  # per phase: seconds since the start, count, fill
        self.task_seconds = self.phase_seconds = 0.0
        self.halo_spheres = 0  # spheres a tile made with their centre outside it (in the halo)
        self.volume = shape.volume().value
        self.covered = float(ball_volume(shape.dim, first.radii).sum())
        lower, upper = (np.stack([tiling.grown_box(t)[i] for t in range(tiling.total)]) for i in (0, 1))
        middle = (lower + upper) / 2
        # A tile whose grown box lies wholly outside the shape has nothing to pack.
        self.live = np.flatnonzero(shape._distance(middle) < np.linalg.norm(upper - middle, axis=1))

    def bands(self, started):
        self.started = started
        high, history, empty = self.first.params["min_radius"], [], 0
        history.append((high, self.spheres.count))
        try:
            while self.spheres.count < self.n:
                low, last = self._next_low(high, history)
                before, band_started, tile_seconds = self.spheres.count, time.perf_counter(), self.task_seconds
                try:
                    for colour in range(2 ** self.shape.dim):
                        self._phase(colour, high, low, len(self.records))
                        if self.spheres.count >= self.n:
                            break
                finally:  # a band cut short by Ctrl-C is recorded too, with the phases that finished
                    self.records.append(dict(min_radius=low, spheres=self.spheres.count - before,
                                             seconds=round(time.perf_counter() - band_started, 3),
                                             tile_seconds=round(self.task_seconds - tile_seconds, 3)))
                history.append((low, self.spheres.count))
                empty = empty + 1 if self.spheres.count == before else 0
                if self.spheres.count >= self.n:
                    self.stop_reason = "count"
                elif last:
                    self.stop_reason = "min_radius"
                    break
                elif empty >= EMPTY_BANDS or low < 1e3 * SAFETY_MARGIN * self.shape.scale:
                    self.stop_reason = "no_room"
                    break
                high = low
        except KeyboardInterrupt:
            self.stop_reason = "interrupted"

    def _next_low(self, high, history):
        """The next band's smallest radius, and whether it is the last band (it reaches
        ``min_radius``): ``band`` times the largest, or where the spheres so far say ``n`` will be
        reached if that is larger (their count grows as a power of the radius, the exponent taken
        from the last two bands)."""
        low = high * self.band
        count = history[-1][1]
        exponent = self.shape.dim - 0.5  # a greedy packing's count grows about as r^-(d - 0.5) before any band says
        if len(history) >= 2 and history[-1][1] > history[-2][1] > 0:
            exponent = math.log(history[-1][1] / history[-2][1]) / math.log(history[-2][0] / history[-1][0])
        reach = high * (self.n / max(count, 1)) ** (-1.0 / max(exponent, 0.5)) * LAST_BAND_SLACK
        last = False
        low = max(low, reach)  # a band more follows should the estimate fall short
        if low <= self.min_radius:
            low, last = self.min_radius, True
        return low, last

    def _phase(self, colour: int, high: float, low: float, band_index: int) -> None:
        """The tiles of one colour pack their grown boxes from ``high`` down to ``low``, at once."""
        phase = band_index * 2 ** self.shape.dim + colour
        options = dict(self.options)
        if options.get("grid") is None:  # cells as the fast mode splits them for the band's largest gaps
            side = float(np.max(self.tiling.size)) + 2 * self.tiling.halo
            options["grid"] = int(np.clip(round(side / (SPLIT_RATIO * high)), 2, MAX_TILE_GRID))
        tasks = {}
        for tile in self.live:
            if self.tiling.colour(tile) != colour:
                continue
            lower, upper = self.tiling.grown_box(tile)
            centers, radii = self.spheres.near(tile)
            seed = int(np.random.SeedSequence([self.seed, phase, int(tile)]).generate_state(1)[0])
            tasks[int(tile)] = _TileTask(int(tile), lower, upper, centers, radii, low, self.n - self.spheres.count,
                                         seed, options, (self.tiling.periods > 0) & (self.tiling.counts == 1))
        if not tasks:
            return
        phase_started = time.perf_counter()
        for tile, result, error in self.pool.run(_pack_tile, tasks):
            if error is not None:
                error.add_note(f"(in tile {tile} of {self.tiling.total}, box {self.tiling.grown_box(tile)[0]} to "
                               f"{self.tiling.grown_box(tile)[1]}, band {band_index + 1}, down to radius {low:.4g})")
                raise error
            self.spheres.add(tile, result["centers"], result["radii"], phase)
            self.task_seconds += result["seconds"]
            lower = self.tiling.lower + self.tiling.index(tile) * self.tiling.size
            outside = np.any((result["centers"] < lower) | (result["centers"] >= lower + self.tiling.size), axis=1)
            self.halo_spheres += int(outside.sum())
            self.covered += float(ball_volume(self.shape.dim, result["radii"]).sum())
            self.bar.update(len(result["radii"]))
        self.phase_seconds += time.perf_counter() - phase_started
        self.stats.append((time.perf_counter() - self.started, self.spheres.count, self.covered / self.volume))

    def packing(self, started, on_invalid) -> Packing:
        """The whole packing, ``n`` spheres at most (the smallest of the last band left out),
        verified in float64."""
        first, tiling = self.first, self.tiling
        if not self.records:
            return first
        centers, radii, phases = self.spheres.all(period_of(self.shape))
        rounds = int(first.rounds.max(initial=-1)) + 1 + phases
        rounds[: len(first)] = first.rounds  # the global spheres come first, in their order
        if len(radii) > self.n:  # the smallest beyond n: a subset of a valid packing is one
            keep = np.sort(np.argsort(-radii, kind="stable")[: self.n])
            centers, radii, rounds = centers[keep], radii[keep], rounds[keep]
        elapsed = time.perf_counter() - started
        times = [float(first.stats.time[-1]) if len(first.stats.time) else 0.0]
        counts, fills = [len(first)], [first.fill]
        for seconds, count, fill in self.stats:  # after each phase (the last one's before the trim to n)
            times.append(seconds)
            counts.append(min(count, self.n))
            fills.append(fill)
        tiled_spheres = max(1, int(sum(record["spheres"] for record in self.records)))
        busy = self.task_seconds / max(1e-12, self.pool.count * self.phase_seconds)
        params = dict(first.params)
        params.update(n=int(self.n), min_radius=float(self.min_radius), tiled=dict(
            tiles=[int(c) for c in tiling.counts], halo=tiling.halo, band=self.band, workers=self.pool.count,
            global_spheres=len(first), global_seconds=round(self.global_seconds, 3), bands=self.records,
            tile_seconds=round(self.task_seconds, 3), phase_seconds=round(self.phase_seconds, 3),
            seconds=round(elapsed, 3), busy_share=round(min(1.0, busy), 4),
            halo_share=round(self.halo_spheres / tiled_spheres, 4)))
        packing = Packing(centers=centers, radii=radii, rounds=rounds, volume=first.volume,
                          volume_error=first.volume_error,
                          stats=RoundStats(np.array(times), np.array(counts, dtype=np.int64), np.array(fills)),
                          medial_axis=first.medial_axis, medial_radii=first.medial_radii, params=params,
                          stop_reason=self.stop_reason, shape=self.shape)
        return _ensure_valid(packing, self.shape, SAFETY_MARGIN * self.shape.scale, "float64", on_invalid)
