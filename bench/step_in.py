"""Fill at equal counts with and without stepping dead cells' starts into the shape.

    python bench/step_in.py --mesh armadillo.obj --out bench/results/step_in_2core_issue21.json

A grid cell near the boundary whose centre and random starts all lie outside had no prototype
before issue 21; it now steps its best start across the boundary, confined to the cell
(``protosphere.STEP_IN``, :meth:`ndpack.drivers.greedy.protosphere.RunState._step_in`). Each case packs both
ways in one process (numba, seeds 0 and 1, both modes), every packing verified; the table gives
the fill before and after and its ratio. Timings are printed but not the point (2 cores, noisy).
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np

import ndpack as nd
from ndpack.drivers.greedy import protosphere

#: The 4-D simplex on which a faithful grid of 4 ran out of room (15 of 51 spheres).
SIMPLEX_4D = [[0.4602, 0.5821, -0.379, -0.3621], [0.8661, -0.039, -0.6904, -0.3044], [-0.8081, 0.568, 0.0748, -0.0781],
              [-0.1044, 0.581, 0.0505, 0.1617], [-0.5906, -0.6482, -0.6381, -0.98]]


def cases(mesh):
    yield "square", nd.Box([0, 0], [1, 1]), 2000, {}
    yield "cube", nd.Box(np.zeros(3), np.ones(3)), 5000, {}
    yield "cube-ball", nd.Box(np.zeros(3), np.ones(3)) - nd.Ball(np.ones(3), 0.5), 3000, {}
    if mesh:
        yield "armadillo", nd.TriangleMesh.load(mesh), 10000, {}
    yield "ball4-hole", nd.Ball(np.zeros(4), 1) - nd.Ball(np.zeros(4), 0.5), 2000, {}
    yield "ball5-hole", nd.Ball(np.zeros(5), 1) - nd.Ball(np.zeros(5), 0.5), 2000, {}
    yield "simplex4", nd.Simplex(SIMPLEX_4D), 500, {}
    yield "simplex4 grid=4", nd.Simplex(SIMPLEX_4D), 51, {"grid": 4}


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--mesh", default=None, help="a mesh file (the armadillo); left out if not given")
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1])
    parser.add_argument("--out", default=None, help="write the rows as JSON here")
    args = parser.parse_args()
    rows = []
    for name, shape, count, options in cases(args.mesh):
        for mode in ("faithful", "fast"):
            for seed in args.seeds:
                result = {}
                for step_in in (False, True):
                    protosphere.STEP_IN = step_in
                    started = time.perf_counter()
                    packing = nd.pack(shape, count, backend="numba", mode=mode, seed=seed, **options)
                    result[step_in] = dict(fill=packing.fill, spheres=len(packing), stop=packing.stop_reason,
                                           seconds=time.perf_counter() - started, valid=bool(packing.verify().ok))
                protosphere.STEP_IN = True
                before, after = result[False], result[True]
                rows.append(dict(case=name, mode=mode, seed=seed, count=count, before=before, after=after,
                                 ratio=after["fill"] / before["fill"]))
                print(f"{name:16s} {mode:8s} seed {seed}: fill {before['fill']:.5f} -> {after['fill']:.5f} "
                      f"({after['fill'] / before['fill']:.4f}), spheres {before['spheres']} -> {after['spheres']} "
                      f"({before['stop']} -> {after['stop']}), valid {before['valid']} {after['valid']}", flush=True)
    if args.out:
        with open(args.out, "w") as file:
            json.dump(rows, file, indent=1)


if __name__ == "__main__":
    main()
