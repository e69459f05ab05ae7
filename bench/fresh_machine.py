"""A fresh machine's first packing of a mesh: every cache empty, each part timed (issue 48).

    python3 bench/fresh_machine.py --mesh armadillo.obj --backends numba-cuda warp --out fresh.json
    PYTHONPATH=old_checkout python3 bench/fresh_machine.py ...   (another version's code)

What a user waits for the first time, on a machine that has compiled nothing: each backend runs in
a child process whose caches are all new and empty (ndpack's and Numba's, Warp's kernel cache and
the CUDA driver's), which times ``import ndpack``, loading the mesh (its tree, and its queries'
compile for the sign check), the first ``nd.pack`` (``--count`` spheres, fast mode: the kernels'
compile, the final check's compile, the packing) and a second one in the same process (what is not
compile), and reads back the compile times ndpack recorded, by title (a compile helper's,
:mod:`ndpack.compile_ahead`, among them: what the helper took, not what the packing waited), and
the compilations made in the child itself (``compiled_here``: the generated modules' kernels that
no helper compiled). ``whole_s`` is import, load and first packing: the time from the command to
the spheres.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))


def child(mesh: str, backend: str, count: int) -> None:
    started = time.perf_counter()
    import ndpack as nd
    from ndpack.kernels.compile import cache_root

    imported = time.perf_counter() - started
    started = time.perf_counter()
    shape = nd.TriangleMesh.load(mesh)
    loaded = time.perf_counter() - started
    runs = []
    for _ in range(2):
        started = time.perf_counter()
        packing = nd.pack(shape, count, backend=backend, mode="fast", seed=0, progress=False)
        runs.append(time.perf_counter() - started)
    from ndpack.kernels.compile import COMPILES

    times_file = cache_root() / "compile-times.json"
    compile_times = json.loads(times_file.read_text()) if times_file.exists() else {}
    print(json.dumps({"backend": backend, "import_s": round(imported, 2), "load_s": round(loaded, 2),
                      "first_packing_s": round(runs[0], 2), "next_packing_s": round(runs[1], 2),
                      "whole_s": round(imported + loaded + runs[0], 2), "spheres": len(packing.radii),
                      "compile_times": compile_times, "compiled_here": dict(COMPILES)}))


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--mesh", required=True)
    parser.add_argument("--backends", nargs="+", default=["numba"])
    parser.add_argument("--count", type=int, default=3, help="spheres of each packing")
    parser.add_argument("--out", type=Path)
    parser.add_argument("--child", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.child:
        return child(args.mesh, args.child, args.count)
    from _common import machine_info, write_json

    rows = []
    for backend in args.backends:
        with tempfile.TemporaryDirectory() as folder:
            env = dict(os.environ, NDPACK_CACHE=folder, NUMBA_CACHE_DIR=os.path.join(folder, "numba-functions"),
                       WARP_CACHE_PATH=os.path.join(folder, "warp"), CUDA_CACHE_DISABLE="1")
            done = subprocess.run([sys.executable, __file__, "--mesh", args.mesh, "--count", str(args.count),
                                   "--child", backend], env=env, stdout=subprocess.PIPE, text=True, check=True)
        row = json.loads(done.stdout.strip().splitlines()[-1])
        rows.append(row)
        parts = ", ".join(f"{title} {seconds:.1f} s" for title, seconds in row["compile_times"].items()
                          if ":" in title)
        print(f"{backend}: whole {row['whole_s']:.1f} s (import {row['import_s']:.1f}, load {row['load_s']:.1f}, "
              f"first packing {row['first_packing_s']:.1f}, the next {row['next_packing_s']:.2f}); compiles: {parts}",
              flush=True)
    if args.out:
        write_json(args.out, {"machine": machine_info(), "command": " ".join(["python3 bench/fresh_machine.py",
                                                                             *(argv or sys.argv[1:])]),
                              "mesh": Path(args.mesh).name, "count": args.count, "rows": rows})
    return None


if __name__ == "__main__":
    main()
