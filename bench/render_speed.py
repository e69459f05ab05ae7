"""How long a shaded 3-D picture takes (``ndpack.pictures.render``), up to a million spheres.

A fast-mode packing of the unit cube is tiled into side-by-side copies (still disjoint) to reach
each count without packing a million spheres first. Times are medians of ``--repeats`` after a
warm-up that compiles: the image alone, and with its PNG written.

    python bench/render_speed.py --out bench/results/render_speed_2core.json
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import ndpack as nd
from ndpack.pictures import render

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import machine_info, write_json

ROOT = Path(__file__).resolve().parent.parent


def tiled(packing, copies):
    """``copies`` unit cubes in a row along x, each holding the packing: (n * copies) spheres."""
    offsets = np.zeros((copies, 3))
    offsets[:, 0] = np.arange(copies)
    centers = (packing.centers[None, :, :] + offsets[:, None, :]).reshape(-1, 3)
    radii = np.tile(packing.radii, copies)
    rounds = np.tile(packing.rounds, copies)
    return nd.Packing(centers, radii, rounds, volume=float(copies))


def median_seconds(repeats, function, *args, **options):
    times = []
    for _ in range(repeats):
        started = time.perf_counter()
        function(*args, **options)
        times.append(time.perf_counter() - started)
    return float(np.median(times))


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--base", type=int, default=100_000, help="spheres packed in one cube")
    parser.add_argument("--copies", type=int, nargs="+", default=[1, 10])
    parser.add_argument("--size", type=int, nargs=2, default=[900, 900])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--out", default=str(ROOT / "bench" / "results" / "render_speed.json"))
    args = parser.parse_args()
    base = nd.pack(nd.Box(np.zeros(3), np.ones(3)), args.base, mode="fast", backend="numba")
    render(base, size=(64, 64))  # compile
    runs = []
    with tempfile.TemporaryDirectory() as folder:
        for copies in args.copies:
            packing = tiled(base, copies)
            for view in ((35.0, 25.0), (0.0, 90.0)):
                size = tuple(args.size)
                image_s = median_seconds(args.repeats, render, packing, size=size, view=view)
                png = Path(folder) / "render.png"
                file_s = median_seconds(args.repeats, render, packing, png, size=size, view=view)
                run = dict(spheres=len(packing), size=args.size, view=view, image_s=image_s, with_png_s=file_s)
                print(run, flush=True)
                runs.append(run)
    write_json(Path(args.out), dict(machine=machine_info(), args=vars(args), runs=runs))


if __name__ == "__main__":
    main()
