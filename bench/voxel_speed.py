"""2,000 spheres in the unit cube against the method a user would write with SciPy, quiet and busy.

    python bench/voxel_speed.py --out bench/results/voxel_speed_2core_issue47.json [--loads 0 2]

The SciPy method is ``bench/scale.py``'s ``voxel_greedy``: the Euclidean distance transform of a
``--voxels``^3 grid, take the maximum, insert, update the distances near the new sphere (one run
per load: it is single-threaded and steady). ndpack packs the same count with ``mode="auto"``
(numba, seed 0), with the default threads and on one thread, ``--repeats`` runs each
(interleaved, median), verified. Each load (``--loads``: spinning processes beside the runs,
bench/_load.py) runs all of it again; the ratio is the voxel method's time over ndpack's.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

import ndpack as nd
from ndpack.backends.numba_backend import NumbaBackend

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import load_average, machine_info, write_json
from _load import busy
from scale import voxel_greedy


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--count", type=int, default=2000)
    parser.add_argument("--voxels", type=int, default=256)
    parser.add_argument("--loads", type=int, nargs="+", default=[0, 2])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--out", type=Path)
    args = parser.parse_args()
    cube = nd.Box([0, 0, 0], [1, 1, 1])
    backends = {"default threads": "numba", "one thread": NumbaBackend(threads=1)}
    nd.pack(cube, n=20, mode="fast", backend="numba", progress=False)  # compile or load the kernels
    rows = []
    for load in args.loads:
        with busy(load):
            started_load = load_average()
            _, radii, voxel_seconds = voxel_greedy(args.voxels, args.count)
            row = dict(load_processes=load, load_average_start=started_load, voxel_seconds=voxel_seconds,
                       voxel_spheres=len(radii), voxel_fill=float(nd.ball_volume(3, radii).sum()))
            times = {name: [] for name in backends}
            for _ in range(args.repeats):
                for name, backend in backends.items():
                    started = time.perf_counter()
                    packing = nd.pack(cube, n=args.count, mode="auto", backend=backend, seed=0, progress=False)
                    times[name].append(time.perf_counter() - started)
                    assert packing.verify().ok and len(packing) == args.count
                    row["fill"] = float(packing.fill)
            for name, values in times.items():
                key = name.replace(" ", "_")
                row[f"{key}_s"] = statistics.median(values)
                row[f"{key}_runs"] = values
                row[f"{key}_ratio"] = voxel_seconds / statistics.median(values)
        rows.append(row)
        print(f"{load} busy: voxels {voxel_seconds:.1f} s ({len(radii)} spheres, fill {row['voxel_fill']:.4f}); "
              f"ndpack {row['default_threads_s']:.2f} s ({row['default_threads_ratio']:.1f}x), one thread "
              f"{row['one_thread_s']:.2f} s ({row['one_thread_ratio']:.1f}x), fill {row['fill']:.4f}", flush=True)
    if args.out:
        write_json(args.out, dict(machine=machine_info(), count=args.count, voxels=args.voxels, repeats=args.repeats,
                                  command="python bench/voxel_speed.py " + " ".join(sys.argv[1:]), rows=rows))


if __name__ == "__main__":
    main()
