"""A process's first packing against its next ones, the compile apart (issue 48).

    python3 bench/first_run.py --mesh armadillo.obj --count 100000 --backend warp --out first_run.json

A command-line user makes one packing a process, so what a first packing costs beyond the next
ones (after a 3-sphere packing has compiled the kernels) is part of what users wait for. Packs
``--repeats`` times (fast mode, seed 0), each timed by stages (set-up, rounds, final check; a
device synchronisation ends each) and with the host's profile of the first and the second run
(own time), so that what only the first pays stands out.
"""

from __future__ import annotations

import argparse
import cProfile
import io
import pstats
import sys
import time
from pathlib import Path

import numpy as np

import ndpack as nd

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import machine_info, write_json
from profile_kernels import device_sync, install_stages


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--mesh", help="a mesh file (else the unit cube)")
    parser.add_argument("--count", type=int, default=100_000)
    parser.add_argument("--backend", default="warp")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--out", type=Path)
    args = parser.parse_args()
    shape = nd.TriangleMesh.load(args.mesh) if args.mesh else nd.Box(np.zeros(3), np.ones(3))
    backend = nd.backends.get_backend(args.backend)
    started = time.perf_counter()
    nd.pack(shape, 3, backend=backend, mode="fast", progress=False)
    runs = [dict(run="3 spheres (compile)", seconds=time.perf_counter() - started)]
    for repeat in range(args.repeats):
        stages, profile = {}, cProfile.Profile()
        undo = install_stages(stages, device_sync(backend))
        started = time.perf_counter()
        try:
            if repeat < 2:
                profile.enable()
            nd.pack(shape, args.count, backend=backend, mode="fast", seed=0, progress=False)
        finally:
            profile.disable()
            undo()
        seconds = time.perf_counter() - started
        runs.append(dict(run=f"run {repeat}", seconds=seconds, stages={k: v[0] for k, v in stages.items()},
                         profiled=repeat < 2))
        print(f"run {repeat}: {seconds:.2f} s (" + ", ".join(f"{k} {v[0]:.2f} s" for k, v in stages.items())
              + ")" + (", profiled" if repeat < 2 else ""), flush=True)
        if repeat < 2:
            text = io.StringIO()
            pstats.Stats(profile, stream=text).sort_stats("tottime").print_stats(18)
            runs[-1]["profile"] = text.getvalue()
            print(text.getvalue().split("\n", 6)[-1])
    if args.out:
        command = "python3 bench/first_run.py " + " ".join(sys.argv[1:])
        write_json(args.out, dict(machine=machine_info(), command=command, runs=runs))


if __name__ == "__main__":
    main()
