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
2. Samples of the boundary and of the inside (:mod:`ndpack.boundary`) make the set to cover;
   the inside is drawn in a grid of cells known to be inside (:mod:`ndpack.inside_cells`), so
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
queries run in pieces of a fraction of a second (:func:`ndpack.ball_union.pieces`, :class:`_InPieces`),
so that Ctrl-C is seen between them, and an interrupted run returns the last whole step's covering,
flagged (:attr:`Covering.interrupted`).
"""

from __future__ import annotations

import itertools
import heapq
import math
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from scipy.spatial import cKDTree
from tqdm.auto import tqdm

from . import ball_union
from .ball_union import pieces
from .backends import get_backend
from .boundary import boundary_samples, exactly_sampled, project, sample_cells, samples as shape_samples
from .errors import ParameterError
from .inside_cells import InsideCells
from .oracle import Oracle, as_points, check_packable
from .packing import Packing
from .protosphere import pack
from .shapes.adapters import as_oracle
from .shapes.mesh import mesh_notes, recorded_holes

#: Boundary samples the cover is made on (the inside gets a quarter as many more).
DEFAULT_SAMPLES = 20_000
#: Fresh boundary samples of the final check (the inside gets a quarter as many more).
CHECK_SAMPLES = 50_000
#: Boundary samples whose shrinking ball becomes a candidate centre, at most.
SHRINKING_BALLS = 8_000
#: Bisection steps of a shrinking ball (its radius to 2^-18 of the largest clearance).
SHRINK_STEPS = 18
#: Sets of fresh samples drawn to close the gaps between samples, at most (two in a row must be
#: covered).
FIX_PASSES = 12
#: Checks on fresh samples, at most: where one finds a gap, it is served and a new check drawn.
CHECKS = 3
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
#: A sample this far outside the union (relative to the shape's scale) still counts as covered:
#: float64 rounding of the distances.
GAP_TOLERANCE = 1e-9
#: Spheres a protrusion may call for (:func:`estimate_count`) before :func:`cover` refuses it: a
#: million spheres take hours and gigabytes, and few collision checkers take more.
MAX_SPHERES = 1_000_000
#: Fresh boundary samples of the quick check an interrupted covering is reported on (a second, not minutes).
INTERRUPTED_CHECK_SAMPLES = 5_000
#: The factor of the effective radius of a covering's balls, ``KAPPA * sqrt(t p)`` (see
#: :func:`estimate_count`), fitted to runs of :func:`cover` (samples 20,000, protrusions of 4%, 2%,
#: 1%, 0.5% and 0.25% of the diagonal; 2 cores). :func:`estimate_count` over the count made: fandisk
#: 0.80-0.85 (86-6,327 spheres), cow 1.1-1.5 (44-3,201), armadillo 1.2-1.5 (135-1,360, to 0.5%),
#: box:dim=3 0.82-0.92 (114-7,299), demo 0.95 (84-483, to 1%), torus 0.96-1.16 (16-67, by the pilot),
#: ball:dim=3 2 (1), square 1.2-1.4 (10-48), annulus 1.3-1.6 (16-68), box:dim=4 0.37-0.48
#: (183-7,119, 8% to 2%: in 4-D the count grows faster than the estimate).
ESTIMATE_KAPPA = 0.72
#: Monte Carlo points of the estimate's boundary measure and volume (shapes other than meshes and
#: outlines), and the half-width of its band around the boundary, as a share of the bounds' largest extent.
ESTIMATE_POINTS = 2**15
ESTIMATE_BAND = 0.005
#: Boundary samples of the estimate's pilot, and the factor its count is taken with (round shapes:
#: the torus needs 1.7-2.1 times the pilot's count).
PILOT_SAMPLES = 4000
PILOT_FACTOR = 2.0
#: Points of a distance query asked at once, at first (:class:`_InPieces`; then sized by the time taken).
PIECE_POINTS = 8192


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
    shape: object = field(default=None, repr=False, compare=False)

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

    def as_packing(self):
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
        from .io import save

        return save(self.as_packing(), path, format, **options)

    def tree(self, branching: int = 8, depth: int = 3, seed: int = 0):
        """A sphere-tree over this covering's shape whose deepest level has at most
        ``branching ** (depth - 1)`` spheres; see :func:`ndpack.sphere_tree.covering_tree`."""
        from .sphere_tree import covering_tree  # lazily: sphere_tree builds on this module

        return covering_tree(self.shape, branching=branching, depth=depth, seed=seed)


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
        _refuse_too_many(shape, float(protrusion), max_spheres, int(samples))
    show = sys.stderr.isatty() if progress is None else progress
    steps = _Steps(show)
    kept, checks, passes, stopped = None, 0, 0, None  # kept: the last whole step's (centers, radii, clearance)
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
            report, missed, missed_normals = _check(reference, *kept[:2], check_samples, 200_000, seed + checks,
                                                    cells)
            steps.done(len(kept[1]))
            if report.covered or checks == CHECKS:
                break
            # The check found points between every sample so far: serve them, and check on fresh ones.
            kept = problem.fix(missed, missed_normals, *kept, inner, limit, tolerance - inner)
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


class TooManySpheres(ParameterError):
    """A protrusion whose covering would need more spheres than :func:`cover` takes on: more than
    ``max_spheres``, or more than the boundary ``samples`` the cover is made on can place (it would
    leave gaps, after a long run). Raised before any work.

    Attributes
    ----------
    expected : float
        The spheres :func:`estimate_count` expects.
    limit : int
        The limit passed: ``max_spheres``, or ``samples``.
    reason : str
        Which: ``"max_spheres"`` or ``"samples"``.
    protrusion : float
        The protrusion asked, a length.
    suggested : float
        A protrusion (a length) that calls for about ``suggested_count`` spheres.
    suggested_count : int
        A tenth of the limit.
    diagonal : float
        The bounding-box diagonal the protrusion is a share of.
    subject : str
        What was to be covered, where not the shape itself (``"link 'wrist'"``).
    """

    def __init__(self, *, expected, limit, reason, protrusion, suggested, suggested_count, diagonal, subject=""):
        self.expected, self.limit, self.reason, self.protrusion = expected, limit, reason, protrusion
        self.suggested, self.suggested_count = suggested, suggested_count
        self.diagonal, self.subject = diagonal, subject
        super().__init__(self.text())

    def __str__(self) -> str:
        return self.text()

    def text(self, asked: str | None = None, larger: str | None = None, count: str = "a count n",
             samples: str = "samples", lift: str = "raise max_spheres (None: no limit)") -> str:
        """The message in an interface's words: ``asked`` what was asked (default: the protrusion,
        as a length and a share of the diagonal), ``larger`` the protrusion to give instead,
        ``count`` and ``samples`` the options of a count and of the boundary samples, ``lift`` how
        to lift ``max_spheres``."""
        share = self.protrusion / self.diagonal
        asked = asked or f"a protrusion of {self.protrusion:.3g} ({share:.3%} of the bounding-box diagonal)"
        larger = larger or f"{self.suggested:.3g}, {self.suggested / self.diagonal:.2%} of the diagonal"
        text = (f"{self.subject + ': ' if self.subject else ''}{asked} calls for about {self.expected:,.0f} spheres "
                "(estimated from the shape, within a factor of about 2), ")
        instead = f"give a larger protrusion ({larger}, calls for some {self.suggested_count:,}) or {count}"
        if self.reason == "max_spheres":
            cost = ": such a run takes hours and gigabytes" if self.limit >= MAX_SPHERES else ""
            return f"{text}more than the limit of {self.limit:,}{cost}; {instead}, or {lift}"
        return (f"{text}more than the {self.limit:,} boundary samples the cover is made on can place: it would leave "
                f"gaps after a long run; {instead}, or pass {samples} of {_round_up(4 * self.expected):,} or more "
                "(a long run)")


def _refuse_too_many(shape, protrusion: float, max_spheres: int | None, samples: int) -> None:
    """:class:`TooManySpheres` where ``protrusion`` calls for more spheres (:func:`estimate_count`)
    than ``max_spheres`` or ``samples``: the first estimate, and the pilot only where that one is
    over (it is the smaller for round shapes)."""
    limit = samples if max_spheres is None else min(max_spheres, samples)
    measures = _measures(shape)
    expected = _expected(measures, shape.dim, protrusion)
    if expected <= limit:
        return
    expected = min(expected, _pilot(shape, measures[0], protrusion))
    if expected <= limit:
        return
    reason = "max_spheres" if max_spheres is not None and expected > max_spheres else "samples"
    limit = max_spheres if reason == "max_spheres" else samples
    target = max(limit // 10, 1)
    raise TooManySpheres(expected=expected, limit=limit, reason=reason, protrusion=protrusion,
                         suggested=_protrusion_for(measures, shape.dim, target), suggested_count=target,
                         diagonal=shape.diagonal)


def _round_up(value: float) -> int:
    """``value`` up to two significant digits (4,812,345 -> 4,900,000)."""
    if value < 100:
        return int(math.ceil(value))
    unit = 10 ** (int(math.log10(value)) - 1)
    return int(math.ceil(value / unit) * unit)


def estimate_count(shape: Oracle, protrusion: float) -> float:
    """About how many spheres :func:`cover` makes for a ``protrusion`` (a length), in about a
    second at most: what :func:`cover` checks ``max_spheres`` against before any work.

    Two estimates, the smaller taken:

    - From the boundary measure ``A`` (area in 3-D, length in 2-D) and volume ``V`` alone. A ball
      of radius ``r`` whose centre lies ``r - p`` inside a flat boundary covers a patch of radius
      ``sqrt(2 r p)`` of it, so about ``A / (V_{d-1} (2 r p)^((d-1)/2))`` balls are needed
      (``V_{d-1}`` the unit ``(d-1)``-ball's volume). The balls a covering keeps are not as large as
      the shape is thick (edges, corners and the candidates' spacing call for smaller ones):
      measured, their effective radius is about ``r = KAPPA sqrt(t p)``, ``t = d V / A`` the
      shape's mean thickness (a ball's or a cube's inradius), so the count grows like
      ``p^(-3(d-1)/4)``. Round shapes need far fewer (one ball covers a ball).
    - A pilot (which :func:`cover` runs only where the first estimate is over its limit):
      on :data:`PILOT_SAMPLES` boundary samples, the patch of samples each one's largest
      inscribed ball, grown by ``p``, covers (at least the flat one), summed as
      ``A / patch`` over the samples' shares and doubled (:data:`PILOT_FACTOR`). It sees the
      curvature that the first one does not.

    Accuracy, against the counts :func:`cover` made (samples 20,000; protrusions 0.25% to 4% of
    the diagonal; see :data:`ESTIMATE_KAPPA`): within a factor of 1.6 in 2-D and 3-D (the sample
    meshes, the cube, the demo part, the torus, the square, the annulus; 2 for the ball: one
    sphere, estimated as two), low by up to 2.7 in 4-D (the cube). The first estimate alone is
    60 times too high for the torus, 3,000 for the ball. Below about 0.1% of the diagonal a
    covering made on 20,000 samples leaves gaps, and its count grows faster than estimated.

    Parameters
    ----------
    shape : Oracle
    protrusion : float

    Returns
    -------
    float
        At least 1.
    """
    shape = as_oracle(shape)
    protrusion = float(protrusion)
    measures = _measures(shape)
    return min(_expected(measures, shape.dim, protrusion), _pilot(shape, measures[0], protrusion))


def _measures(shape) -> tuple[float, float]:
    """The boundary measure and the volume of ``shape``: exact for meshes and outlines, else by
    :data:`ESTIMATE_POINTS` Monte Carlo points in its bounds, those within :data:`ESTIMATE_BAND` of
    the boundary giving its measure (a band's volume over its width)."""
    if exactly_sampled(shape):
        if getattr(shape, "vertices", None) is not None:
            corners = np.asarray(shape.vertices, dtype=np.float64)[np.asarray(shape.faces)]
            sides = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
            boundary = 0.5 * float(np.linalg.norm(sides, axis=1).sum())
        else:
            boundary = float(np.linalg.norm(shape._end - shape._start, axis=1).sum())
        return boundary, float(shape.volume().value)
    lower, upper = (np.asarray(bound, dtype=np.float64) for bound in shape.bounds)
    band = ESTIMATE_BAND * float(np.max(upper - lower))
    lower, upper = lower - band, upper + band
    points = lower + (upper - lower) * np.random.default_rng(0).random((ESTIMATE_POINTS, shape.dim))
    distances = _InPieces(shape)._distance(points)
    box = float(np.prod(upper - lower))
    near = max(int(np.count_nonzero(np.abs(distances) < band)), 1)
    inside = max(int(np.count_nonzero(distances < 0)), 1)
    return box * near / ESTIMATE_POINTS / (2 * band), box * inside / ESTIMATE_POINTS


def _expected(measures, dim: int, protrusion: float) -> float:
    boundary, volume = measures
    if dim < 2:
        return 1.0
    radius = ESTIMATE_KAPPA * math.sqrt(dim * volume / boundary * protrusion)
    patch = _unit_ball(dim - 1) * (2 * radius * protrusion) ** ((dim - 1) / 2)
    return max(boundary / patch, 1.0)


def _protrusion_for(measures, dim: int, count: float) -> float:
    """The protrusion :func:`_expected` gives ``count`` spheres for (the inverse)."""
    boundary, volume = measures
    if dim < 2:
        return math.inf
    # count = boundary / (unit * (2 kappa sqrt(t) p^1.5)^((d-1)/2)), so p^(3(d-1)/4) = ...
    factor = _unit_ball(dim - 1) * (2 * ESTIMATE_KAPPA * math.sqrt(dim * volume / boundary)) ** ((dim - 1) / 2)
    return (boundary / (count * factor)) ** (4 / (3 * (dim - 1)))


def _pilot(shape, boundary: float, protrusion: float) -> float:
    """The pilot estimate of :func:`estimate_count` (``boundary`` the shape's boundary measure)."""
    if shape.dim < 2:
        return 1.0
    rng = np.random.default_rng(0)
    shape = _InPieces(shape)
    points, normals = boundary_samples(shape, PILOT_SAMPLES, rng)
    lower, upper = (np.asarray(bound, dtype=np.float64) for bound in shape.bounds)
    reach = 0.55 * float(np.max(upper - lower))
    # The radii to a quarter of the protrusion: a ball a little short of the largest one reaches less.
    steps = min(max(math.ceil(math.log2(reach / protrusion)) + 2, 8), 40)
    centers = _shrinking_balls(shape, points, normals, reach, steps)
    clearances = np.maximum(-shape._distance(centers), protrusion)  # at least a fallback ball's
    held = cKDTree(points).query_ball_point(centers, clearances + protrusion, return_length=True)
    share = boundary / PILOT_SAMPLES
    flat = _unit_ball(shape.dim - 1) * (2 * clearances * protrusion) ** ((shape.dim - 1) / 2)
    patches = np.maximum(flat, (held - 1) * share)  # the sample itself is no evidence of a patch
    return max(PILOT_FACTOR * float(np.sum(share / patches)), 1.0)


def _unit_ball(dim: int) -> float:
    return math.pi ** (dim / 2) / math.gamma(dim / 2 + 1)


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
    """A shape whose distances are asked for in pieces of about :data:`ndpack.ball_union.PIECE_SECONDS`
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
        The shape's grid of inside and outside cells (:func:`ndpack.boundary.sample_cells`), if
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
