"""The final check's parts at a million spheres, against Numba's threads (issue 48).

    python3 bench/verify_speed.py --count 1000000 --backend warp [--mesh armadillo.obj] --out verify_speed.json

Packs the unit cube (or ``--mesh``; fast mode, seed 0), then times, median of ``--repeats``: ``nd.verify`` whole,
its overlap search (``ndpack.verify.overlapping_pairs``) and its containment (the shape's distance
at the centres), the overlap search with Numba limited to 1, 2, 4, 8 and all threads, and the threading
layer Numba uses.
"""

from __future__ import annotations

import argparse
import importlib
import statistics
import sys
import time
from pathlib import Path

import numpy as np

import ndpack as nd

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import machine_info, write_json


def timed(function, repeats):
    values = []
    for _ in range(repeats):
        started = time.perf_counter()
        function()
        values.append(time.perf_counter() - started)
    return statistics.median(values)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--count", type=int, default=1_000_000)
    parser.add_argument("--backend", default="numba")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--mesh", type=Path, help="a mesh file; default the unit cube")
    parser.add_argument("--out", type=Path)
    args = parser.parse_args()
    import numba

    verify_module = importlib.import_module("ndpack.verify")
    shape = nd.TriangleMesh.load(args.mesh) if args.mesh else nd.Box(np.zeros(3), np.ones(3))
    packing = nd.pack(shape, args.count, backend=args.backend, mode="fast", seed=0, progress=False)
    centers, radii = packing.centers, packing.radii
    verify_module.overlapping_pairs(centers[:100], radii[:100])  # compiled or loaded
    row = dict(shape=str(args.mesh or "unit cube"), count=len(radii), threading_layer=None,
               threads=numba.get_num_threads())
    row["verify_s"] = timed(lambda: nd.verify(packing), args.repeats)
    row["threading_layer"] = numba.threading_layer()
    row["containment_s"] = timed(lambda: shape.distance(centers), args.repeats)
    most = numba.get_num_threads()
    for threads in sorted({min(threads, most) for threads in (1, 2, 4, 8)} | {most}):
        numba.set_num_threads(threads)
        row[f"pairs_{threads}_threads_s"] = timed(lambda: verify_module.overlapping_pairs(centers, radii, 1e-12),
                                                 args.repeats)
    numba.set_num_threads(most)
    print(row)
    if args.out:
        write_json(args.out, dict(machine=machine_info(), command="python3 bench/verify_speed.py " +
                                  " ".join(sys.argv[1:]), rows=[row]))


if __name__ == "__main__":
    main()
