"""The device sphere index at armadillo-like scale, against the CPU index: tightened reaches equal.

    python bench/index_stress.py [numba-cuda | warp]

Spheres with radii over five orders of magnitude in a 100-unit box (offset from the origin, as a
mesh's coordinates are), and boxes of three sizes with random reaches; the store's neighbour
tables are built through the device index in chunks of 16,384 rows, as a packing's moves are,
for a growing sphere set. Written to hunt the numba-cuda crash at about 410,000 spheres in the
armadillo (docs/benchmarks.md): on an H100 these checks all passed without it.
"""

from __future__ import annotations

import sys
import time

import numpy as np

import ndpack as nd
from ndpack.backends.numba_backend import NumbaBackend

CHUNK = 16_384


def main():
    name = sys.argv[1] if len(sys.argv) > 1 else "numba-cuda"
    backend = nd.backends.get_backend(name)
    host = NumbaBackend()
    rng = np.random.default_rng(1)
    dim = 3
    for spheres, cells, offset in ((50_000, 20_000, -50.0), (420_000, 200_000, -50.0), (420_000, 200_000, 30.0)):
        centers = offset + 100.0 * rng.random((spheres, dim))
        radii = 25.0 * rng.random(spheres) ** 12 + 1e-4
        lower = offset + 100.0 * rng.random((cells, dim))
        upper = lower + rng.random((cells, 1)) * np.array([1e-3, 0.3, 3.0])[rng.integers(0, 3, cells)][:, None]
        reach = rng.random(cells) * 5.0
        points = lower + (upper - lower) * rng.random((cells, dim))
        box = nd.Box(offset * np.ones(dim), (offset + 100.0) * np.ones(dim))
        store = backend.prototypes(box, lower, upper, reach.copy(), points, rng.random(cells) * 2 - 0.2)
        started = time.perf_counter()
        for count in (spheres // 3, spheres // 2, spheres):
            store.device.write(store.d_reach, 0, reach, "float")
            for start in range(0, cells, CHUNK):
                ids = np.arange(start, min(start + CHUNK, cells))
                store._neighbours(ids, store.device.upload(ids, "index"), centers[:count], radii[:count])
            store.device.synchronize()
            _, bound = host.near_spheres(lower, upper, reach, centers[:count], radii[:count], return_bound=True)
            same = np.allclose(store.reach, bound, rtol=0, atol=1e-9)
            print(name, spheres, cells, offset, count, "bounds equal", same,
                  f"{time.perf_counter() - started:.1f}s", flush=True)


if __name__ == "__main__":
    main()
