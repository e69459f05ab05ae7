"""The fast mode's fill with a GPU's policies against the faithful mode's, at equal counts (issue 48).

    python bench/policy_fill.py --count 10000 --seeds 3 --out bench/results/policy_fill_2core_10k.json

A launch-bound backend (a GPU) runs the fast mode with its own policies: it polishes ahead
(``rounds.POLISH_AHEAD``) and splits cells down to ``rounds.SPLIT_RATIO_AHEAD``. Their rounds are
the GPU's whatever backend computes them, so numba with ``launch_bound`` set gives the GPU's
packings on the CPU (the device store's tests check that the two agree). For the unit cube, the unit
square and the 20k-triangle armadillo of the tests: the mean fill over ``--seeds`` seeds of the
faithful mode, the fast mode with a CPU's policies, and with a GPU's. Every packing is verified.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

import ndpack as nd
from _common import machine_info, write_json

ROOT = Path(__file__).resolve().parent.parent
SHAPES = {
    "unit cube": lambda: nd.Box(np.zeros(3), np.ones(3)),
    "unit square": lambda: nd.Box(np.zeros(2), np.ones(2)),
    "armadillo (20k triangles)": lambda: nd.TriangleMesh.load(ROOT / "tests/data/meshes/armadillo-20k.ply"),
}
#: The runs: (mode, launch_bound).
RUNS = {"faithful": ("faithful", False), "fast, CPU policies": ("fast", False), "fast, GPU policies": ("fast", True)}


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--count", type=int, default=10_000)
    parser.add_argument("--seeds", type=int, default=3)
    parser.add_argument("--out", type=Path)
    args = parser.parse_args()
    backend = nd.backends.get_backend("numba")
    rows = []
    try:
        for name, make in SHAPES.items():
            shape = make()
            for run, (mode, launch_bound) in RUNS.items():
                backend.launch_bound = launch_bound
                fills, times = [], []
                for seed in range(args.seeds):
                    started = time.perf_counter()
                    packing = nd.pack(shape, args.count, mode=mode, backend=backend, seed=seed, progress=False,
                                      on_invalid="raise")
                    times.append(time.perf_counter() - started)
                    fills.append(float(packing.fill))
                rows.append(dict(shape=name, run=run, count=args.count, fills=fills, fill=float(np.mean(fills)),
                                 seconds=float(np.median(times)), split_ratio=packing.params.get("split_ratio"),
                                 polish_ahead=packing.params.get("polish_ahead")))
                faithful = next(row["fill"] for row in rows if row["shape"] == name and row["run"] == "faithful")
                print(f"{name:28s} {run:20s} fill {rows[-1]['fill']:.5f} ({rows[-1]['fill'] / faithful:.4f} of "
                      f"the faithful mode's), {rows[-1]['seconds']:.1f} s", flush=True)
    finally:
        backend.launch_bound = False
    if args.out:
        write_json(args.out, dict(machine=machine_info(), command="python bench/policy_fill.py --count "
                                  f"{args.count} --seeds {args.seeds}", rows=rows))


if __name__ == "__main__":
    main()
