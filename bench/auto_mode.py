"""Faithful against fast mode at equal counts, small to medium: the evidence for ``mode="auto"``.

    python bench/auto_mode.py --out bench/results/auto_mode_2core.json [--repeats 3]

For each shape and count, packs with ``mode="faithful"`` and ``mode="fast"`` (numba, seed 0) and
records the median time of ``--repeats`` runs, the fill, and their ratios. ``mode="auto"`` takes
the fast mode above ``AUTO_FAST_ABOVE`` spheres; this table says whether the fast mode is as good there
(4-D and up: bench/fast_fill.py).
"""

from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

import numpy as np

import ndpack as nd
from ndpack.drivers.greedy.protosphere import AUTO_FAST_ABOVE, choose_mode

from _common import machine_info, write_json


def shapes(mesh: str | None) -> dict:
    """Name -> shape: 2-D, 3-D (CSG and, given, a mesh) and 4-D cases."""
    found = {
        "unit square": nd.Box([0, 0], [1, 1]),
        "cube minus ball": nd.Box([0, 0, 0], [1, 1, 1]) - nd.Ball([1, 1, 1], 0.6),
        "4-ball, two holes": nd.Ball(np.zeros(4), 1.0) - nd.Ball(np.full(4, 0.3), 0.4) - nd.Ball(np.full(4, -0.4), 0.3),
        "4-ball shell": nd.Ball(np.zeros(4), 1.0) - nd.Ball(np.zeros(4), 0.5),
    }
    if mesh:
        found[Path(mesh).stem] = nd.TriangleMesh.load(mesh)
    return found


def timed(shape, count: int, mode: str, repeats: int) -> tuple[float, float]:
    """Median seconds of ``repeats`` packings, and the fill (equal on every repeat: seeded)."""
    seconds, fill = [], None
    for _ in range(repeats):
        started = time.perf_counter()
        packing = nd.pack(shape, n=count, mode=mode, backend="numba", seed=0, progress=False)
        seconds.append(time.perf_counter() - started)
        fill = packing.fill
    return statistics.median(seconds), fill


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--counts", type=int, nargs="+", default=[50, 200, 1000, 5000])
    parser.add_argument("--mesh", default=None, help="also a mesh file, e.g. ../shared/data/meshes/cow.obj")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--out", type=Path, default=Path("bench/results/auto_mode_2core.json"))
    args = parser.parse_args()
    nd.pack(nd.Box([0, 0, 0], [1, 1, 1]), n=20, mode="fast", backend="numba", progress=False)  # compile
    nd.pack(nd.Box([0, 0, 0], [1, 1, 1]), n=20, mode="faithful", backend="numba", progress=False)
    rows = []
    print("| shape | count | faithful s | fast s | fast / faithful time | fast / faithful fill | auto takes |")
    print("|---|---:|---:|---:|---:|---:|---|")
    for name, shape in shapes(args.mesh).items():
        for count in args.counts:
            faithful_s, faithful_fill = timed(shape, count, "faithful", args.repeats)
            fast_s, fast_fill = timed(shape, count, "fast", args.repeats)
            auto = choose_mode("auto", count, shape.dim, 1)[0]
            rows.append(dict(shape=name, dim=shape.dim, count=count, faithful_s=faithful_s, fast_s=fast_s,
                             faithful_fill=faithful_fill, fast_fill=fast_fill, auto=auto))
            print(f"| {name} | {count:,} | {faithful_s:.2f} | {fast_s:.2f} | {fast_s / faithful_s:.2f} | "
                  f"{fast_fill / faithful_fill:.4f} | {auto} |", flush=True)
    write_json(args.out, dict(machine=machine_info(), numba=__import__("numba").__version__,
                              repeats=args.repeats, auto_fast_above=AUTO_FAST_ABOVE,
                              rows=rows))


if __name__ == "__main__":
    main()
