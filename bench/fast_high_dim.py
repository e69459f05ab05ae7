"""The fast mode against the faithful one in 12-D, on a grid of 2 (4,096 cells).

    python bench/fast_high_dim.py --out bench/results/fast_high_dim_2core_issue21.json
    python bench/fast_high_dim.py --repo ../main --backends numba  # another checkout, e.g. before

Each case packs in a fresh process (so that a peak of memory is the case's own; a warm-up
packing of one sphere first keeps compilation out of the time) and reports the seconds, the
spheres, the rounds, the peak resident memory and the pairs the conflict check decided over.
Before issue 21's fix the fast mode's first round listed every pair of its 4,096 candidates (8.4
million, 5.5 s for one sphere), and the NumPy backend's restarts of a few thousand cells built
(points, neighbours, d) arrays of several GB.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import time
from pathlib import Path

CASES = {"ball": (1, "a 12-D unit ball"), "ball-hole": (2000, "a 12-D unit ball less the ball of radius 1/2")}


def one(case: str, backend: str, mode: str) -> dict:
    """Run in this process: the case's packing, measured."""
    import numpy as np

    import ndpack as nd
    import ndpack.drivers.greedy.conflicts as conflicts

    dim = 12
    shape = nd.Ball(np.zeros(dim), 1.0)
    if case == "ball-hole":
        shape = shape - nd.Ball(np.zeros(dim), 0.5)
    count = CASES[case][0]
    print(f"ndpack from {nd.__file__}", file=sys.stderr)
    nd.pack(shape, n=1, grid=2, mode=mode, backend=backend, progress=False)
    pairs = []
    greedy = conflicts.greedy_over_pairs
    conflicts.greedy_over_pairs = lambda n, first, second: pairs.append(len(first)) or greedy(n, first, second)
    started = time.perf_counter()
    packing = nd.pack(shape, n=count, grid=2, mode=mode, backend=backend, progress=False)
    seconds = time.perf_counter() - started
    assert packing.verify().ok
    return dict(case=case, backend=backend, mode=mode, seconds=round(seconds, 3), spheres=len(packing),
                rounds=len(packing.stats.count), fill=packing.fill, conflict_pairs=int(sum(pairs)),
                peak_rss_mb=round(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024))


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--backends", nargs="+", default=["numpy", "numba"])
    parser.add_argument("--cases", nargs="+", default=list(CASES), choices=list(CASES))
    parser.add_argument("--repo", default=str(Path(__file__).resolve().parent.parent),
                        help="the checkout whose ndpack runs (default: this one)")
    parser.add_argument("--out", help="write the results here as JSON")
    parser.add_argument("--one", nargs=3, metavar=("CASE", "BACKEND", "MODE"), help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.one:
        print(json.dumps(one(*args.one)))
        return
    rows = []
    for case in args.cases:
        for backend in args.backends:
            for mode in ("faithful", "fast"):
                done = subprocess.run([sys.executable, __file__, "--one", case, backend, mode], capture_output=True,
                                      text=True, env={**os.environ, "PYTHONPATH": args.repo})
                row = json.loads(done.stdout) if done.returncode == 0 else dict(
                    case=case, backend=backend, mode=mode, error=(done.stderr.strip().splitlines() or ["killed"])[-1])
                print(row, flush=True)
                rows.append(row)
    if args.out:
        from _common import machine_info, write_json

        write_json(Path(args.out), dict(machine=machine_info(), repo=args.repo, rows=rows))


if __name__ == "__main__":
    main()
