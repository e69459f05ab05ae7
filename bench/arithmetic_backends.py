"""Python's ``//``, ``%`` and ``**`` in a scalar plug-in, packed on every backend that runs here.

A square less a lattice of discs, written with ``%``, ``//`` and ``**`` over negative and
positive coordinates, is packed on each backend; each packing is verified against the same shape
written in NumPy (whose ``np.mod`` and ``np.floor_divide`` follow Python), and its radii compared
with the first backend's. A backend that printed C's ``%`` or ``//`` would put the discs in the
wrong places and fail. The largest gap, at the cells' corners, is known: spacing / sqrt(2) - radius.

    python bench/arithmetic_backends.py --backends numba warp:cuda:0 numba-cuda --out results.json
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

import numpy as np

import ndpack as nd

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import machine_info, write_json

BOUNDS = [[-2.05, -2.05], [2.05, 2.05]]
SPACING, RADIUS = 0.5, 0.2


@nd.scalar_plugin(dim=2, bounds=BOUNDS, params=[SPACING, RADIUS], exact_inside=True)
def lattice(p, params):
    """Discs of radius params[1] at the centres of a grid of cells params[0] wide."""
    s = params[0]
    dx = p[0] % s - 0.5 * s
    dy = p[1] - s * (p[1] // s) - 0.5 * s
    return (dx ** 2 + dy ** 2) ** 0.5 - params[1]


@nd.plugin(dim=2, bounds=BOUNDS, exact_inside=True)
def lattice_numpy(p):
    """The same discs, in NumPy."""
    d = np.mod(p, SPACING) - 0.5 * SPACING
    return np.hypot(d[:, 0], d[:, 1]) - RADIUS


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--backends", nargs="+", default=["numba", "warp:cpu"],
                        help="compiled backends (numba first: the others' radii are compared with it)")
    parser.add_argument("-n", type=int, default=400)
    parser.add_argument("--out", default=None)
    args = parser.parse_args()
    box = nd.Box([-2, -2], [2, 2])
    points = np.random.default_rng(0).uniform(-2.05, 2.05, (100_000, 2))
    gap = float(np.abs(lattice.distance(points) - lattice_numpy.distance(points)).max())
    print(f"distance, numba CPU form against NumPy: largest difference {gap:.3g}")
    reference, rows = None, []
    for backend in args.backends:
        started = time.perf_counter()
        packing = nd.pack(box - lattice, n=args.n, mode="fast", backend=backend)
        seconds = time.perf_counter() - started
        check = packing.verify(box - lattice_numpy)
        if reference is None:
            reference = packing.radii
        same = len(packing) == len(reference) and bool(np.allclose(packing.radii, reference, rtol=1e-9, atol=1e-12))
        row = dict(backend=backend, spheres=len(packing), valid_against_numpy=check.ok, radii_equal_first=same,
                   largest=float(packing.radii.max()), seconds_with_compile=seconds)
        print(row, flush=True)
        rows.append(row)
    largest = max(row["largest"] for row in rows)
    corner_gap = SPACING / math.sqrt(2) - RADIUS
    valid = all(row["valid_against_numpy"] for row in rows)
    equal = all(row["radii_equal_first"] for row in rows)
    print(f"largest radius {largest:.6f} (the corner gap: {corner_gap:.6f}); all valid: {valid}; all equal: {equal}")
    assert math.isclose(largest, corner_gap, rel_tol=1e-3), "the largest sphere should fill a corner gap"
    if args.out:
        write_json(Path(args.out), dict(machine=machine_info(), distance_gap=gap, runs=rows))


if __name__ == "__main__":
    main()
