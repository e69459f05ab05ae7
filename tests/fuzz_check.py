"""Packing a fuzzing case and judging the result against its reference, without ndpack's verify.

A packing is valid when every sample point of every sphere lies inside by the reference
(:mod:`fuzz_reference`) and no two spheres overlap in float64. The sample points of a sphere
of centre ``c`` and radius ``r`` are ``c`` itself and ``c + r (1 - SHRINK) u`` for the unit
vectors ``u``: both ways along every axis, :data:`DIRECTIONS` fixed random ones, towards and away
from each anchor the reference names (the primitives' centres, axes and nearest boundary points),
and along each facet normal; an anchor lying within the sphere is a sample point too. Only the
sign of the reference is used, so a sphere that pokes out between two sample directions can be
missed; the anchors aim the samples where spheres touch the boundary.

Outcomes (:data:`OUTCOMES`): ``valid``; ``clear error`` (an ``NdpackError``, while building the tree
or packing it, on a shape the reference finds empty or for a reason other than emptiness, such as
a NumPy plug-in on a compiled backend); ``refused non-empty`` (a ``ShapeError`` while building the
tree or from ``nd.pack``, or no sphere at all, on a shape in which the reference finds inside
points); ``repaired`` (ndpack's own final check had to shrink or drop spheres: a bug it caught);
``invalid`` (the check here fails); ``crash`` (any other exception); ``timeout`` (the time
budget ran out first).
"""

from __future__ import annotations

import time
import traceback
import warnings
from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from scipy.spatial import cKDTree

import ndpack as nd

#: Sample points are pulled this fraction of the radius towards the centre, so that a sphere
#: touching the boundary (as every packed sphere nearly does) is not judged by a tie.
SHRINK = 1e-9
#: Two spheres may overlap by this fraction of the shape's extent (float64 rounding).
OVERLAP_TOLERANCE = 1e-12
#: Random directions sampled on each sphere, besides the axes.
DIRECTIONS = 48
#: Uniform points in the reference's box that look for an inside point of a refused shape.
EMPTINESS_SAMPLES = 1 << 16
OUTCOMES = ("valid", "clear error", "refused non-empty", "repaired", "invalid", "crash", "timeout")
#: Where the backends that run on CPU and GPU run here.
DEVICES = {"warp": "cpu"}


@lru_cache(maxsize=None)
def directions(dim: int) -> np.ndarray:
    """(2 dim + DIRECTIONS, dim): both ways along each axis, then fixed random unit vectors."""
    axes = np.vstack([np.eye(dim), -np.eye(dim)])
    random = np.random.default_rng(dim).normal(size=(DIRECTIONS, dim))
    return np.vstack([axes, random / np.linalg.norm(random, axis=1)[:, None]])


@dataclass
class Check:
    """What :func:`check_packing` found.

    Attributes
    ----------
    ok : bool
    outside : (k,) int64
        Spheres with a sample point outside.
    worst : (d,) float64 or None
        One sample point outside, of the first such sphere.
    overlapping : (p, 2) int64
        Pairs overlapping by more than the tolerance.
    worst_overlap : float
        Largest ``r_i + r_j - |c_i - c_j|`` over near pairs, relative to the extent.
    samples : int
        Sample points tested.
    """

    ok: bool
    outside: np.ndarray
    worst: np.ndarray | None
    overlapping: np.ndarray
    worst_overlap: float
    samples: int


def _sample_points(centers, radii, reference):
    """(m, k, d) sample points of each sphere (see the module)."""
    reach = (radii * (1 - SHRINK))[:, None, None]
    units = [np.broadcast_to(directions(reference.dim), (len(radii),) + directions(reference.dim).shape)]
    anchors = reference.anchors(centers)
    offsets = anchors - centers[:, None]
    lengths = np.linalg.norm(offsets, axis=2, keepdims=True)
    toward = np.where(lengths > 0, offsets / np.maximum(lengths, 1e-300), 0.0)
    normals = reference.normals(centers)
    units += [toward, -toward, normals, -normals]
    surface = centers[:, None] + reach * np.concatenate(units, axis=1)
    # Anchors within the sphere; the others are replaced by the centre (a point tested anyway).
    within = np.where(lengths < reach, anchors, centers[:, None])
    return np.concatenate([centers[:, None], surface, within], axis=1)


def check_packing(centers: np.ndarray, radii: np.ndarray, reference, chunk: int = 64) -> Check:
    """Judge a packing by the reference's signs and float64 distances between centres.

    Parameters
    ----------
    centers : (n, d) float64
    radii : (n,) float64
    reference : fuzz_reference.Reference
    """
    outside, worst, samples = [], None, 0
    for start in range(0, len(radii), chunk):
        points = _sample_points(centers[start:start + chunk], radii[start:start + chunk], reference)
        flat = points.reshape(-1, reference.dim)
        inside = reference.inside(flat).reshape(points.shape[:2])
        samples += flat.shape[0]
        bad = np.flatnonzero(~inside.all(axis=1))
        if bad.size and worst is None:
            worst = points[bad[0]][~inside[bad[0]]][0]
        outside.extend(start + bad)
    box = reference.box
    extent = float(max(np.ptp(box, axis=0).max(), np.abs(box).max())) if np.all(np.isfinite(box)) else 1.0
    overlapping, worst_overlap = np.zeros((0, 2), np.int64), -np.inf
    if len(radii) > 1:
        pairs = cKDTree(centers).query_pairs(2 * float(radii.max()), output_type="ndarray")
        if len(pairs):
            gaps = np.linalg.norm(centers[pairs[:, 0]] - centers[pairs[:, 1]], axis=1)
            overlap = (radii[pairs[:, 0]] + radii[pairs[:, 1]] - gaps) / extent
            worst_overlap = float(overlap.max())
            overlapping = pairs[overlap > OVERLAP_TOLERANCE]
    ok = not outside and not len(overlapping)
    return Check(ok, np.array(outside, np.int64), worst, overlapping, worst_overlap, samples)


def inside_points(reference, samples: int = EMPTINESS_SAMPLES, seed: int = 0) -> int:
    """How many of ``samples`` uniform points of the reference's box lie inside."""
    lower, upper = reference.box
    if not np.all(upper > lower):
        return 0
    points = lower + (upper - lower) * np.random.default_rng(seed).random((samples, reference.dim))
    return int(np.count_nonzero(reference.inside(points)))


def _error(error: BaseException) -> dict:
    return {"error": type(error).__name__, "message": str(error)[:500]}


def run_case(case, backend: str, mode: str, time_budget: float | None = None) -> dict:
    """Build, pack and judge one case; a dict of what happened (``outcome`` in :data:`OUTCOMES`).

    The packing repairs rather than raises, so that a repair is seen (``repaired``) and the
    repaired packing is still judged here.
    """
    record = {"seed": case.seed, "index": case.index, "dim": case.dim, "kinds": case.kinds, "n": case.n,
              "grid": case.grid, "backend": backend, "mode": mode}
    started = time.perf_counter()
    try:
        shape = case.build()
    except nd.NdpackError as error:
        # The classes leave an empty part out as the operators do (nd.Union(a, empty) is a): a
        # ShapeError while building a tree the reference finds inside points in is a refusal.
        found = inside_points(case.reference) if isinstance(error, nd.ShapeError) else None
        record.update(outcome="refused non-empty" if found else "clear error", where="build", inside_samples=found,
                      **_error(error))
    except Exception as error:  # noqa: BLE001 - every other exception is what fuzzing looks for
        record.update(outcome="crash", where="build", traceback=traceback.format_exc(limit=-4), **_error(error))
    else:
        record.update(_pack_and_judge(case, shape, backend, mode, time_budget))
    record["seconds"] = round(time.perf_counter() - started, 3)
    if record["outcome"] != "valid":
        record["code"] = case.code
    return record


def _pack_and_judge(case, shape, backend, mode, time_budget) -> dict:
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            packing = nd.pack(shape, n=case.n, grid=case.grid, mode=mode, seed=case.pack_seed, backend=backend,
                              device=DEVICES.get(backend), progress=False, on_invalid="repair",
                              time_budget=time_budget)
        except nd.ShapeError as error:
            found = inside_points(case.reference)
            outcome = "refused non-empty" if found else "clear error"
            return dict(outcome=outcome, where="pack", inside_samples=found, **_error(error))
        except nd.NdpackError as error:
            return dict(outcome="clear error", where="pack", **_error(error))
        except Exception as error:  # noqa: BLE001
            return dict(outcome="crash", where="pack", traceback=traceback.format_exc(limit=-4), **_error(error))
    warned = sorted({type(w.message).__name__ for w in caught if issubclass(w.category, Warning)})
    check = check_packing(packing.centers, packing.radii, case.reference)
    result = dict(count=len(packing), stop_reason=packing.stop_reason, fill=round(float(packing.fill), 5),
                  warnings=warned, samples=check.samples, worst_overlap=check.worst_overlap)
    if not check.ok:
        result.update(outcome="invalid", outside=check.outside[:20].tolist(),
                      overlapping=check.overlapping[:20].tolist(),
                      worst_point=None if check.worst is None else check.worst.tolist())
    elif "RepairWarning" in warned:
        result.update(outcome="repaired", repair=str(packing.repair)[:500])
    elif packing.stop_reason == "time" and len(packing) < case.n:
        result.update(outcome="timeout")
    elif len(packing) == 0 and inside_points(case.reference):
        result.update(outcome="refused non-empty", message="no sphere packed")
    else:
        result.update(outcome="valid")
    return result
