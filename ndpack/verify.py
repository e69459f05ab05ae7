"""Independent float64 check of a packing: every sphere inside the shape, no two overlapping.

Containment uses the shape's own oracle, which is conservative (see :mod:`ndpack.oracle`), so a
sphere that passes is truly inside. Overlaps are found per octave of radius, so that a few large
spheres do not make every query reach across the whole packing: in sorted rows of a grid up to
3-D without a period (:mod:`ndpack.geometry.overlaps`), else with SciPy k-d trees.

For a triangle mesh, ``independent=True`` adds a check that shares nothing with the oracle's
queries: points spread over each sphere are classified by the exact winding number of the mesh's
triangles (caps included), summed in NumPy (:mod:`ndpack.meshes.solid_angles`) instead of walked
in the tree with a far-field approximation, and without the sign method the packing used.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import itertools

import numpy as np
from scipy.spatial import cKDTree

from .errors import DimensionError, NdpackError, ParameterError
from .oracle import as_points
from .geometry import overlaps
from .geometry.period import period_of
from .shapes.adapters import as_oracle

#: Default tolerance, as a fraction of the shape's scale: float64 rounding of distances is about
#: 1e-16 of it, and the driver keeps a margin of 1e-10 (ndpack.drivers.greedy.protosphere.SAFETY_MARGIN).
DEFAULT_TOLERANCE = 1e-12
#: Points per sphere of the independent check: a few dozen find a sphere that reaches through a
#: hole by a fraction of its radius.
SAMPLES_PER_SPHERE = 48

#: What a check asks of the spheres. ``"packing"``: each sphere whole inside the shape, no two
#: overlapping. ``"centers_only"``: the centres inside (a DEM bed cut by centre, made with
#: ``centers_only=True``), no two overlapping.
KINDS = ("packing", "centers_only")


@dataclass
class Verification:
    """What :func:`verify` found.

    Attributes
    ----------
    ok : bool
        True when nothing exceeds the tolerance.
    count : int
        Number of spheres checked.
    tol : float
        Absolute tolerance used.
    worst_containment : float
        Largest ``distance(center) + radius``: how far the worst sphere pokes out (< 0: inside);
        ``distance(center)`` where only the centres were checked.
    worst_overlap : float
        Largest ``r_i + r_j - |c_i - c_j|`` over near pairs (< 0: the tightest pair's gap).
    outside : (k,) int64
        Spheres that poke out by more than ``tol``.
    overlapping : (k, 2) int64
        Pairs that overlap by more than ``tol``.
    samples_outside : (k,) int64 or None
        Spheres with a point outside by the independent check (None where it did not run).
    centers_only : bool
        Whether only the centres had to lie inside.
    kind : str
        What was checked: ``"packing"`` or ``"centers_only"`` (:data:`KINDS`).
    from_file : tuple of str
        What the check took from the packing's own record rather than from the caller (a file
        may hold anything): ``"centers_only"``, ``"period"``; the summary names each.
    """

    ok: bool
    count: int
    tol: float
    worst_containment: float
    worst_overlap: float
    outside: np.ndarray = field(repr=False)
    overlapping: np.ndarray = field(repr=False)
    samples_outside: np.ndarray | None = field(default=None, repr=False)
    centers_only: bool = False
    from_file: tuple = ()

    @property
    def kind(self) -> str:
        return "centers_only" if self.centers_only else "packing"

    def __bool__(self) -> bool:
        return self.ok

    def summary(self) -> str:
        verdict = "valid" if self.ok else "INVALID"
        independent = ""
        if self.samples_outside is not None:
            independent = (f"; independent check: {len(self.samples_outside)} spheres with points outside by the "
                           f"exact winding number ({SAMPLES_PER_SPHERE} points each)")
        where = " (centres only)" if self.centers_only else ""
        if self.from_file:  # the file, not the caller, loosened the check: say so in the verdict
            verdict += " as " + " and ".join(_FROM_FILE[what] for what in self.from_file) + " (as the packing records)"
        # With fewer than two spheres there is no pair, and with none no poke-out: say so, not -inf.
        poke = f"{self.worst_containment:.3g}" if np.isfinite(self.worst_containment) else "none, no sphere"
        overlap = f"{self.worst_overlap:.3g}" if np.isfinite(self.worst_overlap) else "none, no pair"
        return (
            f"{verdict}: {self.count} spheres, {len(self.outside)} outside{where}, "
            f"{len(self.overlapping)} overlapping pairs (worst poke-out {poke}, "
            f"worst overlap {overlap}, tolerance {self.tol:.3g}){independent}"
        )

    __str__ = summary

    def notes(self) -> list[str]:
        """One line per thing the check took from the file, saying what it allowed and how to check
        without it."""
        return [_FROM_FILE_NOTE[what] for what in self.from_file]

    def raise_if_invalid(self) -> None:
        """Raise :class:`~ndpack.errors.NdpackError` with the summary unless the packing is valid."""
        if not self.ok:
            raise NdpackError(f"packing is invalid: {self.summary()}")


_FROM_FILE = {"centers_only": "centres only", "period": "periodic"}
_FROM_FILE_NOTE = {
    "centers_only": "the packing records that only the centres must lie inside, so spheres may reach past the "
                    "walls by their radius; `ndpack verify --as packing` (verify(..., kind='packing')) checks whole "
                    "spheres",
    "period": "the packing records a period, so spheres may cross those faces of the box and meet the others' images "
              "there; `ndpack verify --as packing` checks without it, `--periodic AXES` states the axes yourself",
}


def overlapping_pairs(centers: np.ndarray, radii: np.ndarray, tol: float = 0.0, period=None):
    """Pairs of spheres that overlap by more than ``tol``, and the worst overlap.

    Without a period, in 1-D to 3-D, the pairs are found in sorted rows of a grid per octave of
    radius (:mod:`ndpack.geometry.overlaps`, Numba); with a period, from 4-D up, or where that grid
    does not apply (tiny spheres spread over more than 2**20 times their size, ``tol < 0``), by
    SciPy k-d trees, one per octave. Both examine the same pairs and give the same answer.

    Parameters
    ----------
    centers : (n, d) float64
    radii : (n,) float64, positive
    tol : float
    period : Period, optional
        A periodic domain (:class:`~ndpack.geometry.period.Period`): spheres overlap where any images of
        them do, and a sphere wider than a period overlaps its own image (a pair ``(i, i)``).

    Returns
    -------
    pairs : (k, 2) int64
        ``i < j`` for each overlapping pair, sorted.
    worst : float
        Largest ``r_i + r_j - |c_i - c_j|`` among the near pairs examined; ``-inf`` if none. The
        pairs examined include every pair within ``r_i + r_j + tol``, so where one is, ``worst``
        does not depend on which pairs beyond it were examined.
    """
    if period is None and np.ndim(centers) == 2 and np.shape(centers)[1] <= 3:
        # Hand-written, as SciPy's k-d trees measured too slow for this hot path (the last check of
        # every packing): on 100,000 spheres of the armadillo, 0.23 s against 0.041 s for the grid
        # (2 cores, median of 5; ndpack.geometry.overlaps has the figures).
        found = overlaps.overlapping_pairs(centers, radii, tol)
        if found is not None:
            return found
    return _overlapping_pairs_kdtree(centers, radii, tol, period)


def _overlapping_pairs_kdtree(centers: np.ndarray, radii: np.ndarray, tol: float = 0.0, period=None):
    """:func:`overlapping_pairs` by SciPy k-d trees, one per octave of radius: any dimension, any period."""
    if len(radii) < 2 and period is None:
        return np.zeros((0, 2), dtype=np.int64), -np.inf
    # In a periodic domain the trees wrap: one frame for all of them (ndpack.geometry.period).
    points, boxsize = centers, None
    if period is not None:
        points, boxsize = period.frame(centers, 2 * radii.max() + tol)
    octave = np.floor(np.log2(radii)).astype(np.int64)
    firsts, seconds = [], []
    if period is not None:  # a sphere wider than a period meets its own image, a period away
        wide = np.flatnonzero(2 * radii - period.shortest > tol)
        firsts.append(wide)
        seconds.append(wide)
    for level in np.unique(octave):
        members = np.flatnonzero(octave == level)
        tree = cKDTree(points[members], boxsize=boxsize)
        largest = radii[members].max()
        # Pairs within one octave come back as one array (no Python list per sphere: twice as
        # fast as querying them as below, 100,000 spheres); each pair across octaves is found
        # from the larger sphere's side, querying the smaller one's octave with its own radius.
        within = tree.query_pairs(2 * largest + tol, output_type="ndarray")
        firsts.append(members[within[:, 0]])
        seconds.append(members[within[:, 1]])
        queries = np.flatnonzero(octave > level)
        if len(queries) == 0:
            continue
        found = tree.query_ball_point(
            points[queries], radii[queries] + largest + tol, return_sorted=False, workers=-1
        )
        lengths = np.fromiter(map(len, found), dtype=np.int64, count=len(found))
        # One flat pass over the lists: several times faster than an array per list.
        seconds.append(members[np.fromiter(itertools.chain.from_iterable(found), dtype=np.int64,
                                           count=int(lengths.sum()))])
        firsts.append(np.repeat(queries, lengths))
    first, second = np.concatenate(firsts), np.concatenate(seconds)
    if len(first) == 0:
        return np.zeros((0, 2), dtype=np.int64), -np.inf
    delta = centers[first] - centers[second]
    if period is not None:
        delta = period.difference(centers[first], centers[second])
        delta[first == second, np.argmin(period.lengths)] = period.shortest  # the nearest own image
    overlap = radii[first] + radii[second] - np.linalg.norm(delta, axis=1)
    bad = overlap > tol
    pairs = np.sort(np.stack([first[bad], second[bad]], axis=1), axis=1)
    return pairs[np.lexsort((pairs[:, 1], pairs[:, 0]))], float(overlap.max())


def verify(packing, shape=None, tol: float | None = None, radii=None, independent: bool = False,
           centers_only: bool | None = None, kind: str | None = None) -> Verification:
    """Check a packing in float64: every sphere inside ``shape``, no two overlapping.

    Parameters
    ----------
    packing : Packing or (n, d) array_like
        A packing, or sphere centres (then pass ``radii`` too).
    shape : Oracle, optional
        The shape; defaults to ``packing.shape``.
    tol : float, optional
        Absolute tolerance; default ``1e-12 * shape.scale``.
    radii : (n,) array_like, optional
        Radii when ``packing`` is an array of centres.
    independent : bool
        For a :class:`~ndpack.TriangleMesh`: also check 48 points spread over each sphere (its
        radius less ``tol``) by the exact winding number of the mesh's triangles, caps included,
        summed in NumPy (:meth:`~ndpack.TriangleMesh.exact_winding_number`), which shares no code
        with the oracle's distance or sign: a point counts as outside where it is not above 1/2.
        Costs points x triangles.
    centers_only : bool, optional
        Check only that the centres lie inside (a packing made with ``centers_only=True``); the
        same as ``kind="centers_only"``.
    kind : {"packing", "centers_only"}, optional
        What to check (:data:`KINDS`); ``"packing"`` is the strict check whatever the packing
        records. Default: what the packing records (``params["centers_only"]``), else
        ``"packing"``; a looser check taken from the record is named in the verdict
        (:attr:`Verification.from_file`), since a file may hold anything.

    Returns
    -------
    Verification
        Truthy when valid; ``summary()`` reports the worst violations.
    """
    return verify_with(packing, shape, tol, radii, independent, centers_only, kind)


def verify_with(packing, shape=None, tol: float | None = None, radii=None, independent: bool = False,
                centers_only: bool | None = None, kind: str | None = None,
                centre_distances: np.ndarray | None = None) -> Verification:
    """:func:`verify`, with ``shape``'s signed distance at each centre (n,) float64 already
    computed (``shape._distance(centers)``, as the greedy driver computes it while its rounds
    run: :mod:`ndpack.drivers.greedy.centre_distances`), or None to compute it here."""
    if kind is not None and kind not in KINDS:
        raise ParameterError(f"kind must be one of {', '.join(map(repr, KINDS))}, not {kind!r} (a covering is "
                             "checked with nd.check_covering)")
    if kind is not None and centers_only is not None and centers_only != (kind == "centers_only"):
        raise ParameterError(f"centers_only={centers_only} contradicts kind={kind!r}: give one of them")
    if kind is not None:
        centers_only = kind == "centers_only"
    from_file: tuple[str, ...] = ()
    if radii is None:
        centers, radii = packing.centers, packing.radii
        shape = packing.shape if shape is None else shape
        if centers_only is None:
            centers_only = bool((getattr(packing, "params", None) or {}).get("centers_only", False))
            from_file = ("centers_only",) if centers_only else ()
    else:
        centers = packing
    if shape is None:
        raise NdpackError("verify() needs the shape: pass verify(packing, shape)")
    shape = as_oracle(shape)
    centers = as_points(centers, shape.dim) if len(centers) else np.zeros((0, shape.dim))
    radii = np.asarray(radii, dtype=np.float64)
    if radii.shape != (len(centers),):
        raise DimensionError(f"expected {len(centers)} radii, got an array of shape {radii.shape}")
    tol = DEFAULT_TOLERANCE * shape.scale if tol is None else float(tol)
    bad_radius = ~(np.isfinite(radii) & (radii > 0))
    if bad_radius.any():
        raise NdpackError(
            f"{int(bad_radius.sum())} radii are not positive finite numbers, first at index "
            f"{int(np.flatnonzero(bad_radius)[0])}"
        )
    if len(radii) == 0:
        return Verification(True, 0, tol, -np.inf, -np.inf, np.zeros(0, np.int64), np.zeros((0, 2), np.int64),
                            centers_only=bool(centers_only), from_file=from_file)
    samples_outside = _independent_check(shape, centers, radii, tol) if independent else None
    if centre_distances is None or len(centre_distances) != len(centers):
        centre_distances = shape._distance(centers)
    poke_out = centre_distances + (0.0 if centers_only else radii)
    outside = np.flatnonzero(~(poke_out <= tol))  # NaN counts as outside
    pairs, worst_overlap = overlapping_pairs(centers, radii, tol, period_of(shape))
    return Verification(
        ok=len(outside) == 0 and len(pairs) == 0 and (samples_outside is None or len(samples_outside) == 0),
        count=len(radii),
        tol=tol,
        worst_containment=float(np.nanmax(poke_out)),
        worst_overlap=worst_overlap,
        outside=outside,
        overlapping=pairs,
        samples_outside=samples_outside,
        centers_only=bool(centers_only),
        from_file=from_file,
    )


def _independent_check(shape, centers: np.ndarray, radii: np.ndarray, tol: float) -> np.ndarray:
    """(k,) the spheres with a point of their surface (less ``tol``) outside by the shape's
    independent inside test (the exact winding number of a mesh)."""
    winding = getattr(shape, "exact_winding_number", None)
    if winding is None:
        raise ParameterError(f"independent=True checks triangle meshes (ndpack.TriangleMesh) only, not {shape!r}; "
                             "leave it out for other shapes")
    directions = sphere_directions(SAMPLES_PER_SPHERE)
    points = centers[:, None, :] + np.maximum(radii - tol, 0.0)[:, None, None] * directions  # (n, k, 3)
    inside = winding(points.reshape(-1, 3)).reshape(len(radii), -1) > 0.5
    return np.flatnonzero(~inside.all(axis=1))


def sphere_directions(count: int) -> np.ndarray:
    """(count, 3) unit vectors spread evenly over the sphere (a Fibonacci lattice): deterministic."""
    k = np.arange(count) + 0.5
    height = 1.0 - 2.0 * k / count
    angle = np.pi * (1.0 + np.sqrt(5.0)) * k
    ring = np.sqrt(1.0 - height**2)
    return np.column_stack([ring * np.cos(angle), ring * np.sin(angle), height])
