"""Where a round's time goes: cProfile of one packing per backend, top functions by own time.

    python bench/profile_rounds.py --backends warp numba-cuda --count 3000

Compiles first (a 3-sphere packing), then profiles the packing alone. Prints rounds per second
and the functions that take the most time themselves; on a GPU, time spent waiting for the device
shows up in the synchronising calls (fetch).
"""

from __future__ import annotations

import argparse
import cProfile
import io
import pstats
import time

import numpy as np

import ndpack as nd


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--backends", nargs="+", default=["warp"])
    parser.add_argument("--count", type=int, default=3000)
    parser.add_argument("--batch", type=int, default=1)
    parser.add_argument("--top", type=int, default=18)
    args = parser.parse_args()
    shape = nd.Box(np.zeros(3), np.ones(3))
    for backend in args.backends:
        nd.pack(shape, 3, backend=backend)
        profile = cProfile.Profile()
        started = time.perf_counter()
        profile.enable()
        packing = nd.pack(shape, args.count, backend=backend, batch=args.batch)
        profile.disable()
        wall = time.perf_counter() - started
        rounds = len(packing.stats.time)
        print(f"== {backend}: {len(packing.radii)} spheres, {rounds} rounds in {wall:.2f} s "
              f"({1e3 * wall / rounds:.3f} ms a round, profiled)")
        text = io.StringIO()
        pstats.Stats(profile, stream=text).sort_stats("tottime").print_stats(args.top)
        print("\n".join(line for line in text.getvalue().splitlines()[6:] if line.strip()))


if __name__ == "__main__":
    main()
