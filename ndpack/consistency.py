"""Checks that a packing is possible, beyond what :func:`ndpack.verify` can see.

``verify`` asks the shape's own distance whether each sphere is inside. A plug-in steeper than a
distance answers yes for spheres that reach outside the shape (over a small hole, say), and no
check through that function alone can tell. Two things can still be checked, and the driver's
final check (``pack(..., on_invalid=...)``) checks both:

- the slope of the distance across each sphere: along rays from its centre to its surface (up
  the gradient, towards the nearest boundary, and one random direction), a distance rises no
  faster than the way travelled (:func:`steep_spheres`; plug-ins only, since the built-in
  shapes are 1-Lipschitz by construction);
- the spheres' total volume against the shape's: disjoint spheres inside a shape cover at most
  its volume, within the error of a Monte Carlo estimate (:func:`volume_problem`).
"""

from __future__ import annotations

import warnings
from dataclasses import replace

import numpy as np

from .errors import KEPT_IN_ERROR, InvalidPackingError, RepairWarning, ShapeError
from .shapes.plugin import SHORTEST_PAIR, SLOPE_TOLERANCE, Function, steepest_on_rays, tree
from .verify import DEFAULT_TOLERANCE

#: The spheres may exceed a Monte Carlo volume by this many standard errors before the packing
#: counts as impossible: a false alarm at 5 sigma is about 1 in 3.5 million.
VOLUME_SIGMAS = 5.0
#: Relative slack on an exact volume, for the rounding of the spheres' volumes.
VOLUME_ROUNDING = 1e-9
#: The gradients about a sphere's centre are taken this fraction of its radius away: far beyond
#: how near a prototype converges to its node (about 2e-5 of its clearance in the fast mode).
NEAR = 1e-2


def volume_problem(packing) -> str | None:
    """Why the spheres' volume is impossible for the shape's, or None when it is possible.

    Parameters
    ----------
    packing : Packing
        Its ``volume`` and ``volume_error`` (the standard error of a Monte Carlo estimate, 0
        when exact) and its spheres.

    Returns
    -------
    str or None
        One sentence: the two volumes and the likely causes.
    """
    volume, error = float(packing.volume), float(packing.volume_error)
    if not (np.isfinite(volume) and volume > 0 and np.isfinite(error)):
        return None  # no volume to hold the spheres to (an unbounded shape, a foreign file)
    covered = packing.covered_volume
    if covered <= volume + VOLUME_SIGMAS * error + VOLUME_ROUNDING * volume:
        return None
    estimate = f" +- {error:.3g} (a Monte Carlo estimate)" if error else " (exact)"
    return (f"the spheres' volume {covered:.6g} exceeds the shape's volume {volume:.6g}{estimate}: a fill of "
            f"{covered / volume:.4f}, more than the shape holds. Either the distance is steeper than a distance "
            "somewhere its slope checks did not look (spheres there reach outside the shape, which verify() cannot "
            "see), or the volume is wrong (a Monte Carlo estimate that missed thin parts, or a wrong closed form)")


def steep_spheres(packing, shape, seed: int = 0):
    """The spheres across which ``shape``'s distance rises faster than a distance.

    From each centre ``c`` rays of the sphere's radius run to its surface: one up the gradient
    at ``c`` (towards the nearest boundary), one up the gradient at each of the ``2 d`` points
    ``c +- NEAR * r * e_k`` and one in a random direction. A sphere's centre is a node of the
    distance, nearly equally far from several parts of the boundary, and the gradients about it
    point at each of them: at an overstated one (a small hole whose distance is scaled up) the
    sphere reaches past it. :func:`~ndpack.shapes.plugin.steepest_on_rays` finds the steepest
    pair on each ray; a slope above ``1 + 1e-6`` (and a rise beyond the distance by more than
    verification's tolerance, so that rounding never counts) proves that the function is not
    1-Lipschitz there. A test, not a proof: a steep part that no ray crosses goes unseen.

    Parameters
    ----------
    packing : Packing
    shape : Oracle
    seed : int
        Seed of the random directions.

    Returns
    -------
    indices : (k,) int64
        The steep spheres.
    slopes : (k,) float64
        The steepest slope found across each.
    first, second : (k, d) float64
        Where each was found.
    """
    centers, radii = packing.centers, packing.radii
    count, dim = len(radii), shape.dim
    if count == 0:
        return np.zeros(0, np.int64), np.zeros(0), np.zeros((0, dim)), np.zeros((0, dim))
    # Offsets (2d + 1, d): none, then +- each axis.
    offsets = np.concatenate([np.zeros((1, dim)), np.eye(dim), -np.eye(dim)])
    about = (centers[None] + NEAR * radii[None, :, None] * offsets[:, None, :]).reshape(-1, dim)
    random = np.random.default_rng(seed).standard_normal((1, count, dim))
    directions = np.concatenate([shape._gradient(about).reshape(-1, count, dim), random])
    directions /= np.maximum(np.linalg.norm(directions, axis=2), 1e-300)[:, :, None]
    rays = len(directions)
    starts = np.broadcast_to(centers, (rays, count, dim)).reshape(-1, dim)
    slopes, first, second = steepest_on_rays(shape._distance, starts, directions.reshape(-1, dim),
                                             np.tile(radii, rays), shape.bounds, SHORTEST_PAIR * shape.scale)
    rise = np.abs(shape._distance(second) - shape._distance(first)) - np.linalg.norm(second - first, axis=1)
    steep = (slopes > 1 + SLOPE_TOLERANCE) & (rise > DEFAULT_TOLERANCE * shape.scale)
    slopes = np.where(steep, slopes, 0.0).reshape(rays, count)
    ray = np.argmax(slopes, axis=0)  # the steepest of each sphere's rays
    indices = np.flatnonzero(slopes[ray, np.arange(count)] > 0)
    chosen = ray[indices] * count + indices
    return indices, slopes[ray[indices], indices], first[chosen], second[chosen]


def has_plugin(shape) -> bool:
    """Whether a user's function (:class:`~ndpack.Function`) is anywhere in ``shape``'s tree."""
    return any(isinstance(node, Function) for node in tree(shape))


def ensure_possible(packing, shape, on_invalid: str = "repair", margin: float = 0.0):
    """The driver's last check: a packing whose spheres are impossible is never returned as made.

    Spheres across which a plug-in's distance is steep (:func:`steep_spheres`) are dropped
    (``on_invalid="repair"``: recorded in ``packing.repair``, with a :class:`RepairWarning`) or
    raise :class:`InvalidPackingError` (``"raise"``). A volume the spheres exceed
    (:func:`volume_problem`) raises in either mode, since no change of the spheres can mend a
    wrong volume; the error keeps the packing as made in ``error.packing``.

    Parameters
    ----------
    packing : Packing
        Already verified (and repaired) against ``shape``.
    shape : Oracle
    on_invalid : {"repair", "raise"}
    margin : float
        The run's safety margin (absolute): a shape with room for no sphere above it is refused.

    Returns
    -------
    Packing
        ``packing``, or a copy without the steep spheres, or with a Monte Carlo volume that the
        spheres exceed within its error raised to theirs (``params["volume_estimate"]`` keeps the
        estimate).
    """
    if len(packing) == 0 and packing.stop_reason == "no_room":
        raise ShapeError(
            f"no sphere fits in {shape!r}: every clearance found is below the safety margin, {margin:.3g} (for a "
            f"shape whose scale, its largest coordinate or extent, is {shape.scale:.3g}), which keeps rounding from "
            "making spheres overlap; the shape is too small for where it lies: move it nearer the origin "
            "(translate) or scale it up")
    if has_plugin(shape):
        indices, slopes, first, second = steep_spheres(packing, shape)
        if len(indices):
            worst = int(np.argmax(slopes))
            found = (f"the distance of {shape!r} rises faster than a distance across {len(indices)} of the "
                     f"{len(packing)} spheres (slope at least {slopes[worst]:.4g}, between "
                     f"{np.round(first[worst], 6).tolist()} and {np.round(second[worst], 6).tolist()}, inside sphere "
                     f"{int(indices[worst])}): spheres sized by it may reach outside the shape, and verify() cannot "
                     "see it")
            cause = ("a plug-in is steeper than 1 somewhere its slope check (Function.check_lipschitz) did not "
                     "sample; divide it by a bound on its slope")
            if on_invalid == "raise":
                raise InvalidPackingError(f"the packing failed its final check: {found}; {cause}. Pass "
                                          "on_invalid='repair' to drop those spheres (the others rest on the same "
                                          f"function). {KEPT_IN_ERROR}", packing=packing)
            packing = _drop(packing, indices, float(slopes[worst]), cause)
            warnings.warn(f"{found}; they were dropped (the others rest on the same function): {cause}. The repair "
                          "is recorded in packing.repair; on_invalid='raise' raises instead", RepairWarning,
                          stacklevel=4)
    if (packing.params or {}).get("centers_only"):
        return packing  # spheres may reach past the walls: their volume is no bound of the shape's
    problem = volume_problem(packing)
    if problem:
        raise InvalidPackingError(f"the packing failed its final check: {problem}. {KEPT_IN_ERROR}",
                                  packing=packing)
    return _volume_at_least_covered(packing)


def _volume_at_least_covered(packing):
    """``packing`` with a Monte Carlo volume below its spheres' (within its error: else the
    volume check raised) raised to theirs, the estimate kept in ``params["volume_estimate"]``.

    Disjoint spheres inside the shape prove that it holds at least their volume, so the fill
    never prints above 1 (a ball plug-in filled by one sphere had printed 1.0035 +- 0.0018).
    """
    covered = packing.covered_volume
    if not (packing.volume_error and covered > packing.volume):
        return packing
    ratio = packing.volume / covered
    stats = replace(packing.stats, fill=packing.stats.fill * ratio)
    params = {**packing.params, "volume_estimate": packing.volume}
    return replace(packing, volume=covered, stats=stats, params=params)


def _drop(packing, indices, worst_slope: float, cause: str):
    """``packing`` without the spheres ``indices``, the drop added to its repair record."""
    keep = np.ones(len(packing), bool)
    keep[indices] = False
    record = dict(packing.repair or {"outside": 0, "overlapping_pairs": 0, "shrunk": 0, "dropped": 0,
                                     "worst_poke_out": None, "worst_overlap": None, "cause": cause})
    if packing.repair:
        record["cause"] = f"{record['cause']}; {cause}"
    record["dropped"] += len(indices)
    record["steep"] = len(indices)
    record["worst_slope"] = worst_slope
    dropped = packing.replace_spheres(packing.centers[keep], packing.radii[keep], packing.rounds[keep])
    dropped.repair = record
    return dropped
