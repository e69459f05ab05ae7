"""How many spheres a covering of a given protrusion takes, estimated before any work
(:func:`estimate_count`), and the refusal of a protrusion that takes too many
(:class:`TooManySpheres`, :func:`refuse_too_many`)."""

from __future__ import annotations

import math

import numpy as np
from scipy.spatial import cKDTree

from ...errors import ParameterError
from ...oracle import Oracle
from ...shapes.adapters import as_oracle
from .boundary import boundary_samples, exactly_sampled
from .set_cover import _InPieces, _shrinking_balls

#: Spheres a protrusion may call for (:func:`estimate_count`) before :func:`cover` refuses it: a
#: million spheres take hours and gigabytes, and few collision checkers take more.
MAX_SPHERES = 1_000_000
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


def refuse_too_many(shape, protrusion: float, max_spheres: int | None, samples: int) -> None:
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
    limit = max_spheres if max_spheres is not None and reason == "max_spheres" else samples
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
