"""A GPU backend's compile options against the first compile's time and the packing's (issue 48).

    python3 bench/compile_options.py --mesh armadillo.obj --variants ndpack O3 O1 unroll-4 \\
        --out compile_options_h100.json
    python3 bench/compile_options.py --backend numba-cuda --mesh armadillo.obj --variants ndpack cuda-noopt

Each variant runs in a fresh process with an empty cache (``NDPACK_CACHE`` and Warp's kernel cache
in a new folder, and the CUDA driver's cache of compiled PTX off: ``CUDA_CACHE_DISABLE``; where
Warp hands the driver PTX, the driver's own compile of it is most of the time, and its cache
outlives a process), so its first packing of the mesh compiles everything a fresh machine compiles:
the time of that first packing (3 spheres), the longest compile of each kind as ndpack records it
(``compile-times.json``: the notices' estimates come from there), and then ``--count`` spheres
``--repeats`` times (median; fast mode, seed 0) with the same kernels. Variants are set before the
kernels are made: ``ndpack`` changes nothing, ``O<n>`` the CUDA optimisation level ndpack's modules
ask for (``kernels.compile.WARP_OPTIMIZATION``; Warp's default is 3), ``unroll-<n>`` Warp's most
unrolled loop iterations (``wp.config.max_unroll``, 16 by default). (The results of issue 48 were
measured before ndpack set a level: their ``default`` is Warp's, 3, and ``O2`` was set through
Warp's global configuration.) For numba-cuda (``--backend numba-cuda``), ``cuda-noopt`` compiles its kernels
without NVVM's optimisation (``numba_cuda_backend.CUDA_OPT``).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from _common import last_json, machine_info, write_json


def configure(variant: str) -> None:
    from ndpack.kernels import compile as kernel_compile

    if variant == "cuda-noopt":
        from ndpack.backends import numba_cuda_backend

        numba_cuda_backend.CUDA_OPT = False
        return
    import warp as wp

    if variant.startswith("O"):
        kernel_compile.WARP_OPTIMIZATION = int(variant[1:])
    elif variant.startswith("unroll-"):
        wp.config.max_unroll = int(variant.split("-")[1])
    elif variant != "ndpack":
        raise SystemExit(f"unknown variant {variant!r}")


def child(args) -> None:
    configure(args.child)
    import ndpack as nd
    from ndpack.kernels.compile import cache_root

    shape = nd.TriangleMesh.load(args.mesh)
    started = time.perf_counter()
    nd.pack(shape, 3, backend=args.backend, mode="fast", progress=False)
    first = time.perf_counter() - started
    times, fill = [], None
    for _ in range(args.repeats):
        started = time.perf_counter()
        packing = nd.pack(shape, args.count, backend=args.backend, mode="fast", seed=0, progress=False)
        times.append(time.perf_counter() - started)
        fill = float(packing.fill)
    compiles = json.loads((cache_root() / "compile-times.json").read_text())
    row = dict(backend=args.backend, variant=args.child, first_packing_s=first, compiles=compiles, seconds=times,
               median_s=statistics.median(times), fill=fill)
    if args.backend == "warp":
        import warp as wp

        row.update(cuda_output=str(wp.config.cuda_output), ptx_target_arch=str(wp.config.ptx_target_arch))
    print(json.dumps(row))


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--mesh", required=True)
    parser.add_argument("--backend", default="warp", choices=["warp", "numba-cuda"])
    parser.add_argument("--variants", nargs="+", default=["ndpack", "O3"])
    parser.add_argument("--count", type=int, default=100_000)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--child", help=argparse.SUPPRESS)
    parser.add_argument("--out", type=Path)
    args = parser.parse_args()
    if args.child:
        return child(args)
    rows = []
    for variant in args.variants:
        with tempfile.TemporaryDirectory(prefix="ndpack-cold-") as cache:
            env = dict(os.environ, NDPACK_CACHE=cache, WARP_CACHE_PATH=str(Path(cache) / "warp"),
                       CUDA_CACHE_DISABLE="1")
            done = subprocess.run([sys.executable, __file__, "--child", variant, "--mesh", args.mesh, "--count",
                                   str(args.count), "--repeats", str(args.repeats), "--backend", args.backend],
                                  env=env, capture_output=True, text=True)
            if done.returncode:
                print(done.stderr[-3000:], file=sys.stderr)
                continue
            row = last_json(done)
            rows.append(row)
            print(f"{variant:10s} first packing {row['first_packing_s']:6.1f} s (compiles: "
                  + ", ".join(f"{kind} {seconds:.0f} s" for kind, seconds in row["compiles"].items())
                  + f"); {args.count:,} spheres {row['median_s']:.2f} s, fill {row['fill']:.5f}", flush=True)
    if args.out:
        write_json(args.out, dict(machine=machine_info(), command="python3 bench/compile_options.py " +
                                  " ".join(sys.argv[1:]), rows=rows))


if __name__ == "__main__":
    main()
