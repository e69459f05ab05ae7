"""numba-cuda's launches replayed (ndpack.backends.numba_cuda_launch) against its dispatcher's: the
host's time a launch, and which kernels of a packing replay.

    python3 bench/launch_replay.py [--mesh armadillo.obj] [--count 20000] [--launches 2000] [--out RESULT.json]

For the GPU machine. Packs with numba-cuda, then lists the kernels its launches recorded (and those
left to the dispatcher), then launches one store kernel (``set_floats``, 3 arguments) and the move
kernel's arguments' worth of a wide one many times each way, the device synchronised before and
after: microseconds a launch, the host's cost, since the device's work is tiny.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import machine_info, write_json

import numpy as np

import ndpack as nd


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--mesh", default=None)
    parser.add_argument("--count", type=int, default=20_000)
    parser.add_argument("--launches", type=int, default=2000)
    parser.add_argument("--out", default=None)
    args = parser.parse_args(argv)
    from numba import cuda

    shape = nd.TriangleMesh.load(args.mesh) if args.mesh else nd.Box([0, 0, 0], [1, 1, 1])
    backend = nd.backends.get_backend("numba-cuda")
    nd.pack(shape, args.count, mode="fast", backend=backend, progress=False)
    replay = backend._replay
    recorded = {} if replay is None else {getattr(getattr(d, "py_func", None), "__name__", repr(d)): r is not None
                                          for d, r in replay._recorded.items()}
    print(f"replayed kernels: {sorted(k for k, v in recorded.items() if v)}")
    print(f"left to the dispatcher: {sorted(k for k, v in recorded.items() if not v)}")
    namespace = backend._kernels(shape)[0]
    n = 1024
    ids = cuda.to_device(np.arange(n, dtype=np.int64))
    values = cuda.to_device(np.ones(n))
    out = cuda.to_device(np.zeros(n))
    timings = {}
    for way in ("dispatcher", "replay"):
        saved = backend._replay
        backend._replay = None if way == "dispatcher" else (saved or None)
        try:
            for _ in range(10):
                backend._launch(namespace["set_floats"], n, ids, values, out)
            cuda.synchronize()
            started = time.perf_counter()
            for _ in range(args.launches):
                backend._launch(namespace["set_floats"], n, ids, values, out)
            host = time.perf_counter() - started
            cuda.synchronize()
            timings[way] = 1e6 * host / args.launches
        finally:
            backend._replay = saved
        print(f"set_floats through the {way}: {timings[way]:.1f} us a launch (host)")
    if args.out:
        write_json(Path(args.out), dict(machine=machine_info(), recorded=recorded, us_per_launch=timings))


if __name__ == "__main__":
    main()
