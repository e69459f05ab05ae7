"""The fast mode's fill against the faithful mode's, 4-D to 6-D, at equal counts (issue 47).

    python bench/fast_fill.py --out bench/results/fast_fill_2core.json
    python bench/fast_fill.py --dims 4 5 --counts 1000 --seeds 3 --modes fast   # fast only, against a file
    python bench/fast_fill.py --faithful-from bench/results/fast_fill_2core.json --modes fast --out new.json

For each shape (a ball with a hole, a simplex, a CSG part, a periodic box with a radius range),
dimension and count, packs with each mode (numba) for ``--seeds`` seeds and records the mean
fill, its spread over the seeds and the median seconds. Greedy packings of a thousand spheres
differ by about half a percent from seed to seed (which of two equal gaps is taken first), so
the comparison is of the seeds' mean fills. ``--faithful-from`` reuses the faithful rows of an
earlier file (the faithful mode is not what changes, and it is the slow one). Every packing is
verified.
"""

from __future__ import annotations

import argparse
import json
import statistics
import time
from pathlib import Path

import numpy as np

import ndpack as nd

from _common import machine_info, write_json


def shape_of(name: str, dim: int):
    """The case's shape and the packing's radius options."""
    if name == "ball with a hole":
        return nd.Ball(np.zeros(dim), 1.0) - nd.Ball(np.zeros(dim), 0.5), {}
    if name == "simplex":
        return nd.Simplex(np.vstack([np.zeros(dim), np.eye(dim)])), {}
    if name == "csg part":
        cube = nd.Box(np.zeros(dim), np.ones(dim))
        return (cube - nd.Ball(np.ones(dim), 0.6)) | nd.Ball(np.full(dim, 0.2), 0.35), {}
    if name == "periodic box, radii 0.03-0.2":
        return nd.Periodic(nd.Box(np.zeros(dim), np.ones(dim))), dict(min_radius=0.03, max_radius=0.2)
    raise ValueError(name)


SHAPES = ["ball with a hole", "simplex", "csg part", "periodic box, radii 0.03-0.2"]


def one(name: str, dim: int, count: int, mode: str, seeds: int) -> dict:
    shape, options = shape_of(name, dim)
    fills, seconds, placed = [], [], []
    for seed in range(seeds):
        started = time.perf_counter()
        packing = nd.pack(shape, n=count, mode=mode, backend="numba", seed=seed, progress=False, **options)
        seconds.append(time.perf_counter() - started)
        assert packing.verify().ok, (name, dim, count, mode, seed)
        fills.append(packing.fill)
        placed.append(len(packing))
    return dict(shape=name, dim=dim, count=count, mode=mode, fills=fills, mean_fill=statistics.fmean(fills),
                spread=(max(fills) - min(fills)) / statistics.fmean(fills), spheres=placed,
                median_s=statistics.median(seconds), rounds=len(packing.stats.count))


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--shapes", nargs="+", default=SHAPES, choices=SHAPES)
    parser.add_argument("--dims", type=int, nargs="+", default=[4, 5, 6])
    parser.add_argument("--counts", type=int, nargs="+", default=[100, 1000])
    parser.add_argument("--seeds", type=int, default=3)
    parser.add_argument("--modes", nargs="+", default=["faithful", "fast"])
    parser.add_argument("--faithful-from", type=Path, help="reuse this file's faithful rows")
    parser.add_argument("--out", type=Path)
    parser.add_argument("--append", action="store_true", help="add the rows to --out's, if it exists")
    args = parser.parse_args()
    earlier = {}
    if args.faithful_from:
        for row in json.loads(args.faithful_from.read_text())["rows"]:
            if row["mode"] == "faithful":
                earlier[row["shape"], row["dim"], row["count"]] = row
    nd.pack(nd.Box(np.zeros(4), np.ones(4)), n=20, mode="fast", backend="numba", progress=False)  # compile
    rows = []
    print("| shape | dim | count | mode | mean fill | spread | fast / faithful | median s |")
    print("|---|---:|---:|---|---:|---:|---:|---:|")
    for name in args.shapes:
        dims = [dim for dim in args.dims if not name.startswith("periodic") or dim <= 4]
        for dim in dims:
            for count in args.counts:
                found = {}
                for mode in args.modes:
                    row = one(name, dim, count, mode, args.seeds)
                    rows.append(row)
                    found[mode] = row
                if "faithful" not in found and (name, dim, count) in earlier:
                    found["faithful"] = earlier[name, dim, count]
                    rows.append(found["faithful"])
                for mode, row in found.items():
                    ratio = ""
                    if mode == "fast" and "faithful" in found:
                        ratio = f"{row['mean_fill'] / found['faithful']['mean_fill']:.4f}"
                    print(f"| {name} | {dim} | {count:,} | {mode} | {row['mean_fill']:.5f} | {row['spread']:.4f} | "
                          f"{ratio} | {row['median_s']:.2f} |", flush=True)
    if args.out:
        if args.append and args.out.exists():
            rows = json.loads(args.out.read_text())["rows"] + rows
        write_json(args.out, dict(machine=machine_info(), numba=__import__("numba").__version__, seeds=args.seeds,
                                  rows=rows))


if __name__ == "__main__":
    main()
