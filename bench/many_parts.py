"""Parts per minute against the number of workers: ``nd.pack_many`` on a local process pool.

    python bench/many_parts.py --workers 1 2 --count 2000 --out bench/results/many_parts_2core.json

The parts: the three sample meshes (``ndpack samples``) and built-in shapes in 2-D to 4-D, twelve
in all, each packed to ``--count`` spheres (seed 0, the default mode) into a fresh folder per
run. Reports wall seconds, parts per minute and the speed-up over one worker (one worker packs
in this process, so its time has no pool start; the pool's runs include starting the workers
and compiling in each, as a user's first run would on a warm kernel cache).
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import ndpack as nd
import ndpack.samples

from _common import machine_info, write_json

SPECS = ["box:dim=2", "annulus:dim=2", "ball:dim=3", "annulus:dim=3", "torus", "demo", "box:dim=3",
         "simplex:dim=3", "annulus:dim=4"]


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--workers", type=int, nargs="+", default=[1, 2])
    parser.add_argument("--count", type=int, default=2000)
    parser.add_argument("--no-meshes", action="store_true",
                        help="built-in shapes only (three more in place of the meshes): for a machine without trimesh")
    parser.add_argument("--out", type=Path, default=Path("bench/results/many_parts_2core.json"))
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        if args.no_meshes:
            # annulus:dim=2 is cut by manifold3d, which that machine lacks too.
            sources = [spec for spec in SPECS if spec != "annulus:dim=2"] + ["simplex:dim=2", "box:dim=4",
                                                                              "annulus:dim=3,inner=0.3", "torus"]
        else:
            sources = [str(path) for path in ndpack.samples.write(folder, robot=False)] + SPECS
        nd.pack_many(sources, n=50, workers=1)  # compile every kernel once, into the on-disk cache
        rows = []
        for workers in args.workers:
            started = time.perf_counter()
            result = nd.pack_many(sources, n=args.count, out=Path(folder) / f"out{workers}", workers=workers)
            seconds = time.perf_counter() - started
            assert result.ok, result.summary()
            rows.append(dict(workers=workers, parts=len(sources), seconds=seconds,
                             parts_per_minute=60 * len(sources) / seconds,
                             packing_seconds=sum(part["seconds"] for part in result.parts)))
            print(f"{workers} workers: {len(sources)} parts in {seconds:.1f} s, "
                  f"{60 * len(sources) / seconds:.1f} parts/min, speed-up {rows[0]['seconds'] / seconds:.2f}",
                  flush=True)
    write_json(args.out, dict(machine=machine_info(), count=args.count, sources=[Path(s).name for s in sources],
                              rows=rows))


if __name__ == "__main__":
    main()
