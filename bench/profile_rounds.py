"""Where a round's time goes: cProfile of one packing per backend, top functions by own time.

    python bench/profile_rounds.py --backends warp numba-cuda --count 3000
    python bench/profile_rounds.py --backends warp --mode fast --count 1000000 --mesh armadillo.obj --out host.txt

Compiles first (a 3-sphere packing), then profiles the packing alone. Prints rounds per second,
the functions that take the most time themselves, and ndpack's functions by the time spent in
them and what they call (where the host's round goes); on a GPU, time spent waiting for the
device shows up in the synchronising calls (fetch). ``--kernels`` instead times each device-store call
(kernel launches synchronised one by one, uploads, fetches) on the GPU backends: slower overall,
but it says which kernel costs what.
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
    parser.add_argument("--kernels", action="store_true", help="time each device call (GPU backends)")
    parser.add_argument("--mode", default="faithful", choices=["faithful", "fast"])
    parser.add_argument("--mesh", default=None, help="a mesh file; default the unit cube")
    parser.add_argument("--out", default=None, help="also write the listings to this text file")
    args = parser.parse_args()
    shape = nd.TriangleMesh.load(args.mesh) if args.mesh else nd.Box(np.zeros(3), np.ones(3))
    listings = []
    for backend in args.backends:
        nd.pack(shape, 3, backend=backend)
        if args.kernels:
            time_device_calls(shape, backend, args.count, args.batch)
            continue
        profile = cProfile.Profile()
        started = time.perf_counter()
        profile.enable()
        packing = nd.pack(shape, args.count, backend=backend, batch=args.batch, mode=args.mode, progress=False)
        profile.disable()
        wall = time.perf_counter() - started
        rounds = len(packing.stats.time)
        listing = [f"== {backend}, {args.mode}: {len(packing.radii)} spheres, {rounds} rounds in {wall:.2f} s "
                   f"({1e3 * wall / rounds:.3f} ms a round, profiled)", "-- by own time"]
        listing += _listing(profile, "tottime", args.top)
        listing += ["-- ndpack's functions, by time in them and their calls"]
        listing += _listing(profile, "cumulative", 2 * args.top, "ndpack")
        print("\n".join(listing))
        listings += listing
    if args.out:
        with open(args.out, "w") as file:
            file.write("\n".join(listings) + "\n")


def _listing(profile, key, top, only=None):
    """Lines of a cProfile listing sorted by ``key``, its ``top`` rows (of the paths holding ``only``)."""
    text = io.StringIO()
    stats = pstats.Stats(profile, stream=text).sort_stats(key)
    stats.print_stats(*([only] if only else []), top)
    return [line for line in text.getvalue().splitlines()[6:] if line.strip()]


def time_device_calls(shape, backend, count, batch):
    """Seconds and calls per device-store operation, each launch synchronised on its own."""
    from ndpack.backends.prototypes import DevicePrototypes

    totals = {}
    original = DevicePrototypes.__init__

    def timed(name, function, synchronise):
        def wrapper(*args, **kwargs):
            started = time.perf_counter()
            result = function(*args, **kwargs)
            synchronise()
            key = name if name != "launch" else f"launch {args[0]}"
            seconds, calls = totals.get(key, (0.0, 0))
            totals[key] = (seconds + time.perf_counter() - started, calls + 1)
            return result
        return wrapper

    def instrumented(self, device, *rest):
        original(self, device, *rest)
        synchronise = device.synchronize
        for name in ("launch", "upload", "fetch", "fill", "spheres"):
            setattr(device, name, timed(name, getattr(device, name), synchronise))

    DevicePrototypes.__init__ = instrumented
    try:
        started = time.perf_counter()
        packing = nd.pack(shape, count, backend=backend, batch=batch, mode="faithful")
        wall = time.perf_counter() - started
    finally:
        DevicePrototypes.__init__ = original
    rounds = len(packing.stats.time)
    print(f"== {backend} (each call synchronised): {len(packing.radii)} spheres, {rounds} rounds, batch {batch}, "
          f"{wall:.2f} s")
    for key, (seconds, calls) in sorted(totals.items(), key=lambda item: -item[1][0]):
        print(f"  {key:24s} {seconds:8.3f} s  {calls:7d} calls  {1e6 * seconds / calls:9.1f} us each")


if __name__ == "__main__":
    main()
