"""Packing at scale: time and fill to large counts, fast mode against the faithful one.

Cases (each a list of runs; every run is one ``nd.pack`` after a 3-sphere warm-up that compiles):

- ``armadillo``: the shared armadillo mesh (``--mesh``), fast mode to each of ``--counts``;
  the faithful mode (``batch=1``) to ``--faithful-count`` for the quality reference.
- ``armadillo-subdivided``: the same, each triangle split in four (about 400,000).
- ``cube`` / ``square``: fast mode to the largest count, fill against count from the rounds'
  statistics, and the fitted exponent ``a`` of the uncovered fraction ``1 - fill ~ C N^-a``.
- ``nd``: a 4-, 5- and 6-dimensional shape, fast mode to ``--nd-count``.
- ``quality``: unit cube and square, fast and faithful mode to ``--quality-count``: fill at
  equal counts.
- ``voxel``: the method a user would otherwise write with SciPy (Euclidean distance transform of
  a ``--voxels``^3 grid, take the maximum, insert, update the distances near the new sphere)
  against the faithful mode at equal counts: time, fill, radii against the faithful mode's.

Fill at a count is the spheres' volume over the shape's. Compile time is the warm-up's.

    python bench/scale.py --cases armadillo cube --backends numba --counts 10000 100000 \\
        --out bench/results/scale_2core.json
"""

from __future__ import annotations

import argparse
import resource
import sys
import time
from pathlib import Path

import numpy as np

import ndpack as nd

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import machine_info, write_json

ROOT = Path(__file__).resolve().parent.parent
MESH = ROOT.parent / "shared" / "data" / "meshes" / "armadillo.obj"


def fill_at(packing, counts):
    """Fill after the first ``count`` spheres, for each count (insertion order)."""
    volumes = np.cumsum(nd.ball_volume(packing.dim, packing.radii))
    return {int(c): float(volumes[min(c, len(volumes)) - 1] / packing.volume) for c in counts if c <= len(volumes)}


TIME_BUDGET = None


def timed_pack(shape, count, backend, **options):
    if backend == "warp-float32":  # a label: Warp in float32 (its own wp.Mesh queries on meshes)
        backend = nd.backends.get_backend("warp", precision="float32")
    started = time.perf_counter()
    nd.pack(shape, 3, backend=backend, **options)
    compile_s = time.perf_counter() - started
    started = time.perf_counter()
    packing = nd.pack(shape, count, backend=backend, time_budget=TIME_BUDGET, **options)
    seconds = time.perf_counter() - started
    # Time to each count, from the rounds' clocks (they start before the prototypes are placed).
    times = {}
    for c in (10_000, 100_000, 1_000_000, count):
        reached = np.flatnonzero(packing.stats.count >= c)
        if len(reached):
            times[int(c)] = float(packing.stats.time[reached[0]])
    # The process's peak resident memory so far (run a case alone to read it as that case's).
    peak_mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    return packing, dict(compile_s=compile_s, seconds=seconds, spheres=len(packing), rounds=len(packing.stats.time),
                         stop=packing.stop_reason, time_to=times, verified=bool(packing.verify().ok),
                         peak_host_mb=peak_mb, curve=curve(packing))


def show(*runs):
    """Print runs without their curves (they are in the JSON)."""
    for run in runs:
        print({k: v for k, v in run.items() if k != "curve"}, flush=True)


def curve(packing, points=60):
    """Count, fill and seconds at up to ``points`` rounds evenly spaced in log(count), for the plots
    (``bench/plot_scale.py``): a dict of three lists."""
    counts = packing.stats.count
    if len(counts) == 0:
        return dict(count=[], fill=[], seconds=[])
    marks = np.exp(np.linspace(np.log(max(counts[0], 1)), np.log(counts[-1]), points))
    rounds = np.unique(np.minimum(np.searchsorted(counts, marks), len(counts) - 1))
    return dict(count=counts[rounds].tolist(), fill=packing.stats.fill[rounds].tolist(),
                seconds=packing.stats.time[rounds].tolist())


def exponent(packing, low):
    """Least-squares slope of log(1 - fill) against log(count) from ``low`` on, at points evenly
    spaced in log(count)."""
    counts, fills = packing.stats.count.astype(float), packing.stats.fill
    use = counts >= low
    if use.sum() < 3:
        return None
    grid = np.exp(np.linspace(np.log(counts[use][0]), np.log(counts[use][-1]), 30))
    uncovered = 1 - np.interp(grid, counts[use], fills[use])
    return float(-np.polyfit(np.log(grid), np.log(uncovered), 1)[0])


def armadillo(args, backend, subdivided=False):
    if subdivided:  # every triangle in four: about 400,000
        import trimesh

        mesh = nd.TriangleMesh.from_trimesh(trimesh.load(args.mesh, force="mesh").subdivide())
    else:
        mesh = nd.TriangleMesh.load(args.mesh)
    label = f"armadillo, {mesh.n_triangles:,} triangles"
    runs = []
    packing, run = timed_pack(mesh, max(args.counts), backend, mode="fast")
    run.update(case=label, mode="fast", backend=backend, fill=fill_at(packing, args.counts))
    runs.append(run)
    show(run)
    if args.faithful_count:
        reference, run = timed_pack(mesh, args.faithful_count, backend, mode="faithful")
        counts = [c for c in args.counts if c <= args.faithful_count] + [args.faithful_count]
        run.update(case=label, mode="faithful", backend=backend, fill=fill_at(reference, counts))
        run["fast_fill_ratio"] = {c: fill_at(packing, [c])[c] / fill_at(reference, [c])[c] for c in counts}
        runs.append(run)
        show(run)
    return runs


def unit_box(args, backend, dim):
    shape = nd.Box(np.zeros(dim), np.ones(dim))
    count = args.box_count
    packing, run = timed_pack(shape, count, backend, mode="fast")
    marks = [c for c in (1000, 10_000, 100_000, 1_000_000) if c <= count]
    theory = {2: 0.5275, 3: 0.2126}[dim]
    run.update(case=f"unit {('square', 'cube')[dim - 2]}", mode="fast", backend=backend, fill=fill_at(packing, marks),
               exponent=exponent(packing, count / 100), exponent_theory=theory)
    show(run)
    return [run]


def quality(args, backend):
    """Fast against faithful mode in the unit square and cube, at the same counts."""
    runs = []
    marks = [c for c in (1000, 5000, 10_000, 20_000, 50_000, 100_000) if c <= args.quality_count]
    for dim in (3, 2):
        shape = nd.Box(np.zeros(dim), np.ones(dim))
        packings = {}
        for mode in ("faithful", "fast"):
            packings[mode], run = timed_pack(shape, args.quality_count, backend, mode=mode)
            run.update(case=f"unit {('square', 'cube')[dim - 2]}", mode=mode, backend=backend,
                       fill=fill_at(packings[mode], marks))
            runs.append(run)
        runs[-1]["fast_fill_ratio"] = {c: runs[-1]["fill"][c] / runs[-2]["fill"][c] for c in marks}
        show(runs[-2], runs[-1])
    return runs


def high_dimensions(args, backend):
    runs = []
    for dim in (4, 5, 6):
        shape = nd.Ball(np.zeros(dim), 1.0) - nd.Ball(np.full(dim, 0.3), 0.4)
        packing, run = timed_pack(shape, args.nd_count, backend, mode="fast")
        run.update(case=f"{dim}-D ball with a hole", mode="fast", backend=backend,
                   fill=fill_at(packing, [args.nd_count]))
        show(run)
        runs.append(run)
    return runs


def voxel_greedy(voxels, count):
    """The user's SciPy method in the unit cube: distance transform, take the maximum, insert,
    update. Returns centres (k, 3) and radii (k,) and the seconds it took."""
    from scipy.ndimage import distance_transform_edt

    started = time.perf_counter()
    spacing = 1.0 / voxels
    axis = (np.arange(voxels) + 0.5) * spacing
    padded = np.zeros((voxels + 2,) * 3, dtype=bool)
    padded[1:-1, 1:-1, 1:-1] = True
    # Distance of each voxel centre to the boundary: the transform to the outside layer, less half a voxel.
    clearance = (distance_transform_edt(padded)[1:-1, 1:-1, 1:-1] - 0.5) * spacing
    centers, radii = [], []
    for _ in range(count):
        flat = int(np.argmax(clearance))
        radius = float(clearance.flat[flat])
        if radius <= 0:
            break
        center = np.array([axis[i] for i in np.unravel_index(flat, clearance.shape)])
        centers.append(center)
        radii.append(radius)
        # Only voxels whose clearance exceeds their gap to the new sphere change: those within
        # radius + the largest clearance of its centre.
        reach = radius + float(clearance.max())
        low = np.maximum(0, np.floor((center - reach) / spacing).astype(int))
        high = np.minimum(voxels, np.ceil((center + reach) / spacing).astype(int) + 1)
        block = tuple(slice(a, b) for a, b in zip(low, high))
        grid = np.meshgrid(*[axis[s] for s in block], indexing="ij", sparse=True)
        gap = np.sqrt(sum((g - c) ** 2 for g, c in zip(grid, center))) - radius
        np.minimum(clearance[block], gap, out=clearance[block])
    return np.array(centers), np.array(radii), time.perf_counter() - started


def voxel(args, backend):
    shape = nd.Box(np.zeros(3), np.ones(3))
    runs = []
    centers, radii, seconds = voxel_greedy(args.voxels, args.voxel_count)
    reference, run = timed_pack(shape, args.voxel_count, backend, mode="faithful")
    fast, fast_run = timed_pack(shape, args.voxel_count, backend, mode="fast")
    count = min(len(radii), len(reference))
    error = np.abs(radii[:count] / reference.radii[:count] - 1)
    volume = nd.ball_volume(3, radii).sum()
    runs.append(dict(case="unit cube", method=f"scipy voxels {args.voxels}^3", seconds=seconds, spheres=len(radii),
                     fill=float(volume), radius_error_median=float(np.median(error)),
                     radius_error_max=float(error.max())))
    fast_error = np.abs(fast.radii[:count] / reference.radii[:count] - 1)
    run.update(case="unit cube", method="ndpack faithful", backend=backend, fill=float(reference.fill))
    fast_run.update(case="unit cube", method="ndpack fast", backend=backend, fill=float(fast.fill),
                    radius_error_median=float(np.median(fast_error)), radius_error_max=float(fast_error.max()))
    runs += [run, fast_run]
    for r in runs:
        show(r)
    return runs


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--cases", nargs="+", default=["armadillo", "cube", "square", "quality", "nd", "voxel"])
    parser.add_argument("--backends", nargs="+", default=["numba"], help="names, or warp-float32")
    parser.add_argument("--mesh", default=str(MESH))
    parser.add_argument("--counts", nargs="+", type=int, default=[10_000, 100_000])
    parser.add_argument("--faithful-count", type=int, default=10_000)
    parser.add_argument("--box-count", type=int, default=100_000)
    parser.add_argument("--nd-count", type=int, default=20_000)
    parser.add_argument("--quality-count", type=int, default=20_000)
    parser.add_argument("--voxels", type=int, default=256)
    parser.add_argument("--voxel-count", type=int, default=2000)
    parser.add_argument("--time-budget", type=float, default=None, help="seconds a packing may take (then it stops)")
    parser.add_argument("--out", default=str(ROOT / "bench" / "results" / "scale.json"))
    args = parser.parse_args()
    global TIME_BUDGET
    TIME_BUDGET = args.time_budget
    results = dict(machine=machine_info(), args=vars(args), runs=[])
    for backend in args.backends:
        for case in args.cases:
            if case == "armadillo":
                results["runs"] += armadillo(args, backend)
            elif case == "armadillo-subdivided":
                results["runs"] += armadillo(args, backend, subdivided=True)
            elif case in ("cube", "square"):
                results["runs"] += unit_box(args, backend, 3 if case == "cube" else 2)
            elif case == "quality":
                results["runs"] += quality(args, backend)
            elif case == "nd":
                results["runs"] += high_dimensions(args, backend)
            elif case == "voxel":
                results["runs"] += voxel(args, backend)
            write_json(Path(args.out), results)


if __name__ == "__main__":
    main()
