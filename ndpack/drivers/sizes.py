"""Target size distributions of sphere radii, and how far a packing is from one.

What :func:`ndpack.pack_sizes` packs to: a distribution of radii given by count or by mass
(the volume each size holds, as sieve curves of granular materials are), as discrete classes,
a cumulative curve or a log-normal law. :meth:`SizeDistribution.radii` turns it into the list of
radii a run places (by count; a mass distribution is divided by each radius's ball volume), and
:meth:`SizeDistribution.report` measures a packing against it: the Kolmogorov-Smirnov distance
of its radii, each class's count and volume share, and the solid fraction.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import ParameterError
from ..oracle import ball_volume

#: A continuous distribution is handled on this many radii between its smallest and largest.
CURVE_POINTS = 4096
#: A continuous distribution's mean ball volume is the mean over this many of its quantiles.
MEAN_SAMPLES = 20_000
#: How far a discrete distribution's shares may sum from 1: rounding of shares typed to a few
#: digits (1/3 as 0.333333), not a share misread.
SHARES_SUM_TOLERANCE = 1e-6


@dataclass(frozen=True)
class SizeClass:
    """One class of a discrete distribution, target against achieved."""

    radius: float
    target: float  # its share of the spheres by the distribution's basis (count or mass)
    count: int
    count_share: float
    volume_share: float


@dataclass(frozen=True)
class SizeReport:
    """A packing against a size distribution (:meth:`SizeDistribution.report`).

    Attributes
    ----------
    by : "count" or "mass"
        The basis of the distribution, and of ``ks``.
    ks : float
        Kolmogorov-Smirnov distance between the packing's radii and the distribution, on that
        basis: the largest gap between the two cumulative curves.
    count : int
    solid_fraction : float
        The spheres' volume over the shape's.
    classes : tuple of SizeClass
        For a discrete distribution, each class's target and achieved shares; empty otherwise
        (a packing's radii are assigned to the nearest class).
    """

    by: str
    ks: float
    count: int
    solid_fraction: float
    classes: tuple

    def __str__(self) -> str:
        lines = [f"{self.count:,} spheres, solid fraction {self.solid_fraction:.4f}, "
                 f"KS distance by {self.by} {self.ks:.4f}"]
        for c in self.classes:
            share = c.count_share if self.by == "count" else c.volume_share
            lines.append(f"  r = {c.radius:.6g}: {c.count:,} spheres, {share:.4f} of the {self.by} "
                         f"(target {c.target:.4f})")
        return "\n".join(lines)


class SizeDistribution:
    """A target distribution of radii, by count or by mass (volume).

    Made with :meth:`discrete`, :meth:`cumulative` or :meth:`lognormal`. Internally a cumulative
    curve ``cdf`` (k,) over ascending ``radii`` (k,), on the basis ``by``: steps at the radii
    for a discrete distribution, piecewise linear between them for a continuous one.
    """

    def __init__(self, radii, cdf, by: str, discrete: bool, description: dict):
        self._radii, self._cdf, self.by, self.is_discrete = radii, cdf, by, discrete
        self.description = description

    # ------------------------------------------------------------------ construction
    @classmethod
    def discrete(cls, radii, fractions, by: str = "count") -> SizeDistribution:
        """Classes of one radius each: ``radii`` (k,) and their shares ``fractions`` (k,) of the
        count or of the mass, which sum to 1 (to within 1e-6; a sum such as 1.2 is refused rather
        than scaled down, since it is more often a typing error than a wish)."""
        radii, fractions = _positive(radii, "radii"), np.asarray(fractions, dtype=np.float64).reshape(-1)
        if len(fractions) != len(radii) or not np.all(np.isfinite(fractions)) or np.any(fractions < 0) \
                or not fractions.sum() > 0:
            raise ParameterError(f"fractions must be {len(radii)} non-negative numbers (one per radius) with a "
                                 f"positive sum, got {fractions.tolist()!r}")
        if abs(fractions.sum() - 1) > SHARES_SUM_TOLERANCE:
            raise ParameterError(f"fractions must sum to 1 (each radius's share of the {by}), but "
                                 f"{fractions.tolist()!r} sum to {fractions.sum():.6g}: for relative weights, "
                                 "pass them divided by their sum")
        if len(np.unique(radii)) != len(radii):
            raise ParameterError(f"the radii of a discrete distribution must differ, got {radii.tolist()!r}")
        order = np.argsort(radii)
        radii, fractions = radii[order], fractions[order] / fractions.sum()
        return cls(radii, np.cumsum(fractions), _basis(by), True,
                   {"kind": "discrete", "radii": radii.tolist(), "fractions": fractions.tolist(), "by": by})

    @classmethod
    def cumulative(cls, radii, cdf, by: str = "count") -> SizeDistribution:
        """A cumulative curve: the share ``cdf`` (k,) of the count or mass in spheres of radius
        at most ``radii`` (k,), ascending, from 0 to 1 (a sieve curve), linear in between."""
        radii, cdf = _positive(radii, "radii"), np.asarray(cdf, dtype=np.float64).reshape(-1)
        if len(radii) < 2 or len(cdf) != len(radii) or np.any(np.diff(radii) <= 0):
            raise ParameterError("a cumulative curve needs at least 2 ascending radii and one value of cdf each")
        if not (np.all(np.isfinite(cdf)) and np.all(np.diff(cdf) >= 0) and cdf[0] == 0 and cdf[-1] == 1):
            raise ParameterError(f"cdf must rise from 0 to 1 (non-decreasing), got {cdf.tolist()!r}")
        return cls(radii, cdf, _basis(by), False,
                   {"kind": "cumulative", "radii": radii.tolist(), "cdf": cdf.tolist(), "by": by})

    @classmethod
    def lognormal(cls, median: float, sigma: float, by: str = "count", low: float | None = None,
                  high: float | None = None) -> SizeDistribution:
        """A log-normal law of the radius: ``log r`` normal with mean ``log median`` and standard
        deviation ``sigma``, cut to ``[low, high]`` (default: ``median * exp(-+3 sigma)``)."""
        median, sigma = float(median), float(sigma)
        if not (median > 0 and math.isfinite(median) and sigma > 0 and math.isfinite(sigma)):
            raise ParameterError(f"a log-normal law needs median > 0 and sigma > 0, got {median!r} and {sigma!r}")
        low = median * math.exp(-3 * sigma) if low is None else float(low)
        high = median * math.exp(3 * sigma) if high is None else float(high)
        if not 0 < low < high:
            raise ParameterError(f"a log-normal law's cut needs 0 < low < high, got {low!r} and {high!r}")
        from scipy.special import ndtr  # the standard normal's cumulative distribution

        radii = np.geomspace(low, high, CURVE_POINTS)
        normal = ndtr(np.log(radii / median) / sigma)
        cdf = (normal - normal[0]) / (normal[-1] - normal[0])
        return cls(radii, cdf, _basis(by), False,
                   {"kind": "lognormal", "median": median, "sigma": sigma, "by": by, "low": low, "high": high})

    # ------------------------------------------------------------------ use
    @property
    def smallest(self) -> float:
        return float(self._radii[0])

    @property
    def largest(self) -> float:
        return float(self._radii[-1])

    def _number_curve(self, dim: int):
        """Radii (m,) ascending and the cumulative share of the count (m,) in ``dim`` dimensions."""
        radii, cdf = self._radii, self._cdf
        if not self.is_discrete and len(radii) < CURVE_POINTS:  # room for the division by r**d
            fine = np.interp(np.linspace(0, len(radii) - 1, CURVE_POINTS), np.arange(len(radii)), radii)
            radii, cdf = fine, np.interp(fine, self._radii, self._cdf)
        if self.by == "count":
            return radii, cdf
        if self.is_discrete:  # a class's count goes as its mass over a ball's volume
            counts = np.diff(cdf, prepend=0.0) / radii**dim
            return radii, np.cumsum(counts) / counts.sum()
        middle = 0.5 * (radii[1:] + radii[:-1])
        counts = np.diff(cdf) / middle**dim
        return radii, np.concatenate([[0.0], np.cumsum(counts)]) / counts.sum()

    def radii(self, dim: int, count: int) -> np.ndarray:
        """``count`` radii that follow the distribution, largest first: (count,) float64.

        Quantiles, not random draws: the i-th smallest is the ``(i + 1/2) / count`` quantile
        of the count distribution, so the list is within ``1 / (2 count)`` of it (KS). A
        discrete distribution's classes get their counts by largest remainders.
        """
        radii, cdf = self._number_curve(dim)
        if self.is_discrete:
            wanted = np.diff(cdf, prepend=0.0) * count
            counts = np.floor(wanted).astype(np.int64)
            short = count - counts.sum()
            counts[np.argsort(-(wanted - counts), kind="stable")[:short]] += 1
            return np.repeat(radii, counts)[::-1].copy()
        # The inverse of the curve; a flat stretch (no spheres there) is skipped.
        keep = np.concatenate([[True], np.diff(cdf) > 0])
        quantiles = (np.arange(count) + 0.5) / count
        return np.interp(quantiles, cdf[keep], radii[keep])[::-1].copy()

    def mean_volume(self, dim: int) -> float:
        """The mean ball volume of a sphere drawn by count, in ``dim`` dimensions."""
        if self.is_discrete:
            values, cdf = self._number_curve(dim)
            return float((np.diff(cdf, prepend=0.0) * ball_volume(dim, values)).sum())
        return float(ball_volume(dim, self.radii(dim, MEAN_SAMPLES)).mean())  # the quantiles' mean

    def cdf(self, radii, dim: int, left: bool = False) -> np.ndarray:
        """The target's cumulative share (on its basis) of radius ``<= radii`` (``< radii`` with
        ``left``, which differs only at a discrete class's radius): same shape as ``radii``."""
        radii = np.asarray(radii, dtype=np.float64)
        if self.is_discrete:
            rows = np.searchsorted(self._radii, radii, side="left" if left else "right")
            return np.concatenate([[0.0], self._cdf])[rows]
        return np.interp(radii, self._radii, self._cdf, left=0.0, right=1.0)

    def report(self, packing) -> SizeReport:
        """How far ``packing``'s radii are from this distribution (a :class:`SizeReport`)."""
        dim, radii = packing.dim, np.sort(packing.radii)
        weights = np.ones(len(radii)) if self.by == "count" else ball_volume(dim, radii)
        ks = 1.0
        if len(radii):
            below = np.concatenate([[0.0], np.cumsum(weights)]) / weights.sum()  # share up to each sphere
            points = np.unique(np.concatenate([radii, self._radii if self.is_discrete else []]))
            after = below[np.searchsorted(radii, points, side="right")]
            before = below[np.searchsorted(radii, points, side="left")]
            ks = float(max(np.abs(after - self.cdf(points, dim)).max(),
                           np.abs(before - self.cdf(points, dim, left=True)).max()))
        classes: tuple[SizeClass, ...] = ()
        if self.is_discrete:
            nearest = np.abs(np.log(packing.radii)[:, None] - np.log(self._radii)[None]).argmin(axis=1)
            volumes = ball_volume(dim, packing.radii)
            total = max(volumes.sum(), 1e-300)
            targets = np.diff(self._cdf, prepend=0.0)
            classes = tuple(
                SizeClass(float(r), float(targets[k]), int((nearest == k).sum()),
                          float((nearest == k).mean()) if len(radii) else 0.0,
                          float(volumes[nearest == k].sum() / total))
                for k, r in enumerate(self._radii))
        return SizeReport(self.by, ks, len(radii), float(packing.fill), classes)

    def __repr__(self) -> str:
        return f"SizeDistribution({self.description})"


def _basis(by: str) -> str:
    if by not in ("count", "mass"):
        raise ParameterError(f"by must be 'count' or 'mass' (volume), got {by!r}")
    return by


def _positive(values, name) -> np.ndarray:
    values = np.asarray(values, dtype=np.float64).reshape(-1)
    if len(values) == 0 or not np.all(np.isfinite(values)) or np.any(values <= 0):
        raise ParameterError(f"{name} must be positive finite numbers, got {values.tolist()!r}")
    return values
