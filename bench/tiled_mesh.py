"""A mesh in tiles: why it is slow. ``nd.pack`` of a mesh, of the mesh intersected with a box
around it (what each tile packs: ``mesh & Box``), and ``nd.pack_tiled`` of the mesh.

    ndpack samples .
    python bench/tiled_mesh.py --mesh cow.obj --count 20000 --workers 1 2 --out bench/results/tiled_mesh_2core.json

A mesh alone has a closed-form gradient (its nearest triangle); an intersection's is taken by
differences, d + 1 distances a step, so a tile's run costs several times the mesh's own. One run
each, seed 0, the default backend.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import ndpack as nd

from _common import machine_info, write_json


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--mesh", default="cow.obj")
    parser.add_argument("--count", type=int, default=20_000)
    parser.add_argument("--workers", type=int, nargs="*", default=[1, 2])
    parser.add_argument("--out", type=Path, default=Path("bench/results/tiled_mesh_2core.json"))
    args = parser.parse_args()
    mesh = nd.TriangleMesh.load(args.mesh)
    lower, upper = mesh.bounds
    clipped = mesh & nd.Box(lower - 0.1 * (upper - lower), upper + 0.1 * (upper - lower))  # cuts nothing
    nd.pack(mesh, n=500, progress=False)
    nd.pack(clipped, n=500, progress=False)  # compile both first
    rows = []
    for label, run in [("mesh alone", lambda: nd.pack(mesh, n=args.count, seed=0, progress=False)),
                       ("mesh & box", lambda: nd.pack(clipped, n=args.count, seed=0, progress=False))] + [
            (f"tiled, {workers} workers", lambda workers=workers: nd.pack_tiled(mesh, n=args.count, workers=workers,
                                                                                seed=0, progress=False))
            for workers in args.workers]:
        started = time.perf_counter()
        packing = run()
        seconds = time.perf_counter() - started
        rows.append(dict(run=label, spheres=len(packing), seconds=round(seconds, 3), fill=packing.fill))
        print(f"{label}: {len(packing):,} spheres in {seconds:.1f} s, fill {packing.fill:.4f}", flush=True)
    write_json(args.out, dict(machine=machine_info(), mesh=Path(args.mesh).name, count=args.count, rows=rows))


if __name__ == "__main__":
    main()
