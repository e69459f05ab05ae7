"""How much clearance a polish or a move gives up when its cooling schedule stops early.

    python bench/polish_loss.py --mesh armadillo.obj --count 30000 --steps 40 50 60 70

Runs a fast-mode packing with whole schedules (no cut) and, at every polish and move, also
converges the same prototypes from the same points with only the first ``k`` steps; prints the
relative loss ``(c_full - c_k) / c_full`` of the clearances (a polish keeps the better of its start
and its result, as the store does). Twice the moves' work: keep the count moderate.
"""

from __future__ import annotations

import argparse

import numpy as np

import ndpack as nd
from ndpack.drivers.greedy import protosphere
from ndpack.backends import prototypes


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--mesh", default=None, help="a mesh file; default the unit cube")
    parser.add_argument("--count", type=int, default=30_000)
    parser.add_argument("--steps", nargs="+", type=int, default=[30, 40, 50, 60, 70, 80, 90])
    args = parser.parse_args()
    shape = nd.TriangleMesh.load(args.mesh) if args.mesh else nd.Box(np.zeros(3), np.ones(3))
    protosphere.FAST_EPS_END = protosphere.FAST_POLISH_EPS_END = 0.0  # whole schedules
    found = {"polish": [], "move": []}
    original = prototypes.HostPrototypes.move

    def move(self, ids, centers, radii, steps, starts=None, polish=False):
        backend, lower, upper = self.backend, self.cell_lower[ids], self.cell_upper[ids]
        start, before = self.points[ids].copy(), self.clearance[ids].copy()
        near, _ = backend.near_spheres(lower, upper, self.reach[ids].copy(), centers, radii, return_bound=True)
        rows = []
        for k in [len(steps)] + [k for k in args.steps if k < len(steps)]:
            clearance = backend.converge(self.shape, start, lower, upper, centers, radii, near, steps[:k],
                                         self.wall[ids], starts)[1]
            rows.append(np.maximum(before, clearance) if polish else clearance)
        found["polish" if polish else "move"].append((len(steps), rows))
        return original(self, ids, centers, radii, steps, starts, polish)

    prototypes.HostPrototypes.move = move
    nd.pack(shape, args.count, backend="numba", mode="fast", progress=False)
    for kind, calls in found.items():
        total = calls[0][0]
        full = np.concatenate([rows[0] for _, rows in calls])
        keep = full > 0
        print(f"{kind}: {keep.sum():,} prototypes, whole schedule {total} steps")
        for j, k in enumerate(k for k in args.steps if k < total):
            loss = (full - np.concatenate([rows[j + 1] for _, rows in calls]))[keep] / full[keep]
            print(f"  first {k:3d} steps: loss median {np.median(loss):.1e}  p90 {np.quantile(loss, 0.9):.1e}  "
                  f"p99 {np.quantile(loss, 0.99):.1e}  max {loss.max():.1e}")


if __name__ == "__main__":
    main()
