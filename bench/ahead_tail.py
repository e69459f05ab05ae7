"""The polish ahead's schedule (issue 48): fill with a GPU's policies where it starts at each ``eps``.

    python bench/ahead_tail.py --out bench/results/ahead_tail_2core.json

A launch-bound backend (a GPU) ends each fast round by polishing ahead in the move launch
(``rounds.POLISH_AHEAD``), with the polish schedule's steps from ``rounds.AHEAD_EPS_START`` down. A move
launch lasts as long as its longest prototype's chain of distance evaluations, a move's and then its
polish's, so the tail's length is the chain's. Numba with ``launch_bound`` set runs the GPU's rounds (the
device store's tests check that the two agree): for each start, the polish ahead's steps and the mean fill
over ``--seeds`` seeds of the unit cube, the unit square and the 20k-triangle armadillo of the tests at
``--count`` spheres, and of the 100k-triangle armadillo at ``--large`` (seed 0). ``inf``: the whole
schedule. Every packing is verified.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

import ndpack as nd
from _common import machine_info, write_json
from ndpack.drivers.greedy import rounds
from ndpack.drivers.greedy.protosphere import schedules

ROOT = Path(__file__).resolve().parent.parent
SHAPES = {
    "unit cube": lambda: nd.Box(np.zeros(3), np.ones(3)),
    "unit square": lambda: nd.Box(np.zeros(2), np.ones(2)),
    "armadillo (20k triangles)": lambda: nd.TriangleMesh.load(ROOT / "tests/data/meshes/armadillo-20k.ply"),
}
LARGE = ROOT.parent / "shared/data/meshes/armadillo.obj"


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--starts", nargs="+", type=float, default=[np.inf, 1e-3, 3e-4, 1e-4])
    parser.add_argument("--count", type=int, default=10_000)
    parser.add_argument("--seeds", type=int, default=3)
    parser.add_argument("--large", type=int, default=100_000, help="spheres in the 100k-triangle armadillo (0: none)")
    parser.add_argument("--out", type=Path)
    args = parser.parse_args()
    backend = nd.backends.get_backend("numba")
    polish = schedules("fast", 50)[1]
    cases = [(name, make, args.count, args.seeds) for name, make in SHAPES.items()]
    if args.large and LARGE.exists():
        cases.append(("armadillo (100k triangles)", lambda: nd.TriangleMesh.load(LARGE), args.large, 1))
    saved, rows = rounds.AHEAD_EPS_START, []
    try:
        backend.launch_bound = True
        for name, make, count, seeds in cases:
            shape = make()
            for start in args.starts:
                rounds.AHEAD_EPS_START = start
                fills, times, counts = [], [], []
                for seed in range(seeds):
                    began = time.perf_counter()
                    packing = nd.pack(shape, count, mode="fast", backend=backend, seed=seed, progress=False,
                                      on_invalid="raise")
                    times.append(time.perf_counter() - began)
                    fills.append(float(packing.fill))
                    counts.append(len(packing.stats.count))
                steps = int(np.count_nonzero(polish <= start))
                rows.append(dict(shape=name, count=count, start=start, polish_steps=steps, fills=fills,
                                 fill=float(np.mean(fills)), rounds=counts, seconds=float(np.median(times))))
                whole = next(row["fill"] for row in rows if row["shape"] == name)
                print(f"{name:28s} {count:>7,} from eps {start:<6g} ({steps:2d} steps): fill {rows[-1]['fill']:.5f} "
                      f"({rows[-1]['fill'] / whole:.4f} of the first start's), rounds {counts}", flush=True)
    finally:
        backend.launch_bound = False
        rounds.AHEAD_EPS_START = saved
    if args.out:
        command = "python bench/ahead_tail.py" + (f" --count {args.count}" if args.count != 10_000 else "")
        write_json(args.out, dict(machine=machine_info(), command=command,
                                  rows=[{**row, "start": None if row["start"] == np.inf else row["start"]}
                                        for row in rows]))


if __name__ == "__main__":
    main()
