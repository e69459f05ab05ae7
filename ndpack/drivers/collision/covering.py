"""Coverings: spheres whose union holds a shape and reaches at most a given distance outside it.

Collision checkers (robot motion planners, physics engines) stand a part in for a few dozen
spheres that must *cover* it, so that no contact is missed, and protrude as little as possible.
A packing's spheres are inside the part and cover only part of it; a covering's spheres hold
all of it.

How a covering is made
----------------------
A ball of centre ``c`` whose clearance (distance to the boundary, ``-f(c)``) is ``d`` and whose
radius is ``d + t`` reaches at most ``t`` outside the shape: the ball of radius ``d`` is inside,
and every point of the larger ball is within ``t`` of it. This holds for every conservative
oracle (a lower bound of the distance only makes ``d`` smaller). A covering that protrudes at most
``t`` is therefore a set cover of the shape by such balls, and it is made on samples:

1. Candidate centres: the medial-axis sample of a packing's first round (ProtoSphere's converged
   prototypes) and, for a share of the boundary samples, the centre of the largest inscribed
   ball touching there (the shrinking-ball method, a bisection along the inward normal).
2. Samples of the boundary and of the inside (:mod:`ndpack.drivers.collision.boundary`) make the set to cover;
   the inside is drawn in a grid of cells known to be inside (:mod:`ndpack.drivers.collision.inside_cells`), so
   that few points need a distance.
3. A greedy set cover (within a factor ``ln n`` of the fewest balls) picks balls of radius
   ``d + t``; balls it made redundant are dropped. Samples no candidate reaches get a ball of
   their own.
4. Local refinement: each ball shrinks to the samples it serves best (the fewest reaching out),
   plus a seam (the share :data:`SEAM_SHARE` of ``t`` kept back in step 3; half the samples'
   spacing for a count), which lowers the mean protrusion.
5. Gaps between samples: fresh samples are drawn; each one found outside the union is served by
   growing the ball that then reaches out least (within ``t``), or by a new ball, until a fresh
   set is covered (at most :data:`FIX_PASSES` sets).
6. The check (:func:`check_covering`) on samples not used so far; where it finds a point outside
   the union, that point is served as in step 5 and a new check is drawn (at most
   :data:`CHECKS`), so that the report is always on samples the covering was not fitted to.

Given a count instead of a tolerance, the smallest ``t`` whose cover needs at most that many balls
is found by bisection (on fewer samples where the balls are large), and step 5 grows balls
without limit, so the count holds and the protrusion is what it takes.

Coverage is checked, not proven: :func:`check_covering` counts fresh boundary and interior
samples outside the union, and reports the protrusion bound and the volume covered outside.

Long runs: before any work, a protrusion whose covering :func:`estimate_count` puts at more
spheres than ``max_spheres`` or ``samples`` is refused (:class:`TooManySpheres`); the compiled
queries run in pieces of a fraction of a second (:func:`ndpack.geometry.ball_union.pieces`, :class:`_InPieces`),
so that Ctrl-C is seen between them, and an interrupted run returns the last whole step's covering,
flagged (:attr:`Covering.interrupted`).
"""

from __future__ import annotations

import math
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from tqdm.auto import tqdm

from ... import io
from ...errors import ParameterError
from ...geometry import ball_union
from ...oracle import Oracle, as_points, check_packable
from ...packing import Packing
from ...shapes.adapters import as_oracle
from ...shapes.mesh import mesh_notes, recorded_holes
from . import sphere_tree
from .boundary import sample_cells
from .boundary import samples as shape_samples
from .estimate import MAX_SPHERES, refuse_too_many
from .inside_cells import InsideCells
from .set_cover import FIX_PASSES, SEAM_SHARE, Problem, _cover_at, _InPieces, _protrusions, _refine, _thin

#: Boundary samples the cover is made on (the inside gets a quarter as many more).
DEFAULT_SAMPLES = 20_000
#: Fresh boundary samples of the final check (the inside gets a quarter as many more).
CHECK_SAMPLES = 50_000
#: Checks on fresh samples, at most: where one finds a gap, it is served and a new check drawn.
CHECKS = 3
#: A sample this far outside the union (relative to the shape's scale) still counts as covered:
#: float64 rounding of the distances.
GAP_TOLERANCE = 1e-9
#: Fresh boundary samples of the quick check an interrupted covering is reported on (a second, not minutes).
INTERRUPTED_CHECK_SAMPLES = 5_000


@dataclass
class CoverReport:
    """How well spheres cover a shape, checked in float64 against its oracle on fresh samples.

    Attributes
    ----------
    boundary_samples, interior_samples : int
        Samples drawn on the boundary and inside.
    boundary_covered, interior_covered : float
        The fraction of each inside the union of the spheres (up to :attr:`gap_tolerance`).
    worst_gap : float
        The farthest any sample lies outside the union (<= 0 when every one is inside).
    gap_tolerance : float
        Rounding allowed: samples at most this far outside count as covered.
    max_protrusion, mean_protrusion : float
        Over the spheres, of ``r + f(c)``: a bound of how far each reaches outside the shape, exact
        for a convex shape's spheres (valid for centres inside, or where the oracle is exact
        outside). 0 for a sphere inside.
    diagonal : float
        The shape's bounding-box diagonal, the unit of the relative figures.
    outside_volume, outside_volume_error : float
        Volume of the union outside the shape (Monte Carlo over the union's bounds) and its
        standard error.
    shape_volume : float
    """

    boundary_samples: int
    interior_samples: int
    boundary_covered: float
    interior_covered: float
    worst_gap: float
    gap_tolerance: float
    max_protrusion: float
    mean_protrusion: float
    diagonal: float
    outside_volume: float
    outside_volume_error: float
    shape_volume: float

    @property
    def covered(self) -> bool:
        """Every sample, on the boundary and inside, is in the union."""
        return self.worst_gap <= self.gap_tolerance

    @property
    def outside_ratio(self) -> float:
        """Volume covered outside the shape over the shape's volume."""
        return self.outside_volume / self.shape_volume

    def summary(self) -> str:
        covered = "all covered" if self.covered else (
            f"NOT COVERED: {1 - self.boundary_covered:.2%} of boundary and {1 - self.interior_covered:.2%} of "
            f"interior samples outside (worst by {self.worst_gap:.3g})")
        return (f"{covered} ({self.boundary_samples} boundary, {self.interior_samples} interior samples); "
                f"protrusion max {self.max_protrusion:.4g} ({self.max_protrusion / self.diagonal:.2%} of the "
                f"diagonal), mean {self.mean_protrusion:.4g}; volume outside {self.outside_ratio:.1%} of the shape's")


@dataclass
class Covering:
    """Spheres whose union covers a shape (see :func:`cover`).

    Attributes
    ----------
    centers : (n, d) float64
    radii : (n,) float64
    protrusion : (n,) float64
        Each sphere's bound of how far it reaches outside the shape, ``r + f(c)`` (0 if inside).
    report : CoverReport
        The check on fresh samples.
    params : dict
        The run's parameters: ``n`` or ``protrusion`` as asked, ``tolerance`` (the protrusion the
        cover was made for), samples, seed, candidates, passes (fresh sets drawn to close gaps),
        checks (checks drawn; the report is the last one's), holes (as :func:`ndpack.pack` records
        it), notes (see :attr:`notes`) and seconds.
    shape : Oracle
    """

    centers: np.ndarray
    radii: np.ndarray
    protrusion: np.ndarray
    report: CoverReport
    params: dict = field(default_factory=dict)
    shape: Oracle | None = field(default=None, repr=False, compare=False)

    @property
    def dim(self) -> int:
        return self.centers.shape[1]

    def __len__(self) -> int:
        return len(self.radii)

    @property
    def interrupted(self) -> bool:
        """Whether Ctrl-C stopped the run: the spheres are what it had made (``params["interrupted"]``
        names the step it stopped in), and may leave gaps that the report (on fewer samples) counts."""
        return bool(self.params.get("interrupted"))

    @property
    def notes(self) -> list[str]:
        """What the shape's meshes were made into before covering (holes capped, welded vertices,
        inside by winding number for a surface that crosses itself): the spheres cover that solid."""
        return list(self.params.get("notes", []))

    def summary(self) -> str:
        notes = "".join(f"\n  note: {note}" for note in self.notes)
        stopped = (f"INTERRUPTED (Ctrl-C) while {self.params['interrupted']}, kept what was made: "
                   if self.interrupted else "")
        return (f"{stopped}{len(self)} spheres in {self.dim}-D covering {self.shape!r}: "
                f"{self.report.summary()}{notes}")

    def __repr__(self) -> str:
        return f"<Covering {self.summary()}>"

    def as_packing(self) -> Packing:
        """The spheres as a :class:`~ndpack.Packing` (to save in any sphere format); its
        ``params["covering"]`` holds this run's parameters. Its spheres overlap and reach out of
        the shape, so :meth:`Packing.verify` fails on it: check it with :func:`check_covering`
        (``ndpack verify`` does, for a saved covering)."""
        volume = self.report.shape_volume
        params = {"covering": dict(self.params)}
        if self.params.get("holes") is not None:  # verify and render reload the mesh the same way
            params["holes"] = self.params["holes"]
        return Packing(self.centers.copy(), self.radii.copy(), np.zeros(len(self), np.int64), volume,
                       params=params, stop_reason="interrupted" if self.interrupted else "covered",
                       shape=self.shape)

    def save(self, path, format: str | None = None, **options) -> Path:
        """Write the spheres in any of :func:`ndpack.io.table`'s formats (``.sph`` as a 2-level
        tree, ``format="curobo"`` as one link's ``collision_spheres``); returns the path.
        For a hierarchy, save :meth:`tree`."""
        return io.save(self.as_packing(), path, format, **options)

    def tree(self, branching: int = 8, depth: int = 3, seed: int = 0) -> sphere_tree.SphereTree:
        """A sphere-tree over this covering's shape whose deepest level has at most
        ``branching ** (depth - 1)`` spheres; see :func:`.sphere_tree.covering_tree`."""
        return sphere_tree.covering_tree(self.shape, branching=branching, depth=depth, seed=seed)


# ------------------------------------------------------------------------------------------------ driver
def cover(
    shape: Oracle,
    n: int | None = None,
    protrusion: float | None = None,
    *,
    samples: int = DEFAULT_SAMPLES,
    check_samples: int = CHECK_SAMPLES,
    packing=None,
    seed: int = 0,
    backend=None,
    device=None,
    progress: bool | None = None,
    max_spheres: int | None = MAX_SPHERES,
) -> Covering:
    """Spheres whose union covers ``shape``, each reaching at most a given distance outside it.

    Parameters
    ----------
    shape : Oracle
        Any bounded ndpack shape, of any dimension: a mesh, CSG, a polygon, a plug-in.
    n : int, optional
        At most this many spheres, protruding as little as that allows.
    protrusion : float, optional
        No sphere reaches farther than this outside the shape (a length; for example
        ``0.01 * diagonal``), with as few spheres as the greedy cover finds. Give ``n`` or
        ``protrusion``, not both.
    samples : int
        Boundary samples the cover is made on (and a quarter as many inside); more samples
        leave fewer gaps for the fresh samples to close.
    check_samples : int
        Fresh boundary samples of the final check (:attr:`Covering.report`).
    packing : Packing, optional
        A packing of this shape whose medial-axis sample (and spheres) seed the candidates;
        default: one round of the fast mode is run for it.
    seed : int
        Seed of every random sample; equal seeds give equal coverings.
    backend, device :
        Run the packing that finds the medial-axis sample on this backend (see :func:`ndpack.pack`),
        and, for shapes other than meshes and outlines, the distance queries on its compiled
        float64 kernels (:class:`CompiledQueries`).
    progress : bool, optional
        Show a progress bar (a tick per step: samples, the cover, each set of fresh samples,
        each check; the spheres so far beside it); by default only when stderr is a terminal.
    max_spheres : int or None
        A ``protrusion`` whose covering is estimated (:func:`estimate_count`, within a factor of
        about 2) to need more spheres than this, or than ``samples`` (the cover could not place
        them: it would leave gaps), is refused before any work, with :class:`TooManySpheres`
        giving the estimate and a protrusion that would do: such a run takes hours. None: no
        limit but ``samples``.

    Returns
    -------
    Covering
        Its ``report`` says whether fresh samples are all covered, and the protrusion.

    Raises
    ------
    TooManySpheres
        Where ``protrusion`` calls for more than ``max_spheres`` spheres, or than ``samples``.
    KeyboardInterrupt
        Where Ctrl-C comes before the first cover is made (or a second one during the check that
        follows the first).

    Notes
    -----
    Ctrl-C (KeyboardInterrupt) is seen several times a second, and a run interrupted after its
    first cover returns the covering made so far (the last whole step's), with
    :attr:`Covering.interrupted` set and a report on :data:`INTERRUPTED_CHECK_SAMPLES` fresh samples:
    it may leave gaps, which the report counts.
    """
    started = time.perf_counter()
    shape = as_oracle(shape)
    check_packable(shape)
    _check_request(n, protrusion, samples, check_samples, max_spheres)
    if protrusion is not None:
        refuse_too_many(shape, float(protrusion), max_spheres, int(samples))
    show = sys.stderr.isatty() if progress is None else progress
    steps = _Steps(show)
    kept: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None  # the last whole step's (centers, radii, clearance)
    checks, passes, stopped = 0, 0, None
    try:
        steps.start("samples and candidates")
        problem = Problem.make(shape, samples, packing, seed, backend, device, compiled=True)
        # The check asks the shape itself (the reference), in its own cells.
        reference, cells = (problem.shape, problem.cells) if problem.is_reference else (_InPieces(shape), None)
        steps.done()
        steps.start("the cover")
        # The cover is made for a share of the tolerance; the rest (the seam) is added to every
        # radius at the end, so that the neighbourhood of every covered sample is covered too.
        everything = np.arange(len(problem.points))
        if protrusion is not None:
            tolerance = float(protrusion)
            inner, limit = (1 - SEAM_SHARE) * tolerance, tolerance
            sub_points, sub_ids, tree = _thin(problem.points, problem.candidates, problem.clearances, inner,
                                              problem.rng)
            chosen = sub_ids[_cover_at(sub_points, problem.candidates[sub_ids], problem.clearances[sub_ids], inner,
                                       tree)]
            centers, clearance = problem.candidates[chosen], problem.clearances[chosen]
            centers, radii, clearance = problem.serve(everything, centers, clearance + tolerance, clearance, inner,
                                                      limit, tolerance - inner)
            radii, keep = _refine(problem.points, centers, radii, clearance, tolerance - inner)
            centers, radii, clearance = centers[keep], radii[keep], clearance[keep]
        else:
            assert n is not None  # a count, where no protrusion was given (checked above)
            centers, radii, clearance, inner = problem.cover_count(everything, int(n))
            tolerance, limit = inner + 0.5 * problem.spacing, None
        kept = centers, radii, clearance
        steps.done(len(radii))
        steps.start(f"closing gaps (fresh samples, set 1 of at most {FIX_PASSES})")
        for passes, kept in enumerate(problem.close_gaps(*kept, inner, limit, tolerance - inner), 1):
            steps.done(len(kept[1]))
            steps.start(f"closing gaps (fresh samples, set {passes + 1} of at most {FIX_PASSES})")
        steps.done(count=FIX_PASSES - passes)
        for checks in range(1, CHECKS + 1):
            steps.start(f"checking on {check_samples} fresh samples ({checks} of at most {CHECKS})")
            report, missed, missed_normals = _check(reference, kept[0], kept[1], check_samples, 200_000,
                                                    seed + checks, cells)
            steps.done(len(kept[1]))
            if report.covered or checks == CHECKS:
                break
            # The check found points between every sample so far: serve them, and check on fresh ones.
            kept = problem.fix(missed, missed_normals, kept[0], kept[1], kept[2], inner, limit, tolerance - inner)
            report = None
        reach = _protrusions(reference, *kept[:2])
        steps.done(len(kept[1]), count=steps.left)
    except KeyboardInterrupt:
        if kept is None:
            raise
        stopped = steps.what
        steps.start("interrupted: a quick check of what was made")
        report = _check(reference, *kept[:2], INTERRUPTED_CHECK_SAMPLES, 4 * INTERRUPTED_CHECK_SAMPLES,
                        seed + CHECKS + 1, cells)[0]
        reach = _protrusions(reference, *kept[:2])
    finally:
        steps.close()
    centers, radii, _ = kept
    params = {"n": None if n is None else int(n), "protrusion": None if protrusion is None else float(protrusion),
              "tolerance": tolerance, "samples": int(samples), "seed": int(seed),
              "candidates": len(problem.candidates), "passes": passes, "checks": checks,
              "holes": recorded_holes(shape), "notes": mesh_notes(shape), "seconds": time.perf_counter() - started}
    if stopped is not None:
        params["interrupted"] = stopped
    return Covering(centers, radii, reach, report, params, shape)


class _Steps:
    """A covering's progress bar: a tick a step (samples and candidates, the cover, each set of fresh
    samples, each check), the step's name before it and the spheres so far after it."""

    def __init__(self, show):
        self.bar = tqdm(total=2 + FIX_PASSES + CHECKS, desc="covering", unit="step", disable=not show,
                        dynamic_ncols=True, bar_format="{desc}: {n_fmt}/{total_fmt} steps [{elapsed}{postfix}]")
        self.what = None

    def start(self, what: str) -> None:
        self.what = what
        self.bar.set_description_str(f"covering: {what}", refresh=True)

    def done(self, spheres: int | None = None, count: int = 1) -> None:
        if spheres is not None:
            self.bar.set_postfix_str(f"{spheres:,} spheres", refresh=False)
        self.bar.update(count)

    @property
    def left(self) -> int:
        return self.bar.total - self.bar.n

    def close(self) -> None:
        self.bar.close()


def _check_request(n, protrusion, samples, check_samples, max_spheres=None):
    if (n is None) == (protrusion is None):
        raise ParameterError("give either n (the most spheres) or protrusion (how far a sphere may reach "
                             "outside the shape), not both and not neither")
    if n is not None and (isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1):
        raise ParameterError(f"n must be a positive integer, got {n!r}")
    if protrusion is not None and not (isinstance(protrusion, (int, float, np.floating)) and protrusion > 0
                                       and math.isfinite(protrusion)):
        raise ParameterError(f"protrusion must be a positive length, got {protrusion!r}; for a share of the shape's "
                             "size, multiply by its bounding-box diagonal")
    for name, value in (("samples", samples), ("check_samples", check_samples)):
        if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 100:
            raise ParameterError(f"{name} must be an integer of at least 100, got {value!r}")
    if max_spheres is not None and (isinstance(max_spheres, bool) or not isinstance(max_spheres, (int, np.integer))
                                    or max_spheres < 1):
        raise ParameterError(f"max_spheres must be a positive integer or None (no limit), got {max_spheres!r}")


# ------------------------------------------------------------------------------------------------ the check
def check_covering(shape: Oracle, centers, radii, *, samples: int = CHECK_SAMPLES, volume_samples: int = 200_000,
                   seed: int = 1, cells: InsideCells | None = None) -> CoverReport:
    """Check in float64 how well spheres cover ``shape``: fresh boundary and interior samples
    outside their union, how far they reach outside the shape, and the volume they cover there.

    Parameters
    ----------
    shape : Oracle
    centers : (n, d) array_like
    radii : (n,) array_like
    samples : int
        Boundary samples (and a quarter as many inside).
    volume_samples : int
        Monte Carlo points for the volume outside.
    seed : int
    cells : InsideCells, optional
        The shape's grid of inside and outside cells (:func:`ndpack.drivers.collision.boundary.sample_cells`), if
        already built: it spares most distances.

    Returns
    -------
    CoverReport
    """
    shape = as_oracle(shape)
    centers = as_points(centers, shape.dim).reshape(-1, shape.dim)
    radii = np.asarray(radii, dtype=np.float64).reshape(-1)
    if radii.shape != (len(centers),) or not np.all(np.isfinite(radii)):
        raise ParameterError(f"radii must be {len(centers)} finite numbers, one per centre; got shape {radii.shape}")
    return _check(shape, centers, radii, samples, volume_samples, seed, cells)[0]


def _check(shape, centers, radii, samples, volume_samples, seed, cells=None):
    """:func:`check_covering`'s report, and the samples outside the union with their normals
    (zero rows inside)."""
    rng = np.random.default_rng(seed)
    cells = sample_cells(shape) if cells is None else cells
    points, normals = shape_samples(shape, samples, rng, cells)
    tolerance = GAP_TOLERANCE * shape.scale
    all_gaps = ball_union.gaps(points, centers, radii)
    boundary_gaps, inside_gaps = all_gaps[:samples], all_gaps[samples:]
    protrusion = _protrusions(shape, centers, radii)
    volume = float(shape.volume().value)
    outside, error = _outside_volume(cells, centers, radii, volume_samples, rng)
    report = CoverReport(
        boundary_samples=len(boundary_gaps), interior_samples=len(inside_gaps),
        boundary_covered=float(np.mean(boundary_gaps <= tolerance)),
        interior_covered=float(np.mean(inside_gaps <= tolerance)),
        worst_gap=float(max(boundary_gaps.max(), inside_gaps.max())), gap_tolerance=tolerance,
        max_protrusion=float(protrusion.max(initial=0.0)),
        mean_protrusion=float(protrusion.mean()) if len(radii) else 0.0,
        diagonal=shape.diagonal,
        outside_volume=outside, outside_volume_error=error, shape_volume=volume)
    missed = all_gaps > tolerance
    return report, points[missed], normals[missed]


def _outside_volume(cells, centers, radii, count, rng):
    """Monte Carlo volume of the union of the balls outside the shape (of ``cells``), and its standard error."""
    if not len(radii):
        return 0.0, 0.0
    lower = (centers - radii[:, None]).min(axis=0)
    upper = (centers + radii[:, None]).max(axis=0)
    box = float(np.prod(upper - lower))
    points = lower + (upper - lower) * rng.random((count, len(lower)))
    in_union = np.flatnonzero(ball_union.covered(points, centers, radii))
    share = float(np.count_nonzero(~cells.inside(points[in_union]))) / count
    return box * share, box * math.sqrt(max(share * (1 - share), 0.25 / count ** 2) / count)

__all__ = ["Covering", "CoverReport", "cover", "check_covering"]
