"""Start-up cost with and without the kernel cache on disk.

Each backend packs the same shape in fresh processes that share one new ``$NDPACK_CACHE``:
the first process compiles (a cold cache), the later ones load (a warm cache); Warp's own
binary cache is moved there too (``WARP_CACHE_PATH``). Inside each process the shape is packed
twice, so the second packing's time is the packing alone and the difference is what starting
the backend cost: compiling, or loading the cached code. The process's wall time also counts
Python's start, imports and loading the shape (a mesh's own queries compile there).

    python bench/compile_cache.py --backends numba --shape tests/data/meshes/armadillo-20k.ply
    python bench/compile_cache.py --backends numba warp:cuda:0 numba-cuda --shape ... --out x.json

Writes one JSON row per process (backend, run, start-up and packing seconds, count, fill, the
packing's radius sum, valid) and prints a table.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time

CHILD = """
import json, sys, time
import numpy as np
import ndpack as nd
from ndpack.sources import load_shape

spec, backend, count = sys.argv[1], sys.argv[2], int(sys.argv[3])
shape = load_shape(spec)
times = []
for _ in range(2):
    start = time.perf_counter()
    packing = nd.pack(shape, count, mode="fast", backend=backend, seed=0)
    times.append(time.perf_counter() - start)
print(json.dumps({"first": times[0], "second": times[1], "count": len(packing), "fill": packing.fill,
                  "radius_sum": float(np.sum(packing.radii)), "valid": bool(packing.verify().ok)}))
"""


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--backends", nargs="+", default=["numba"])
    parser.add_argument("--shape", default="demo", help="anything `ndpack pack` takes (default: demo)")
    parser.add_argument("-n", type=int, default=2000, help="spheres per packing (default 2000)")
    parser.add_argument("--runs", type=int, default=3, help="processes per backend, the first cold (default 3)")
    parser.add_argument("--out", help="JSON file for the rows")
    args = parser.parse_args(argv)

    rows = []
    for backend in args.backends:
        with tempfile.TemporaryDirectory(prefix="ndpack-cache-") as cache:
            for run in range(args.runs):
                start = time.perf_counter()
                result = subprocess.run(
                    [sys.executable, "-c", CHILD, args.shape, backend, str(args.n)],
                    capture_output=True, text=True,
                    env={**os.environ, "NDPACK_CACHE": cache, "WARP_CACHE_PATH": os.path.join(cache, "warp-binaries")},
                )
                wall = time.perf_counter() - start
                if result.returncode != 0:
                    print(f"{backend} run {run}: failed\n{result.stderr[-2000:]}", file=sys.stderr)
                    break
                row = json.loads(result.stdout.strip().splitlines()[-1])
                row.update(backend=backend, run=run, cache="cold" if run == 0 else "warm", wall=wall,
                           start_up=row["first"] - row["second"])
                rows.append(row)
                print(f"{backend:14s} {row['cache']:5s} process {wall:6.1f} s, start-up {row['start_up']:6.1f} s, "
                      f"packing {row['second']:5.2f} s, {row['count']} spheres, fill {row['fill']:.4f}, "
                      f"radius sum {row['radius_sum']:.12g}, valid {row['valid']}", flush=True)
    if args.out:
        with open(args.out, "w") as handle:
            json.dump({"shape": args.shape, "n": args.n, "rows": rows}, handle, indent=1)
    return 0 if rows and all(row["valid"] for row in rows) else 1


if __name__ == "__main__":
    sys.exit(main())
