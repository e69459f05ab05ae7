"""Granular beds: solid fraction against time, for equal spheres and for size distributions.

    python bench/dem_fill.py --backends numba --out bench/results/dem_fill_2core.json \\
        --figure docs/img/dem-4d-periodic-fill.png
    python bench/dem_fill.py --backends numba warp numba-cuda --device cuda:0 --out bench/results/dem_fill_h100.json

Cases, each after a warm-up packing of its backend (compilation apart), every packing verified
in float64 (periodic ones against every image):

- equal spheres (``min_radius == max_radius``) until none fits, in the unit square and cube with
  walls and in the periodic ones, against random sequential addition's saturation (0.547 in
  2-D, 0.38 in 3-D, periodic: no walls);
- ``pack_sizes`` in a cylinder (radius 0.5, height 1) at rising solid fractions for a bimodal
  and a log-normal distribution by mass (KS distance, radii given up), beside the greedy
  driver (``pack``, fast mode) run to the same count in the same cylinder;
- a log-normal by mass (median 0.06) in a periodic 4-D unit cell to a solid fraction of 0.4,
  about 10,000 spheres (``--figure`` draws its fill against the count).

Each row keeps its fill-against-time curve (``curve``: seconds and fill after each round, thinned
to at most 60 points).
"""

from __future__ import annotations

import argparse
import json
import platform
import time

import numpy as np

import ndpack as nd

CURVE_POINTS = 60


def timed(make):
    started = time.perf_counter()
    packing = make()
    return packing, time.perf_counter() - started


def curve(packing):
    """(seconds, fill) after each round, thinned to at most ``CURVE_POINTS`` (the last kept)."""
    seconds, fill = np.asarray(packing.stats.time), np.asarray(packing.stats.fill)
    keep = np.unique(np.linspace(0, len(fill) - 1, min(len(fill), CURVE_POINTS)).astype(int)) if len(fill) else []
    return [[round(float(seconds[i]), 4), round(float(fill[i]), 5)] for i in keep]


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--backends", nargs="+", default=["numba"])
    parser.add_argument("--device", help="cuda:N for the GPU backends")
    parser.add_argument("--fractions", nargs="+", type=float, default=[0.45, 0.5, 0.55, 0.6])
    parser.add_argument("--out")
    parser.add_argument("--figure", help="the 4-D periodic run's fill against count, to this picture")
    args = parser.parse_args()
    cylinder = nd.Cylinder([0, 0, 0], [0, 0, 1], 0.5) & nd.Slab([0, 0, 1], 0.0, 1.0)
    distributions = {
        "bimodal 0.04/0.015, 60/40 by mass": nd.SizeDistribution.discrete([0.04, 0.015], [0.6, 0.4], by="mass"),
        "log-normal median 0.02, sigma 0.25, by mass": nd.SizeDistribution.lognormal(0.02, 0.25, by="mass"),
    }
    grains = nd.SizeDistribution.lognormal(0.06, 0.25, by="mass")
    rows = []
    versions = {"ndpack": nd.__version__, "numpy": np.__version__, "python": platform.python_version()}
    for module in ("numba", "warp"):
        try:
            versions[module] = __import__(module).__version__
        except ImportError:
            pass

    def row(case, backend, packing, seconds, **extra):
        """One result, printed and (with ``--out``) written at once: a run cut short keeps the rows so far."""
        rows.append(dict(case=case, backend=backend, seconds=round(seconds, 3), count=len(packing),
                         solid_fraction=round(packing.fill, 5), valid=bool(packing.verify().ok), **extra,
                         curve=curve(packing)))
        print({key: value for key, value in rows[-1].items() if key != "curve"}, flush=True)
        if args.out:
            with open(args.out, "w") as file:
                json.dump({"versions": versions, "machine": platform.node(), "rows": rows}, file, indent=1)

    for backend in args.backends:
        device = args.device if backend in ("warp", "numba-cuda") else None
        options = dict(backend=backend, device=device, progress=False)
        for dim in (2, 3):  # warm-up: the 2-D and 3-D kernels, compiled or loaded apart from the timings
            unit = nd.Box(np.zeros(dim), np.ones(dim))
            for shape in (unit, nd.Periodic(unit)):
                nd.pack(shape, n=20, mode="fast", min_radius=0.1, max_radius=0.1, **options)
        nd.pack_sizes(cylinder, list(distributions.values())[0], n=50, **options)
        nd.pack(cylinder, n=50, mode="fast", **options)
        for dim, radius in ((2, 0.01), (3, 0.025)):
            box = nd.Box(np.zeros(dim), np.ones(dim))
            name = "square" if dim == 2 else "cube"
            for shape, label in ((box, f"unit {name}"), (nd.Periodic(box), f"periodic unit {name}")):
                packing, seconds = timed(lambda: nd.pack(shape, n=10**7, min_radius=radius, max_radius=radius,
                                                         mode="fast", **options))
                row(f"equal spheres, {label}, r = {radius}", backend, packing, seconds)
        for name, distribution in distributions.items():
            for fraction in args.fractions:
                packing, seconds = timed(lambda: nd.pack_sizes(cylinder, distribution, solid_fraction=fraction,
                                                               **options))
                report = distribution.report(packing)
                row(name, backend, packing, seconds, target=fraction, ks=round(report.ks, 5),
                    unplaced=packing.params["unplaced"])
            greedy, seconds = timed(lambda: nd.pack(cylinder, n=len(packing), mode="fast", **options))
            row(f"greedy driver (pack, fast), cylinder, as many spheres as {name} at {args.fractions[-1]}",
                backend, greedy, seconds)
        cell = nd.Periodic(nd.Box(np.zeros(4), np.ones(4)))
        nd.pack_sizes(cell, grains, n=200, grid=8, **options)  # the 4-D kernels' warm-up
        experiment, seconds = timed(lambda: nd.pack_sizes(cell, grains, solid_fraction=0.4, grid=8, **options))
        row("log-normal median 0.06, sigma 0.25, by mass, periodic 4-D unit cell, solid fraction 0.4", backend,
            experiment, seconds, ks=round(grains.report(experiment).ks, 5), unplaced=experiment.params["unplaced"])
        if args.figure and backend == args.backends[0]:
            from ndpack.pictures import save_fill_figure

            save_fill_figure(experiment, args.figure, labels=["4-D periodic, log-normal by mass"])


if __name__ == "__main__":
    main()
