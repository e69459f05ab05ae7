"""What a new user waits for: whole `ndpack pack` processes, from a fresh kernel cache on.

Per backend, one new ``$NDPACK_CACHE`` (and Warp binary cache) is shared by a sequence of
processes, as a user meets them: the demo part first (a fresh install's first command), then a
new size of a part, a new CSG tree of built-ins, a first mesh and a second, new mesh; each is
run twice in a row, so the second run (warm: nothing left to compile or load for the first
time) is what the first costs against. Every process is ``python -m ndpack.cli pack SPEC -n N
--mode fast --backend B -q``, timed whole (Python's start, imports, loading the shape, compiling
or loading kernels, packing and verifying).

    python bench/compile_cache.py                                    # numba, the 2-core table
    python bench/compile_cache.py --backends warp:cuda:0 numba-cuda --scenario meshes \\
        --mesh ../shared/data/meshes/armadillo.obj --out results.json  # the GPU machine

Prints a table (first run, warm re-run, ratio) and writes JSON rows with each process's output.
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

ROOT = Path(__file__).resolve().parents[1]
MESHES = ROOT / "tests" / "data" / "meshes"

#: Shapes written as scripts for `ndpack pack part.py`: sizes and trees the cache has never seen.
PART = """import ndpack as nd
side = {side}
shape = nd.Box([0, 0, 0], [side] * 3) - nd.Ball([side] * 3, 0.6 * side)
"""
TREE = """import ndpack as nd
shape = (nd.Box([0, 0, 0], [1, 1, 1]) | nd.Capsule([0, 0, 0], [1.5, 1.5, 0], 0.3)) \\
    - nd.Cylinder([0.5, 0.5, -1], [0.5, 0.5, 2], 0.2)
"""


def scenario(name: str, folder: Path, mesh: str | None) -> list[tuple[str, str]]:
    """(label, shape spec) in the order a user meets them."""
    for label, text in (("part_1", PART.format(side=1.0)), ("part_2.7", PART.format(side=2.7)),
                        ("part_0.001", PART.format(side=0.001)), ("tree", TREE)):
        (folder / f"{label}.py").write_text(text)
    first_mesh = mesh or str(MESHES / "cow.ply")
    meshes = [("first mesh", first_mesh), ("new mesh", str(MESHES / "fandisk.ply"))]
    if name == "meshes":
        return meshes
    return [("demo", "demo"), ("part", str(folder / "part_1.py")), ("new size 2.7", str(folder / "part_2.7.py")),
            ("new size 0.001", str(folder / "part_0.001.py")), ("new tree", str(folder / "tree.py")), *meshes]


def pack(spec: str, backend: str, count: int, cache: str) -> dict:
    """One whole `ndpack pack` process: wall seconds, its report, and whether it said it compiled."""
    name, _, device = backend.partition(":")
    command = [sys.executable, "-m", "ndpack.cli", "pack", spec, "-n", str(count), "--mode", "fast",
               "--backend", name, "-q"] + (["--device", device] if device else [])
    env = {**os.environ, "NDPACK_CACHE": cache, "WARP_CACHE_PATH": os.path.join(cache, "warp-binaries")}
    start = time.perf_counter()
    result = subprocess.run(command, capture_output=True, text=True, env=env)
    wall = time.perf_counter() - start
    compiled = [line for line in result.stderr.splitlines() if line.startswith("ndpack: compiling")]
    return {"wall": wall, "status": result.returncode, "compiled": compiled,
            "valid": "verified: valid" in result.stdout, "stdout": result.stdout,
            "stderr": result.stderr[-2000:] if result.returncode else ""}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--backends", nargs="+", default=["numba"], help="names, with :device (warp:cuda:0)")
    parser.add_argument("--scenario", choices=("user", "meshes"), default="user",
                        help="user: demo, sizes, a tree and two meshes; meshes: the two meshes only")
    parser.add_argument("--mesh", help="the first mesh (default: tests/data/meshes/cow.ply)")
    parser.add_argument("-n", type=int, default=200, help="spheres per packing (default 200)")
    parser.add_argument("--out", help="JSON file for the rows")
    parser.add_argument("--cache", help="a new folder for the caches, kept afterwards (default: a temporary one "
                        "per backend, removed)")
    args = parser.parse_args(argv)

    rows = []
    for number, backend in enumerate(args.backends):
        with tempfile.TemporaryDirectory(prefix="ndpack-cache-") as temporary:
            # Each backend from a fresh cache; with --cache, one folder per backend inside it.
            cache = os.path.join(args.cache, str(number)) if args.cache else temporary
            if os.path.exists(cache) and os.listdir(cache):
                parser.error(f"{cache} is not empty: the first processes would not start from a fresh cache")
            folder = Path(cache) / "shapes"
            folder.mkdir(parents=True)
            print(f"\n{backend}: fresh cache, {args.n} spheres, fast mode, whole processes")
            print(f"  {'shape':16s} {'first':>8s} {'warm':>8s} {'ratio':>6s}  compiled in the first")
            for label, spec in scenario(args.scenario, folder, args.mesh):
                first, warm = pack(spec, backend, args.n, cache), pack(spec, backend, args.n, cache)
                for run in (first, warm):
                    if run["status"] != 0:
                        print(f"{label} failed:\n{run['stderr']}", file=sys.stderr)
                ratio = first["wall"] / warm["wall"]
                said = "; ".join(line.split(" (")[0].removeprefix("ndpack: compiling ") for line in first["compiled"])
                print(f"  {label:16s} {first['wall']:7.1f}s {warm['wall']:7.1f}s {ratio:6.2f}  {said or '-'}",
                      flush=True)
                rows.append({"backend": backend, "shape": label, "spec": Path(spec).name, "first": first,
                             "warm": warm, "ratio": ratio})
    if args.out:
        with open(args.out, "w") as handle:
            json.dump({"n": args.n, "scenario": args.scenario, "rows": rows}, handle, indent=1)
    ok = rows and all(row[run]["valid"] for row in rows for run in ("first", "warm"))
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
