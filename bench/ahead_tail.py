"""The polish ahead's schedule and reach (issue 48): fill with a GPU's policies where it starts at each
``eps``, and above each fraction of the frontier.

    python bench/ahead_tail.py --out bench/results/ahead_tail_2core.json
    python bench/ahead_tail.py --starts 3e-4 --fractions 0.64 0.512 0.4 --large-seeds 3 \
        --out bench/results/ahead_fraction_2core.json

A launch-bound backend (a GPU) ends each fast round by polishing ahead in the move launch
(``rounds.POLISH_AHEAD``), with the polish schedule's steps from ``rounds.AHEAD_EPS_START`` down. A move
launch lasts as long as its longest prototype's chain of distance evaluations, a move's and then its
polish's, so the tail's length is the chain's. Numba with ``launch_bound`` set runs the GPU's rounds (the
device store's tests check that the two agree): for each start, the polish ahead's steps and the mean fill
over ``--seeds`` seeds of the unit cube, the unit square and the 20k-triangle armadillo of the tests at
``--count`` spheres, and of the 100k-triangle armadillo at ``--large`` (seed 0). ``inf``: the whole
schedule. ``--fractions``: the polish ahead's reach (``rounds.POLISH_AHEAD``; a fraction of the round's
frontier), with the polish launches a choice still needed (a GPU's launch each, as long as a move's chain).
Every packing is verified.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

import ndpack as nd
from _common import machine_info, write_json
from ndpack.drivers.greedy import protosphere, rounds
from ndpack.drivers.greedy.protosphere import RunState, schedules

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
    parser.add_argument("--fractions", nargs="+", type=float, default=[rounds.POLISH_AHEAD])
    parser.add_argument("--count", type=int, default=10_000)
    parser.add_argument("--seeds", type=int, default=3)
    parser.add_argument("--large", type=int, default=100_000, help="spheres in the 100k-triangle armadillo (0: none)")
    parser.add_argument("--large-seeds", type=int, default=1)
    parser.add_argument("--out", type=Path)
    args = parser.parse_args()
    backend = nd.backends.get_backend("numba")
    polish_steps = schedules("fast", 50)[1]
    cases = [(name, make, args.count, args.seeds) for name, make in SHAPES.items()]
    if args.large and LARGE.exists():
        cases.append(("armadillo (100k triangles)", lambda: nd.TriangleMesh.load(LARGE), args.large, args.large_seeds))
    saved, saved_fraction, rows = rounds.AHEAD_EPS_START, protosphere.POLISH_AHEAD, []
    polish, launches = RunState.polish, []

    def counted(state, ids):  # a choice's polish: a launch of its own on a GPU
        launches[-1] += 1
        return polish(state, ids)

    try:
        backend.launch_bound, RunState.polish = True, counted
        for name, make, count, seeds in cases:
            shape = make()
            for start in args.starts:
                for fraction in args.fractions:
                    rounds.AHEAD_EPS_START, protosphere.POLISH_AHEAD = start, fraction
                    fills, times, counts, launches = [], [], [], []
                    for seed in range(seeds):
                        launches.append(0)
                        began = time.perf_counter()
                        packing = nd.pack(shape, count, mode="fast", backend=backend, seed=seed, progress=False,
                                          on_invalid="raise")
                        times.append(time.perf_counter() - began)
                        fills.append(float(packing.fill))
                        counts.append(len(packing.stats.count))
                    steps = int(np.count_nonzero(polish_steps <= start))
                    rows.append(dict(shape=name, count=count, start=start, polish_steps=steps, fraction=fraction,
                                     fills=fills, fill=float(np.mean(fills)), rounds=counts,
                                     polish_launches=list(launches), seconds=float(np.median(times))))
                    first = next(row["fill"] for row in rows if row["shape"] == name)
                    print(f"{name:28s} {count:>7,} from eps {start:<6g} ({steps:2d} steps) above {fraction:.3f}: "
                          f"fill {rows[-1]['fill']:.5f} ({rows[-1]['fill'] / first:.4f} of the first row's), "
                          f"rounds {counts}, polish launches {launches}", flush=True)
    finally:
        backend.launch_bound, RunState.polish = False, polish
        rounds.AHEAD_EPS_START, protosphere.POLISH_AHEAD = saved, saved_fraction
    if args.out:
        command = "python bench/ahead_tail.py" + (f" --count {args.count}" if args.count != 10_000 else "")
        if args.fractions != [rounds.POLISH_AHEAD] or args.large_seeds != 1:
            command += " --starts " + " ".join(f"{start:g}" for start in args.starts)
            command += " --fractions " + " ".join(f"{fraction:g}" for fraction in args.fractions)
            command += f" --large-seeds {args.large_seeds}"
        write_json(args.out, dict(machine=machine_info(), command=command,
                                  rows=[{**row, "start": None if row["start"] == np.inf else row["start"]}
                                        for row in rows]))


if __name__ == "__main__":
    main()
