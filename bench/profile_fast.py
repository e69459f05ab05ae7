"""Where a fast-mode packing's time goes: cProfile of one run per backend, top functions by own time.

    python bench/profile_fast.py --backends numba-cuda warp --count 30000
        [--mesh armadillo.obj] [--sort tottime cumulative]

Compiles first (a 3-sphere packing), then profiles the packing alone.
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
    parser.add_argument("--backends", nargs="+", default=["numba"])
    parser.add_argument("--count", type=int, default=30_000)
    parser.add_argument("--mesh", default=None, help="a mesh file; default the unit cube")
    parser.add_argument("--top", type=int, default=25)
    parser.add_argument("--sort", nargs="+", default=["tottime"],
                        help="pstats orders to print, e.g. tottime cumulative")
    parser.add_argument("--out", default=None, help="also save the raw profile of each backend here (.prof suffixed)")
    args = parser.parse_args()
    shape = nd.TriangleMesh.load(args.mesh) if args.mesh else nd.Box(np.zeros(3), np.ones(3))
    for backend in args.backends:
        nd.pack(shape, 3, backend=backend, mode="fast")
        profile = cProfile.Profile()
        started = time.perf_counter()
        profile.enable()
        packing = nd.pack(shape, args.count, backend=backend, mode="fast")
        profile.disable()
        wall = time.perf_counter() - started
        print(f"== {backend}: {len(packing.radii)} spheres, {len(packing.stats.time)} rounds in {wall:.2f} s "
              "(profiled)")
        if args.out:
            profile.dump_stats(f"{args.out}.{backend}.prof")
        for order in args.sort:
            text = io.StringIO()
            pstats.Stats(profile, stream=text).sort_stats(order).print_stats(args.top)
            print(f"-- by {order}")
            print("\n".join(line for line in text.getvalue().splitlines()[6:] if line.strip()))


if __name__ == "__main__":
    main()
