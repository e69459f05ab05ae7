"""Dense granular beds: random close packings by collective rearrangement (:func:`pack_dense`).

The greedy drivers place spheres one after another in the largest gaps (an Apollonian packing);
a granular bed is something else: all its particles jammed together at once, random, at a
solid fraction near random close packing (about 0.64 for equal spheres in 3-D). This driver
makes one the way jamming studies do (O'Hern, Silbert, Liu and Nagel, 2003): the particles start
at random places, their radii a common ``scale`` times the drawn sizes, and soft springs push
overlapping ones apart (:mod:`ndpack.geometry.soft_contacts`; the walls are the shape's distance:
a particle pokes out by ``r + distance(centre)``) while FIRE (Bitzek et al., 2006) minimises the
overlap energy. Where the energy reaches zero the bed is *free* and the scale grows; where it
cannot (forces balanced with overlaps left) the bed is *jammed* and the scale shrinks; each
change of direction halves the step, until it is below ``PRECISION``. The densest free bed is
kept, shrunk by a common factor until no two spheres overlap and none pokes out (in float64),
and checked like every packing.
"""

from __future__ import annotations

import sys
import time
from dataclasses import dataclass

import numpy as np
from tqdm.auto import tqdm

from ..errors import InvalidPackingError, ParameterError, ShapeError
from ..geometry.period import period_of
from ..geometry.soft_contacts import close_pairs, contact_forces, fire_move, largest_move, neighbour_lists, periods
from ..oracle import ball_volume, check_compatible
from ..packing import Packing, RoundStats
from ..reproducible import root
from ..shapes.adapters import as_oracle
from ..verify import verify
from .sizes import SizeDistribution

#: Random close packing (jamming) fractions of equal spheres by dimension, from the literature
#: (2-D: a bidisperse disc mix), where a quench starts: ``START_SHARE`` of them.
JAMMING = {1: 1.0, 2: 0.84, 3: 0.64, 4: 0.46, 5: 0.31, 6: 0.20}
#: A quench starts at this share of the dimension's jamming fraction (or of the fraction asked).
START_SHARE = 1.05
#: The first change of the radii's scale between relaxations (relative).
FIRST_STEP = 0.01
#: The search stops when a step of the scale falls below this (relative; the fraction to d times it).
PRECISION = 2e-4
#: A bed is free when no pair overlaps by more than this share of its reach (nor any wall), the
#: rest taken by the final shrink.
FREE = 1e-8
#: A relaxation is jammed when its forces balance with overlaps left: the squared force below
#: this share of the energy (a bed that still relaxes keeps them of one order) ...
BALANCED = 1e-10
#: ... or, near jamming, where relaxing slows down without end, when it is not free after this
#: many FIRE steps. Against 2,000 (2 cores, seed 0): equal spheres in a periodic cube at 30,000
#: filled 0.6392 against 0.6407 in 22.9 s against 43.5 s, in 4-D at 10,000 0.4535 against 0.4553.
MAX_STEPS = 1000
#: Neighbour lists reach this share of the mean diameter beyond contact, and are rebuilt when a
#: sphere has moved half of it.
SKIN = 0.25
#: FIRE's constants (Bitzek et al. 2006; time in units of the unit-stiffness, unit-mass spring).
FIRE_DT, FIRE_DT_MAX, FIRE_ALPHA, FIRE_DELAY = 0.05, 0.5, 0.1, 5
#: A particle that the walls squeeze by more than this share of its radius, and by more than this
#: many times the bed's typical overlap, after a relaxation that did not free the bed, is wedged
#: in a part too thin for it, and starts again elsewhere (:meth:`Bed.reseat_wedged`).
WEDGED, WEDGED_OVER = 0.1, 5.0
#: The search stops after this many relaxations, whatever its step (a bed that never frees
#: shrinks by the first step each time).
MAX_RELAXATIONS = 60
#: Two spheres are in contact when their gap is at most this share of their reach (a wall: of the radius).
CONTACT_GAP = 1e-3
#: Most random tries per particle for a start inside the shape.
START_TRIES = 1000


@dataclass
class Relaxed:
    """How one relaxation ended: ``free`` or not, its FIRE steps and largest overlap left."""

    free: bool
    steps: int
    overlap: float


class Bed:
    """Particles at ``centers`` (n, d) with sizes ``sizes`` (n,) in ``shape``: radii are
    ``scale * sizes``; holds the neighbour lists and which particles may touch a wall."""

    def __init__(self, shape, centers, sizes, compiled: bool):
        self.shape, self.sizes, self.compiled = shape, sizes, compiled
        self.period = period_of(shape)
        self.lengths = periods(self.period, shape.dim)
        self.centers = centers if self.period is None else self.period.wrap(centers)
        self.mean_diameter = 2.0 * float(sizes.mean())
        self._built_at = None
        self._built_scale = -1.0
        self.pair_overlap = np.zeros(len(sizes))  # each sphere's largest relative overlap, at the last forces

    def _lists(self, scale: float) -> None:
        """The neighbour lists and near-wall particles, rebuilt when a particle has moved half
        the skin since they were built, or the radii grew."""
        skin = SKIN * scale * self.mean_diameter
        if self._built_at is not None and scale <= self._built_scale:
            if largest_move(self.centers, self._built_at, self.lengths, self.compiled) <= (0.5 * skin) ** 2:
                return
        if self.period is not None:
            self.centers = self.period.wrap(self.centers)
        reach = 2.0 * scale * float(self.sizes.max()) + skin
        self.starts, self.neighbours = neighbour_lists(self.centers, reach, self.period)
        distance = self.shape._distance(self.centers)
        self.near_wall = np.flatnonzero(distance > -(scale * self.sizes + skin))
        self._built_at, self._built_scale = self.centers.copy(), scale

    def forces(self, scale: float):
        """Forces (n, d), the energy, and the largest relative overlap at radii ``scale * sizes``."""
        self._lists(scale)
        radii = scale * self.sizes
        forces, energy, overlap = contact_forces(self.centers, radii, self.starts, self.neighbours, self.lengths,
                                                 self.compiled)
        self.pair_overlap = overlap
        total, worst = float(energy.sum()), float(overlap.max(initial=0.0))
        if len(self.near_wall):
            ids = self.near_wall
            distance, gradient = self.shape._distance_and_gradient(self.centers[ids])
            depth = radii[ids] + distance
            poking = depth > 0
            if poking.any():
                ids, depth, gradient = ids[poking], depth[poking], gradient[poking]
                forces[ids] -= depth[:, None] * gradient
                total += 0.5 * float(np.dot(depth, depth))
                worst = max(worst, float((depth / radii[ids]).max()))
        return forces, total, worst

    def relax(self, scale: float) -> Relaxed:
        """FIRE until no overlap is left (free), or the forces balance with overlaps left or
        ``MAX_STEPS`` pass (not free: jammed, or too near jamming to tell)."""
        velocity = np.zeros_like(self.centers)
        dt, alpha, since = FIRE_DT, FIRE_ALPHA, 0
        forces, energy, worst = self.forces(scale)
        for step in range(MAX_STEPS):
            if worst < FREE:
                return Relaxed(True, step, worst)
            squared_force = float(np.vdot(forces, forces))
            if squared_force < BALANCED * energy:
                return Relaxed(False, step, worst)
            power = float(np.vdot(forces, velocity))
            if power > 0:
                since += 1
                if since > FIRE_DELAY:
                    dt, alpha = min(dt * 1.1, FIRE_DT_MAX), alpha * 0.99
            else:
                self.centers -= 0.5 * dt * velocity  # back half a step, as FIRE 2.0 does
                velocity[:] = 0.0
                since, dt, alpha = 0, dt * 0.5, FIRE_ALPHA
            fire_move(self.centers, velocity, forces, dt, alpha, self.compiled)
            forces, energy, worst = self.forces(scale)
        return Relaxed(worst < FREE, MAX_STEPS, worst)

    def reseat_wedged(self, scale: float, rng) -> int:
        """Particles wedged in a part of the shape too thin for them (a mesh's leg or ear), from
        which no push gets them out, start again at random places where they fit; how many did.
        Wedged: the walls squeeze it by more than ``WEDGED`` of its radius and by more than
        ``WEDGED_OVER`` times the bed's typical overlap (a bed pressed against its walls
        squeezes every particle there about as much as its neighbours do)."""
        radii = scale * self.sizes
        squeeze = 1.0 + self.shape._distance(self.centers) / radii
        overlap = self.pair_overlap  # of the relaxation's last forces, at these centres
        typical = float(np.median(overlap[overlap > 0])) if (overlap > 0).any() else 0.0
        wedged = np.flatnonzero((squeeze > WEDGED) & (squeeze > WEDGED_OVER * typical))
        if len(wedged):
            order = wedged[np.argsort(-radii[wedged], kind="stable")]
            self.centers[order] = _start(self.shape, radii[order], rng)
            self._built_at = None
        return len(wedged)

    def largest_valid_scale(self, scale: float) -> float:
        """The largest scale up to ``scale`` at which no two spheres overlap and none pokes out
        at the present centres, in float64, a hair below (so the check's rounding cannot bite);
        0 where a centre is not inside."""
        clearance = -self.shape._distance(self.centers)
        if not (clearance > 0).all():
            return 0.0
        fits = [scale, float((clearance / self.sizes).min())]
        if self.period is not None:  # no sphere as wide as a period: it would meet its own image
            fits.append(0.5 * self.period.shortest / float(self.sizes.max()))
        rows, cols, distance = close_pairs(self.centers, 2.0 * scale * float(self.sizes.max()) * (1.0 + 1e-6),
                                           self.period)
        if len(rows):
            fits.append(float((distance / (self.sizes[rows] + self.sizes[cols])).min()))
        return min(fits) * (1.0 - 1e-9)


def _sizes(shape, sizes, n, solid_fraction, volume) -> np.ndarray:
    """The particles' sizes (n,) float64, largest first: a distribution's radii, equal radii, or
    the radii given."""
    dim = shape.dim
    if isinstance(sizes, SizeDistribution):
        count = n if n is not None else int(round(solid_fraction * volume / sizes.mean_volume(dim)))
        return sizes.radii(dim, max(count, 1))
    values = np.asarray(sizes, dtype=np.float64).reshape(-1)
    if len(values) == 0 or not np.all(np.isfinite(values)) or np.any(values <= 0):
        raise ParameterError(f"sizes must be a SizeDistribution, a radius or radii (positive numbers), got {sizes!r}")
    if len(values) > 1:
        if n is not None and n != len(values):
            raise ParameterError(f"n={n} but {len(values)} radii were given: give one or the other")
        return np.sort(values)[::-1].copy()
    count = n if n is not None else int(round(solid_fraction * volume / float(ball_volume(dim, values[0]))))
    return np.full(max(count, 1), values[0])


def _start(shape, radii, rng) -> np.ndarray:
    """Centres (n, d) drawn uniformly inside the shape (by rejection in its bounds), each where
    its sphere of ``radii`` (n,), largest first, fits the walls: a particle started in a part too
    thin for it (a mesh's leg or ear) could not get out, and its size would bound the bed's."""
    lower, upper = shape.bounds
    count = len(radii)
    found = np.empty((count, shape.dim))
    placed, tries = 0, 0
    while placed < count:
        batch = max(256, 2 * (count - placed))
        points = lower + rng.random((batch, shape.dim)) * (upper - lower)
        clearance = -shape._distance(points)
        for point, room in zip(points[clearance >= radii[-1]], clearance[clearance >= radii[-1]]):
            if room >= radii[placed]:
                found[placed] = point
                placed += 1
                if placed == count:
                    break
        tries += batch
        if tries > START_TRIES * count and placed < count:
            raise ShapeError(f"found room for only {placed:,} of {count:,} particles in {tries:,} random points over "
                             f"the bounds of {shape!r}: the shape is too thin for its bounds or for the particles "
                             f"(the {placed + 1}th needs a radius of {radii[placed]:.4g})")
    return found


def _grid_order(points, bounds, side: float) -> np.ndarray:
    """The order (n,) int64 of ``points`` (n, d) by the cell of side ``side`` that holds each, cell
    after cell along the last axis, then the one before, and so on."""
    cells = np.floor((points - bounds[0]) / side).astype(np.int64)
    return np.lexsort(cells.T[::-1])


def contacts(centers, radii, shape, period=None, gap: float = CONTACT_GAP) -> dict:
    """Contact statistics of a bed: the mean number of contacts a particle (``mean``; walls
    count), the wall contacts, the rattlers (fewer than d + 1 contacts) and the mean among the
    others (``backbone_mean``, 2d at isostatic jamming of frictionless spheres); a contact is a
    gap of at most ``gap`` of the pair's reach (a wall: of the radius)."""
    count, dim = centers.shape
    rows, cols, distance = close_pairs(centers, 2.0 * float(radii.max()) * (1.0 + gap), period)
    touching = distance <= (radii[rows] + radii[cols]) * (1.0 + gap)
    per_particle = np.bincount(rows[touching], minlength=count) + np.bincount(cols[touching], minlength=count)
    walls = -shape._distance(centers) <= radii * (1.0 + gap)
    per_particle = per_particle + walls
    rattlers = per_particle < dim + 1
    backbone = per_particle[~rattlers]
    return dict(mean=float(per_particle.mean()), wall=int(walls.sum()), rattlers=int(rattlers.sum()),
                backbone_mean=float(backbone.mean()) if len(backbone) else 0.0, gap=gap)


def pack_dense(
    shape,
    sizes,
    *,
    n: int | None = None,
    solid_fraction: float | None = None,
    seed: int | None = 0,
    backend: str | None = None,
    time_budget: float | None = None,
    progress: bool | None = None,
) -> Packing:
    """A dense random bed: particles of the given sizes jammed together in ``shape``.

    All particles move and grow together (see the module's docstring) until the bed jams, or
    until it reaches ``solid_fraction``. Walls are the shape's distance, so any container
    works (meshes, CSG, manifold3d solids, outlines, plug-ins); ``nd.Periodic(box)`` gives a
    periodic cell; any dimension.

    Parameters
    ----------
    shape : Oracle
        A bounded shape, any dimension.
    sizes : SizeDistribution, float or (n,) array_like
        The particles' radii: drawn from a distribution (its quantiles,
        :meth:`~ndpack.drivers.sizes.SizeDistribution.radii`), one radius for equal spheres, or
        the radii themselves.
    n : int, optional
        How many particles (radii given one by one are as many): the bed jams, its radii the
        sizes times a common factor (``params["scale"]``), as large as they can be and fit.
    solid_fraction : float, optional
        Instead of ``n``: the sizes as given, as many as fill this share of the shape's
        volume. A fraction above what the particles can jam at gives the jammed bed, its radii
        scaled down to fit (``params["scale"]`` < 1, ``stop_reason`` ``"jammed"``).
    seed : int
        The random start; the same seed gives the same bed.
    backend : {"numba", "numpy"}, optional
        Where the contact forces run: Numba (default) or the NumPy reference.
    time_budget : float, optional
        Seconds; the densest bed found so far is returned when they are spent (as on Ctrl-C).
    progress : bool, optional
        A progress bar of the solid fraction (default: when writing to a terminal).

    Returns
    -------
    Packing
        Verified in float64: no overlap, every sphere inside. ``params["contacts"]`` holds
        the contact statistics (:func:`contacts`), ``params["scale"]`` the factor on the sizes,
        ``params["relaxations"]`` the search's steps (scale, free, FIRE steps).
    """
    started = time.perf_counter()
    shape = as_oracle(shape)
    check_compatible(shape)
    if not shape.is_bounded:
        raise ShapeError(f"a dense bed needs a bounded shape (a container); {shape!r} is unbounded: intersect it "
                         "with a box")
    listed = not isinstance(sizes, SizeDistribution) and np.size(sizes) > 1
    if listed and solid_fraction is not None:
        raise ParameterError("the radii were given one by one, so their count is set: give no solid_fraction (the bed "
                             "jams, the radii scaled by one factor), or one radius or a SizeDistribution with it")
    if not listed and (n is None) == (solid_fraction is None):
        raise ParameterError("give either n (the number of particles) or solid_fraction (the share of the volume), "
                             "not both and not neither")
    if n is not None and (isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1):
        raise ParameterError(f"n must be a positive whole number, got {n!r}")
    if solid_fraction is not None and not (isinstance(solid_fraction, (int, float)) and 0 < solid_fraction < 1):
        raise ParameterError(f"solid_fraction must lie in (0, 1), got {solid_fraction!r}")
    if backend not in (None, "numba", "numpy"):
        raise ParameterError(f"pack_dense runs its contact forces with backend='numba' or 'numpy', not {backend!r} "
                             "(the GPU backends do not run dense beds yet)")
    volume = shape.volume()
    sizes_ = _sizes(shape, sizes, n, solid_fraction, volume.value)
    dim, count = shape.dim, len(sizes_)
    period = period_of(shape)
    solids = float(ball_volume(dim, sizes_).sum())  # the particles' volume at scale 1
    guess = JAMMING.get(dim, JAMMING[6] * 0.5 ** (dim - 6))
    target = 1.0 if solid_fraction is not None else np.inf
    scale = root(START_SHARE * min(guess, solid_fraction or guess) * volume.value / solids, dim)
    scale = min(scale, target)
    largest = 0.5 * (period.shortest if period is not None else float(np.min(np.ptp(shape.bounds, axis=0))))
    if solid_fraction is not None and sizes_[0] >= largest:
        raise ParameterError(f"the largest radius, {sizes_[0]:.4g}, is at least half the container's "
                             f"{'shortest period' if period is not None else 'narrowest extent'} ({2 * largest:.4g}): "
                             "scale the sizes to the container")
    rng = np.random.default_rng(seed)
    centers = _start(shape, scale * sizes_, rng)
    # Particles numbered along a grid of cells of about a diameter, so that neighbours are near in
    # memory: 1.45x faster forces at 100,000 (the sizes stay where they were drawn).
    order = _grid_order(centers, shape.bounds, 2.0 * scale * float(sizes_.mean()))
    centers, sizes_ = centers[order], sizes_[order]
    bed = Bed(shape, centers, sizes_, compiled=backend != "numpy")
    deadline = None if time_budget is None else started + float(time_budget)
    best_scale, best_centers = 0.0, bed.centers.copy()
    step, grew = FIRST_STEP, None
    history, stats = [], []
    stop_reason = "jammed"
    show = sys.stderr.isatty() if progress is None else progress
    bar = tqdm(total=None, unit="relaxation", disable=not show, dynamic_ncols=True)
    try:
        while True:
            result = bed.relax(scale)
            # Every relaxation's bed, shrunk until nothing overlaps, is a candidate: a jammed one
            # by its small overlaps, a free one by a hair.
            fits = bed.largest_valid_scale(scale)
            history.append((scale, result.free, result.steps, fits))
            if fits > best_scale:
                best_scale, best_centers = fits, bed.centers.copy()
            if not result.free:
                bed.reseat_wedged(scale, rng)  # for the next relaxation
            fraction = solids * best_scale**dim / volume.value
            stats.append((time.perf_counter() - started, count, fraction))
            bar.update(1)
            bar.set_postfix(fraction=f"{fraction:.4f}", step=f"{step:.1e}")
            if result.free and scale >= target:
                stop_reason = "fraction"
                break
            if grew is not None and grew != result.free:
                step *= 0.5  # the direction changed: halve the step
            grew = result.free
            if step < PRECISION and best_scale > 0:
                break
            if len(history) >= MAX_RELAXATIONS and best_scale > 0:
                stop_reason = "relaxations"
                break
            if result.free:
                scale = min(scale * (1.0 + step), target)
            else:  # a bed far above jamming (a candidate far below) goes halfway there at once
                scale = min(scale / (1.0 + step), float(np.sqrt(scale * fits)) if fits > 0 else scale)
            if deadline is not None and time.perf_counter() > deadline and best_scale > 0:
                stop_reason = "time"
                break
    except KeyboardInterrupt:
        stop_reason = "interrupted"
    finally:
        bar.close()
    if best_scale == 0.0 and stop_reason == "interrupted":
        raise KeyboardInterrupt  # before any bed was made: nothing to keep
    if best_scale == 0.0:
        raise InvalidPackingError("the bed never relaxed to a state with every centre inside (interrupted before "
                                  "the first relaxation ended, or the shape's gradient points the wrong way)")
    bed.centers = best_centers
    final = best_scale
    centers = bed.centers if period is None else period.wrap(bed.centers)
    radii = final * sizes_
    table = np.array(stats, dtype=np.float64).reshape(-1, 3)
    packing = Packing(
        centers=centers, radii=radii, rounds=np.zeros(count, dtype=np.int64), volume=volume.value,
        volume_error=volume.error,
        stats=RoundStats(table[:, 0], table[:, 1].astype(np.int64), table[:, 2]),
        params=dict(
            mode="dense", n=count, solid_fraction=solid_fraction, seed=seed, backend=backend or "numba",
            distribution=sizes.description if isinstance(sizes, SizeDistribution) else None,
            scale=final, relaxations=[dict(scale=s, free=f, steps=k, fits=v) for s, f, k, v in history],
            contacts=contacts(centers, radii, shape, period),
            period=None if period is None else period.periods,
            bounds=shape.bounds.tolist() if period is not None else None,
            seconds=time.perf_counter() - started,
        ),
        stop_reason=stop_reason,
        shape=shape,
    )
    verification = verify(packing, shape)
    if not verification:
        raise InvalidPackingError(f"the dense bed failed its float64 check: {verification.summary()}")
    return packing
