"""Faithful against fast mode at equal counts, small to medium: the evidence for ``mode="auto"``.

    python bench/auto_mode.py --out bench/results/auto_mode_2core.json [--repeats 3]
    python bench/auto_mode.py --modes auto --one-thread [--load 2] --out FILE

For each shape and count, packs with ``mode="faithful"`` and ``mode="fast"`` (numba, seed 0) and
records the median time of ``--repeats`` runs, the fill, and their ratios. ``mode="auto"`` takes
the fast mode above ``AUTO_FAST_ABOVE`` spheres; this table says whether the fast mode is as good there
(4-D and up: bench/fast_fill.py).

``--one-thread`` also times each mode on one thread (``NumbaBackend(threads=1)``), interleaved with
the default threads, and adds the quick start's 4-D example (``box:dim=4 -n 500``); ``--load N``
runs N spinning processes beside the whole sweep (bench/_load.py): a machine shared with other work.
"""

from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

import numpy as np

import ndpack as nd
from ndpack.drivers.greedy.protosphere import AUTO_FAST_ABOVE, choose_mode

from _common import load_average, machine_info, write_json
from _load import busy


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


def timed(shape, count: int, mode: str, repeats: int, backends=("numba",)) -> tuple[list[float], float]:
    """Median seconds of ``repeats`` packings on each backend (interleaved), and the fill (equal on
    every repeat and backend: seeded, and threads do not change the spheres)."""
    seconds, fills = [[] for _ in backends], set()
    for _ in range(repeats):
        for times, backend in zip(seconds, backends):
            started = time.perf_counter()
            packing = nd.pack(shape, n=count, mode=mode, backend=backend, seed=0, progress=False)
            times.append(time.perf_counter() - started)
            fills.add(packing.fill)
    assert len(fills) == 1, f"{count} spheres, {mode}: the fill differs between runs ({fills})"
    return [statistics.median(times) for times in seconds], fills.pop()


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--counts", type=int, nargs="+", default=[50, 200, 1000, 5000])
    parser.add_argument("--mesh", default=None, help="also a mesh file, e.g. ../shared/data/meshes/cow.obj")
    parser.add_argument("--modes", nargs="+", default=["faithful", "fast"], choices=["faithful", "fast", "auto"])
    parser.add_argument("--one-thread", action="store_true", help="also time each mode on one thread")
    parser.add_argument("--load", type=int, default=0, help="spinning processes beside the sweep")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--out", type=Path, default=Path("bench/results/auto_mode_2core.json"))
    args = parser.parse_args()
    from ndpack.backends.numba_backend import NumbaBackend

    backends = ("numba", NumbaBackend(threads=1)) if args.one_thread else ("numba",)
    cases = [(name, shape, count) for name, shape in shapes(args.mesh).items() for count in args.counts]
    if args.one_thread:
        cases.append(("quick start box:dim=4", nd.Box(np.zeros(4), np.ones(4)), 500))
    for mode in ("fast", "faithful"):  # compile
        nd.pack(nd.Box([0, 0, 0], [1, 1, 1]), n=20, mode=mode, backend="numba", progress=False)
    rows = []
    columns = [f"{mode} s" + (f" | {mode} 1 thread s" if args.one_thread else "") for mode in args.modes]
    print(f"| shape | count | {' | '.join(columns)} | fill | auto takes |")
    print("|---|---:|" + "---:|" * (len(columns) * len(backends) + 1) + "---|")
    with busy(args.load):
        load = load_average()
        for name, shape, count in cases:
            row = dict(shape=name, dim=shape.dim, count=count, auto=choose_mode("auto", count, shape.dim, 1)[0])
            cells = []
            for mode in args.modes:
                seconds, row[f"{mode}_fill"] = timed(shape, count, mode, args.repeats, backends)
                row[f"{mode}_s"] = seconds[0]
                cells.append(f"{seconds[0]:.2f}")
                if args.one_thread:
                    row[f"{mode}_one_thread_s"] = seconds[1]
                    cells.append(f"{seconds[1]:.2f}")
            if "faithful" in args.modes and "fast" in args.modes:
                row["fast_over_faithful_fill"] = row["fast_fill"] / row["faithful_fill"]
            rows.append(row)
            fill = row.get("fast_over_faithful_fill", row[f"{args.modes[0]}_fill"])
            print(f"| {name} | {count:,} | {' | '.join(cells)} | {fill:.4f} | {row['auto']} |", flush=True)
    write_json(args.out, dict(machine=machine_info(), numba=__import__("numba").__version__,
                              repeats=args.repeats, auto_fast_above=AUTO_FAST_ABOVE, modes=args.modes,
                              load_processes=args.load, load_average_start=load,
                              command="python bench/auto_mode.py " + " ".join(__import__("sys").argv[1:]),
                              rows=rows))


if __name__ == "__main__":
    main()
