"""Why a process's first packing is slower than its next: cProfile of two packings in a row.

    python bench/first_packing.py --backend numba-cuda --mesh armadillo.obj --count 100000 [--warmup 2000]

After a warm-up packing (``--warmup`` spheres, fast mode: compiles the kernels), packs the same
shape twice, each under cProfile, and prints both times and the functions whose own time differs
most between the first and the second (a one-off cost shows there: loading kernels, first
allocations, lazy compiles). On numba-cuda it also names the kernels compiled for new argument
types during the first packing, with their signatures.
"""

from __future__ import annotations

import argparse
import cProfile
import pstats
import time

import numpy as np

import ndpack as nd


def signatures(backend) -> dict:
    """numba-cuda: kernel name -> the argument types it is compiled for, over the backend's namespaces."""
    from ndpack.kernels.compile import CudaKernel

    found = {}
    for _, namespace in getattr(backend, "_namespaces", {}).values():
        for name, value in namespace.items():
            if isinstance(value, CudaKernel):
                found.setdefault(name, set()).update(str(key) for key in value.kernel.overloads)
    return found


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--backend", default="numba")
    parser.add_argument("--mesh", default=None, help="a mesh file; default the unit cube")
    parser.add_argument("--count", type=int, default=100_000)
    parser.add_argument("--warmup", type=int, default=2000)
    parser.add_argument("--top", type=int, default=20)
    args = parser.parse_args()
    shape = nd.TriangleMesh.load(args.mesh) if args.mesh else nd.Box(np.zeros(3), np.ones(3))
    backend = nd.backends.get_backend(args.backend)
    nd.pack(shape, args.warmup, mode="fast", backend=backend)
    stats, compiled = [], [signatures(backend)]
    for attempt in ("first", "second"):
        profile = cProfile.Profile()
        started = time.perf_counter()
        profile.enable()
        packing = nd.pack(shape, args.count, mode="fast", backend=backend)
        profile.disable()
        print(f"{attempt}: {time.perf_counter() - started:.2f} s, {len(packing.stats.count)} rounds", flush=True)
        stats.append({key: value[2] for key, value in pstats.Stats(profile).stats.items()})  # own time
        compiled.append(signatures(backend))
        for name, types in sorted(compiled[-1].items()):
            for new in sorted(types - compiled[-2].get(name, set())):
                print(f"  compiled during the {attempt}: {name}{new}")
    first, second = stats
    gaps = sorted(((first.get(key, 0.0) - second.get(key, 0.0), key) for key in set(first) | set(second)), reverse=True)
    print("own time, first - second (s), first, second, function:")
    for gap, (path, line, name) in gaps[: args.top]:
        print(f"  {gap:7.3f} {first.get((path, line, name), 0.0):7.3f} {second.get((path, line, name), 0.0):7.3f}  "
              f"{path.split('/')[-1]}:{line}({name})")


if __name__ == "__main__":
    main()
