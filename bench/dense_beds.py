"""Dense granular beds (nd.pack_dense) against the literature's random close packing fractions.

    python bench/dense_beds.py --out bench/results/dense_beds_2core.json
    python bench/dense_beds.py --cases cube-100k --out ...       (one case)

Each case is one bed, seed 0, numba on this machine's cores, timed from the call to the verified
packing (the contact kernels compiled by a warm-up bed first). Written: the solid fraction, the
goal (issue 49), the particles, seconds, relaxations and FIRE steps, the contact statistics, and
for a size distribution the KS distance by mass against it scaled by the bed's factor
(``params["scale"]``) and the class shares. Every bed is checked in float64 (``verify``).
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

import ndpack as nd
from _common import machine_info, write_json

MESHES = Path(__file__).resolve().parents[2] / "shared" / "data" / "meshes"


def periodic(dim):
    return nd.Periodic(nd.Box(np.zeros(dim), np.ones(dim)))


def cow():
    return nd.TriangleMesh.load(MESHES / "cow.obj")


#: name: (what, goal, the shape, the sizes, keyword arguments of pack_dense)
CASES = {
    "cube-10k": ("equal spheres, periodic unit cube", 0.635, lambda: periodic(3), 1.0, dict(n=10_000)),
    "4d-10k": ("equal spheres, periodic 4-D unit cell", 0.45, lambda: periodic(4), 1.0, dict(n=10_000)),
    "5d-10k": ("equal spheres, periodic 5-D unit cell", 0.30, lambda: periodic(5), 1.0, dict(n=10_000)),
    "cylinder": ("equal spheres r = 0.05, walled cylinder 10 diameters across and high", 0.60,
                 lambda: nd.Cylinder([0.5, 0.5, 0.0], [0.5, 0.5, 1.0], 0.5), 0.05, dict(solid_fraction=0.64)),
    "cow": ("equal spheres in the cow mesh", 0.58, cow, 1.0, dict(n=3_000)),
    "box-1k": ("equal spheres, walled unit cube, 1,222 (11 diameters across)", None,
               lambda: nd.Box(np.zeros(3), np.ones(3)), 1.0, dict(n=1_222)),
    "box-10k": ("equal spheres, walled unit cube, 10,000 (21 diameters across)", None,
                lambda: nd.Box(np.zeros(3), np.ones(3)), 1.0, dict(n=10_000)),
    "lognormal": ("log-normal by mass, median 0.02, sigma 0.25, periodic unit cube", 0.65, lambda: periodic(3),
                  nd.SizeDistribution.lognormal(0.02, 0.25, by="mass"), dict(n=10_000)),
    "cube-100k": ("equal spheres, periodic unit cube", 0.635, lambda: periodic(3), 1.0, dict(n=100_000)),
}


def run(name):
    what, goal, make, sizes, options = CASES[name]
    shape = make()
    started = time.perf_counter()
    packing = nd.pack_dense(shape, sizes, seed=0, progress=False, **options)
    seconds = time.perf_counter() - started
    check = packing.verify(shape)
    relaxations = packing.params["relaxations"]
    row = dict(case=name, what=what, goal=goal, fill=packing.fill, spheres=len(packing.radii), seconds=seconds,
               relaxations=len(relaxations), steps=sum(r["steps"] for r in relaxations),
               scale=packing.params["scale"], stop_reason=packing.stop_reason, contacts=packing.params["contacts"],
               valid=bool(check))
    if isinstance(sizes, nd.SizeDistribution):  # the radii back at the distribution's scale
        unscaled = dataclasses.replace(packing, radii=packing.radii / packing.params["scale"])
        row["ks_by_mass"] = sizes.report(unscaled).ks
    print(f"{name}: fill {row['fill']:.4f} (goal {goal or 'none'}), {row['spheres']:,} spheres, {seconds:.1f} s, "
          f"{row['relaxations']} relaxations, {row['steps']:,} steps, contacts {row['contacts']['mean']:.2f} "
          f"(backbone {row['contacts']['backbone_mean']:.2f}), valid {row['valid']}", flush=True)
    return row


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--cases", nargs="+", default=list(CASES), choices=list(CASES))
    parser.add_argument("--out", default=None)
    args = parser.parse_args()
    nd.pack_dense(periodic(3), 1.0, n=100, progress=False)  # compile apart
    rows = [run(name) for name in args.cases]
    if args.out:
        write_json(Path(args.out), dict(machine=machine_info(), command="python " + " ".join(sys.argv), rows=rows))


if __name__ == "__main__":
    main()
