"""Where the host's time goes in one fast-mode packing: cProfile, sorted by own time.

    python bench/host_profile.py --backend warp --mesh armadillo.obj --count 100000 [--top 30]

Compiles first (a 3-sphere packing). Kernel launches are asynchronous, so a GPU's kernels show up
in the calls that wait for them (the copies back to the host); bench/profile_kernels.py times
each launch instead.
"""

from __future__ import annotations

import argparse
import cProfile
import pstats
import time

import numpy as np

import ndpack as nd


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--backend", default="numba")
    parser.add_argument("--count", type=int, default=100_000)
    parser.add_argument("--mesh", default=None, help="a mesh file; default the unit cube")
    parser.add_argument("--top", type=int, default=30)
    args = parser.parse_args()
    shape = nd.TriangleMesh.load(args.mesh) if args.mesh else nd.Box(np.zeros(3), np.ones(3))
    nd.pack(shape, 3, backend=args.backend, mode="fast")
    profile = cProfile.Profile()
    started = time.perf_counter()
    profile.enable()
    packing = nd.pack(shape, args.count, backend=args.backend, mode="fast")
    profile.disable()
    print(f"{args.backend}: {len(packing.radii)} spheres, {len(packing.stats.time)} rounds, "
          f"{time.perf_counter() - started:.2f} s profiled")
    pstats.Stats(profile).sort_stats("tottime").print_stats(args.top)


if __name__ == "__main__":
    main()
