"""Granular beds: solid fraction and time of equal spheres and of size distributions.

    python bench/dem_fill.py --backends numba --out bench/results/dem_fill_2core_issue22.json

Equal spheres (``min_radius == max_radius``) until none fits, in the unit square and cube, against
random sequential addition's saturation (0.547 in 2-D, 0.38 in 3-D, without walls); then
``pack_sizes`` in a cylinder (radius 0.5, height 1) at rising solid fractions for a bimodal and a
log-normal distribution by mass, reporting the KS distance and the radii given up. Each case runs
after a warm-up packing (compilation apart); every packing is verified in float64.
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np

import ndpack as nd


def timed(make):
    started = time.perf_counter()
    packing = make()
    return packing, time.perf_counter() - started


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--backends", nargs="+", default=["numba"])
    parser.add_argument("--fractions", nargs="+", type=float, default=[0.45, 0.5, 0.55, 0.6])
    parser.add_argument("--out")
    args = parser.parse_args()
    cylinder = nd.Cylinder([0, 0, 0], [0, 0, 1], 0.5) & nd.Slab([0, 0, 1], 0.0, 1.0)
    distributions = {
        "bimodal 0.04/0.015, 60/40 by mass": nd.SizeDistribution.discrete([0.04, 0.015], [0.6, 0.4], by="mass"),
        "log-normal median 0.02, sigma 0.25, by mass": nd.SizeDistribution.lognormal(0.02, 0.25, by="mass"),
    }
    rows = []
    for backend in args.backends:
        nd.pack(nd.Box([0, 0, 0], [1, 1, 1]), n=20, mode="fast", backend=backend, max_radius=0.1)  # warm-up
        for dim, radius in ((2, 0.01), (3, 0.025)):
            box = nd.Box(np.zeros(dim), np.ones(dim))
            packing, seconds = timed(lambda: nd.pack(box, n=10**7, min_radius=radius, max_radius=radius, mode="fast",
                                                     backend=backend, progress=False))
            rows.append(dict(case=f"equal spheres, unit {'square' if dim == 2 else 'cube'}, r = {radius}",
                             backend=backend, seconds=seconds, count=len(packing), solid_fraction=packing.fill,
                             valid=packing.verify().ok))
            print(rows[-1], flush=True)
        for name, distribution in distributions.items():
            for fraction in args.fractions:
                packing, seconds = timed(lambda: nd.pack_sizes(cylinder, distribution, solid_fraction=fraction,
                                                               backend=backend, progress=False))
                report = distribution.report(packing)
                rows.append(dict(case=name, backend=backend, target=fraction, seconds=seconds, count=len(packing),
                                 solid_fraction=report.solid_fraction, ks=report.ks,
                                 unplaced=packing.params["unplaced"], valid=packing.verify().ok))
                print(rows[-1], flush=True)
    if args.out:
        with open(args.out, "w") as file:
            json.dump({"versions": {"ndpack": nd.__version__, "numpy": np.__version__}, "rows": rows}, file, indent=1)


if __name__ == "__main__":
    main()
