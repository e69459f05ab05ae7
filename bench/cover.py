"""Coverings of the shared meshes (issue 23): spheres needed for a protrusion, ndpack against k-means.

For each mesh (cow, fandisk, rocker-arm, armadillo from /work/shared/data/meshes) and each
protrusion tolerance (a share of the bounding-box diagonal, 1% and 0.5% by default):

- ``ndpack``: ``nd.cover(mesh, protrusion=tol * diagonal)``, timed after warm-up calls (so that
  compiling or loading the kernels is not counted; the warm-ups' own times are recorded);
- ``k-means``: the baseline below, with the fewest clusters whose protrusion is within ``tol``,
  found by search.

and, at equal counts (``--counts``), ``nd.cover(mesh, n=k)`` beside k-means with ``k`` clusters:
the protrusion each reaches.

The baseline: sample the surface uniformly by area (``ndpack.drivers.collision.boundary.boundary_samples``), cluster
the samples with k-means (k-means++ seeding, then 10 Lloyd iterations, as
``scipy.cluster.vq.kmeans2(..., minit="++")`` does), and give each cluster the sphere centred on
its centroid that holds all its samples (radius: the farthest one). Every sample is then covered;
points between samples, and the inside, need not be. It draws ``max(--baseline-samples,
SAMPLES_PER_CLUSTER * k)`` samples, so that a cluster has enough samples to stand for its patch.
The k-means is written out here (same algorithm, same result up to the random draws) because
scipy's k-means++ seeding costs O(k^2 n): 2,000 clusters of 50,000 samples took more than 5
minutes on 2 cores. Here the seeding updates the squared distances only within reach of each new
centre (a k-d tree) and the Lloyd steps assign the samples through a k-d tree of the centroids;
``--scipy-kmeans`` runs scipy's kmeans2 instead (a check at small k).

The search for the fewest clusters: k = 1, 2, 4, ... until the protrusion is within ``tol`` (at
most ``--max-k`` clusters: a row says ``cap_hit`` when even that many were not enough), then a
bisection on k between the last failing and the first passing count to ``--precision`` (relative).
The protrusion falls with k almost monotonically; the count reported is the smallest passing k
found, and ``history`` keeps every (k, protrusion) tried.

Both coverings are judged alike, by ``nd.check_covering(mesh, centers, radii,
samples=--check-samples, seed=1)`` (``nd.cover`` runs that same check on its result): the share
of fresh boundary and interior samples inside the union, and the protrusion, the largest
``r + f(c)`` over the spheres (a bound of how far a sphere reaches outside, exact for meshes since
their distance is exact outside). Times: ``nd.cover``'s wall time (its final check included);
the baseline's time is one k-means covering at the count found (sampling, clustering, radii), and
``search_seconds`` the whole search.

Rows are written to ``--out`` as each finishes; a markdown table is printed at the end, and
``--table FILE`` prints the tables of a results file without running anything (``markdown()``
renders them, for docs/benchmarks.md).

    python bench/cover.py                                    # everything; bench/results/cover_2core.json
    python bench/cover.py --meshes cow fandisk --tolerances 0.01
    python bench/cover.py --quick --meshes cow               # smoke run: fewer samples, a small cap
    python bench/cover.py --tolerances 0.01 0.005 --counts --no-baseline --repeats 5   # ndpack's times: medians
    python bench/cover.py --table bench/results/cover_2core.json
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time
from pathlib import Path

import numpy as np
from scipy.spatial import cKDTree

ROOT = Path(__file__).resolve().parent.parent
sys.path[:0] = [str(ROOT), str(ROOT / "bench")]  # this checkout's ndpack, whatever is installed

import ndpack as nd  # noqa: E402
from ndpack.drivers.collision.boundary import boundary_samples  # noqa: E402

from _common import load_average, machine_info, write_json  # noqa: E402

MESH_DIR = ROOT.parent / "shared" / "data" / "meshes"
MESHES = ("cow", "fandisk", "rocker-arm", "armadillo")
#: The baseline draws at least this many surface samples per cluster.
SAMPLES_PER_CLUSTER = 10
#: Lloyd iterations of the baseline's k-means (kmeans2's default ``iter``).
LLOYD_ITERATIONS = 10
#: Seed of every run (ndpack's samples, the baseline's samples and seeding).
SEED = 0
#: Seed of the check (``nd.cover`` checks its result with ``seed + 1``).
CHECK_SEED = SEED + 1
#: The --quick run's settings: samples of ndpack, of the check and of the baseline, and the cap on k.
QUICK = dict(samples=5_000, check_samples=10_000, baseline_samples=5_000, max_k=2_048,
             tolerances=[0.02], counts=[8, 32])


# ------------------------------------------------------------------------------------------------ baseline
def kmeans_pp(points, k, rng):
    """k-means++ seeding: each next centre is a sample drawn with probability proportional to its
    squared distance to the nearest centre so far. (k, d) float64."""
    n = len(points)
    centers = np.empty((k, points.shape[1]))
    first = int(rng.integers(n))
    centers[0] = points[first]
    nearest = ((points - points[first]) ** 2).sum(axis=1)
    tree = cKDTree(points)
    for i in range(1, k):
        total = np.cumsum(nearest)
        if total[-1] <= 0:  # every sample sits on a centre: the rest are duplicates of samples
            centers[i:] = points[rng.integers(n, size=k - i)]
            break
        j = min(int(np.searchsorted(total, rng.random() * total[-1], side="right")), n - 1)
        centers[i] = points[j]
        # Only samples nearer to the new centre than to every old one change; they lie within
        # the largest such distance of it.
        near = np.asarray(tree.query_ball_point(points[j], math.sqrt(nearest.max())), dtype=np.int64)
        if len(near):
            nearest[near] = np.minimum(nearest[near], ((points[near] - points[j]) ** 2).sum(axis=1))
    return centers


def kmeans(points, k, rng, iterations=LLOYD_ITERATIONS):
    """k-means++ seeding then Lloyd iterations, as ``kmeans2(points, k, iter=iterations, minit="++")``:
    returns the centroids (k, d) and each sample's cluster (n,), the labels of the last assignment
    and the centroids their means (an empty cluster keeps its centre)."""
    k = min(k, len(points))
    centers = kmeans_pp(points, k, rng)
    for _ in range(iterations):
        _, labels = cKDTree(centers).query(points, workers=-1)
        counts = np.bincount(labels, minlength=k)
        sums = np.stack([np.bincount(labels, weights=points[:, axis], minlength=k)
                         for axis in range(points.shape[1])], axis=1)
        filled = counts > 0
        centers = centers.copy()
        centers[filled] = sums[filled] / counts[filled, None]
    return centers, labels


def kmeans_covering(mesh, k, samples, seed=SEED, scipy_kmeans=False):
    """The baseline: spheres on the k-means centroids of surface samples, each holding its cluster.

    Returns centres (m, 3), radii (m,) (m <= k: empty clusters are dropped) and the samples drawn.
    """
    rng = np.random.default_rng(seed)
    count = max(samples, SAMPLES_PER_CLUSTER * k)
    points, _ = boundary_samples(mesh, count, rng)
    if scipy_kmeans:
        from scipy.cluster.vq import kmeans2

        centers, labels = kmeans2(points, k, iter=LLOYD_ITERATIONS, minit="++", seed=rng)
    else:
        centers, labels = kmeans(points, k, rng)
    radii = np.zeros(len(centers))
    np.maximum.at(radii, labels, np.linalg.norm(points - centers[labels], axis=1))
    used = np.bincount(labels, minlength=len(centers)) > 0
    return centers[used], radii[used], count


def protrusion(mesh, centers, radii) -> float:
    """The largest ``r + f(c)`` over the spheres (0 for one inside): ``check_covering``'s ``max_protrusion``."""
    return float(np.maximum(radii + mesh.distance(centers), 0.0).max(initial=0.0))


def search_count(mesh, tolerance, samples, max_k, precision, scipy_kmeans=False):
    """The fewest clusters (found by doubling, then bisection) whose covering protrudes at most
    ``tolerance`` (a length). Returns a dict: ``k``, the covering's ``centres``/``radii``/``seconds``/
    ``samples``, ``cap_hit`` and the ``history`` of (k, spheres, protrusion, seconds)."""
    history, found = [], {}

    def evaluate(k):
        started = time.perf_counter()
        centers, radii, count = kmeans_covering(mesh, k, samples, scipy_kmeans=scipy_kmeans)
        seconds = time.perf_counter() - started
        reach = protrusion(mesh, centers, radii)
        history.append([int(k), len(radii), reach, round(seconds, 3)])
        print(f"    k-means k={k}: {len(radii)} spheres, protrusion {reach:.4g} ({seconds:.2f} s)", flush=True)
        found["last"] = dict(centers=centers, radii=radii, seconds=seconds, samples=count)
        if reach <= tolerance and k <= found.get("k", k):  # the smallest passing count's covering
            found["best"], found["k"] = found["last"], k
        return reach <= tolerance

    low, high, k = None, None, 1
    while high is None:
        if evaluate(k):
            high = k
        elif k >= max_k:
            break
        else:
            low, k = k, min(2 * k, max_k)
    if high is None:  # the cap was not enough: report the cap's covering
        return dict(k=k, cap_hit=True, history=history, **found["last"])
    while low is not None and high - low > max(1, precision * high):
        middle = (low + high) // 2
        if evaluate(middle):
            high = middle
        else:
            low = middle
    return dict(k=high, cap_hit=False, history=history, **found["best"])


# ------------------------------------------------------------------------------------------------ rows
def report_fields(report, diagonal) -> dict:
    """A CoverReport as JSON: shares covered, worst gap, protrusion (also relative to the diagonal)."""
    return dict(covered=bool(report.covered), boundary_covered=report.boundary_covered,
                interior_covered=report.interior_covered, worst_gap=report.worst_gap,
                max_protrusion=report.max_protrusion, max_protrusion_rel=report.max_protrusion / diagonal,
                mean_protrusion_rel=report.mean_protrusion / diagonal, outside_ratio=report.outside_ratio,
                outside_volume_error=report.outside_volume_error / report.shape_volume,
                boundary_samples=report.boundary_samples, interior_samples=report.interior_samples,
                diagonal=report.diagonal)


def ndpack_row(mesh, diagonal, backend, args, **request) -> dict:
    """``nd.cover`` run ``--repeats`` times with the same seed (the same covering): the median time."""
    times = []
    for _ in range(args.repeats):
        started = time.perf_counter()
        covering = nd.cover(mesh, samples=args.samples, check_samples=args.check_samples, seed=SEED,
                            backend=backend, progress=False, **request)
        times.append(time.perf_counter() - started)
    params = {key: value for key, value in covering.params.items()}
    return dict(method="ndpack", spheres=len(covering), seconds=round(float(np.median(times)), 3),
                seconds_all=[round(t, 3) for t in times], **report_fields(covering.report, diagonal), params=params)


def baseline_row(mesh, diagonal, centers, radii, seconds, args, **extra) -> dict:
    report = nd.check_covering(mesh, centers, radii, samples=args.check_samples, seed=CHECK_SEED)
    return dict(method="k-means", spheres=len(radii), seconds=round(seconds, 3),
                **report_fields(report, diagonal), **extra)


# ------------------------------------------------------------------------------------------------ tables
def _percent(value, digits=2):
    return "–" if value is None else f"{100 * value:.{digits}f}%"


def _covered(row) -> str:
    if row["covered"]:
        return "yes"
    return f"no ({_percent(row['boundary_covered'])} / {_percent(row['interior_covered'])})"


def markdown(results: dict) -> str:
    """The results as markdown: spheres for each tolerance, then protrusion at equal counts.

    "covered" is every fresh check sample inside the union; otherwise the shares of boundary /
    interior samples covered."""
    rows = results["rows"]
    lines = ["| mesh | triangles | tol (of diagonal) | ndpack spheres | ndpack s | ndpack covered "
             "| k-means spheres | k-means s (search s) | k-means covered |",
             "|---|---:|---:|---:|---:|---|---:|---:|---|"]
    keys = list(dict.fromkeys((r["mesh"], r["tolerance"]) for r in rows if r["kind"] == "tolerance"))
    for mesh, tol in keys:
        pair = {r["method"]: r for r in rows if r["kind"] == "tolerance" and r["mesh"] == mesh
                and r["tolerance"] == tol}
        ours, base = pair.get("ndpack"), pair.get("k-means")
        triangles = (ours or base)["triangles"]
        cells = [mesh, f"{triangles:,}", _percent(tol, 1)]
        cells += [f"{ours['spheres']:,}", f"{ours['seconds']:.2f}", _covered(ours)] if ours else ["–"] * 3
        if base:
            count = f"{base['spheres']:,}" + (" (cap hit)" if base["cap_hit"] else "")
            cells += [count, f"{base['seconds']:.2f} ({base['search_seconds']:.0f})", _covered(base)]
        else:
            cells += ["–"] * 3
        lines.append("| " + " | ".join(cells) + " |")
    counts = [r for r in rows if r["kind"] == "count"]
    if counts:
        lines += ["", "| mesh | k | ndpack spheres | ndpack protrusion | ndpack s | ndpack covered "
                  "| k-means protrusion | k-means s | k-means covered |",
                  "|---|---:|---:|---:|---:|---|---:|---:|---|"]
        for mesh, k in dict.fromkeys((r["mesh"], r["k"]) for r in counts):
            pair = {r["method"]: r for r in counts if r["mesh"] == mesh and r["k"] == k}
            ours, base = pair.get("ndpack"), pair.get("k-means")
            cells = [mesh, str(k)]
            cells += ([f"{ours['spheres']}", _percent(ours["max_protrusion_rel"]), f"{ours['seconds']:.2f}",
                       _covered(ours)] if ours else ["–"] * 4)
            cells += ([_percent(base["max_protrusion_rel"]), f"{base['seconds']:.2f}", _covered(base)]
                      if base else ["–"] * 3)
            lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


# ------------------------------------------------------------------------------------------------ run
def warm_up(backend, args) -> dict:
    """Cover a small CSG part and the cow twice with few samples: the first calls compile or load
    the kernels; their times are kept (``cold``) beside the second, warm mesh call's."""
    times = {}
    small = dict(samples=500, check_samples=500, seed=SEED, backend=backend, progress=False)
    part = nd.Box([0, 0, 0], [1, 1, 1]) - nd.Ball([1, 1, 1], 0.5)
    cow = load_mesh("cow")[0]
    for label, shape in (("csg_cold", part), ("mesh_cold", cow), ("mesh_warm", cow)):
        started = time.perf_counter()
        nd.cover(shape, protrusion=0.02 * shape.diagonal, **small)
        times[label] = round(time.perf_counter() - started, 3)
    return times


def load_mesh(name):
    path = Path(name) if name.endswith((".obj", ".stl", ".ply", ".off")) else MESH_DIR / f"{name}.obj"
    started = time.perf_counter()
    mesh = nd.TriangleMesh.load(path)
    return mesh, time.perf_counter() - started


def versions() -> dict:
    found = {}
    for module in ("scipy", "numba"):
        try:
            found[module] = __import__(module).__version__
        except ImportError:
            pass
    return found


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--meshes", nargs="+", default=list(MESHES), help="names in the shared folder, or paths")
    parser.add_argument("--tolerances", nargs="*", type=float, help="protrusion, as a share of the diagonal "
                        "(default 0.01 0.005)")
    parser.add_argument("--counts", nargs="*", type=int,
                        help="sphere counts of the equal-count rows (default 8 32 128)")
    parser.add_argument("--backend", default="numba", help="nd.cover's backend (default numba)")
    parser.add_argument("--samples", type=int, help="nd.cover's samples (default 20000)")
    parser.add_argument("--check-samples", type=int, help="boundary samples of the check (default 50000)")
    parser.add_argument("--baseline-samples", type=int, help="the baseline's surface samples at least (default "
                        f"20000; {SAMPLES_PER_CLUSTER} a cluster if more)")
    parser.add_argument("--max-k", type=int, help="the baseline's cap on clusters (default 20000)")
    parser.add_argument("--precision", type=float, default=0.02, help="relative precision of the search on k")
    parser.add_argument("--scipy-kmeans", action="store_true", help="scipy's kmeans2 (slow at large k)")
    parser.add_argument("--no-baseline", dest="baseline", action="store_false")
    parser.add_argument("--repeats", type=int, default=1, help="runs of each nd.cover; its time is the median")
    parser.add_argument("--quick", action="store_true", help="a smoke run: " + ", ".join(
        f"{key}={value}" for key, value in QUICK.items()) + " unless given")
    parser.add_argument("--out", type=Path, help="default bench/results/cover_<cores>core[_quick].json")
    parser.add_argument("--table", type=Path, help="only print the tables of this results file")
    args = parser.parse_args(argv)
    if args.table:
        print(markdown(json.loads(args.table.read_text())))
        return 0
    defaults = dict(samples=20_000, check_samples=50_000, baseline_samples=20_000, max_k=20_000,
                    tolerances=[0.01, 0.005], counts=[8, 32, 128])
    for key, value in (QUICK if args.quick else defaults).items():
        if getattr(args, key) is None:
            setattr(args, key, value)
    if args.out is None:
        args.out = ROOT / "bench" / "results" / f"cover_{os.cpu_count()}core{'_quick' if args.quick else ''}.json"

    results = dict(machine=machine_info(), versions=versions(), args={k: str(v) if isinstance(v, Path) else v
                                                                      for k, v in vars(args).items()}, rows=[])
    print("warming up ...", flush=True)
    results["warmup_seconds"] = warm_up(args.backend, args)
    print(f"warm-up: {results['warmup_seconds']}", flush=True)
    write_json(args.out, results)

    def add(row):
        row["load"] = load_average()
        results["rows"].append(row)
        write_json(args.out, results)
        print({key: value for key, value in row.items() if key not in ("params", "history")}, flush=True)

    for name in args.meshes:
        mesh, load_seconds = load_mesh(name)
        diagonal = mesh.diagonal
        common = dict(mesh=Path(name).stem, triangles=len(mesh.faces), load_seconds=round(load_seconds, 3))
        for tol in args.tolerances:
            print(f"{name}: tolerance {tol:g} of the diagonal ({tol * diagonal:.4g})", flush=True)
            add(dict(kind="tolerance", tolerance=tol, **common,
                     **ndpack_row(mesh, diagonal, args.backend, args, protrusion=tol * diagonal)))
            if args.baseline:
                started = time.perf_counter()
                found = search_count(mesh, tol * diagonal, args.baseline_samples, args.max_k, args.precision,
                                     args.scipy_kmeans)
                search_seconds = time.perf_counter() - started
                add(dict(kind="tolerance", tolerance=tol, **common,
                         **baseline_row(mesh, diagonal, found["centres"], found["radii"], found["seconds"], args,
                                        k=found["k"], cap_hit=found["cap_hit"], samples=found["samples"],
                                        search_seconds=round(search_seconds, 3), history=found["history"])))
        for k in args.counts:
            print(f"{name}: {k} spheres", flush=True)
            add(dict(kind="count", k=k, **common, **ndpack_row(mesh, diagonal, args.backend, args, n=k)))
            if args.baseline:
                started = time.perf_counter()
                centers, radii, count = kmeans_covering(mesh, k, args.baseline_samples,
                                                        scipy_kmeans=args.scipy_kmeans)
                seconds = time.perf_counter() - started
                add(dict(kind="count", k=k, **common,
                         **baseline_row(mesh, diagonal, centers, radii, seconds, args, samples=count)))
    print()
    print(markdown(results))
    return 0


if __name__ == "__main__":
    sys.exit(main())
