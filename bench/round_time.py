"""Fast-mode packing time of one shape, per backend and per version of the code, in one run.

    python bench/round_time.py --mesh armadillo.obj --count 100000 --backends warp numba-cuda numba \
        --versions before=/path/to/old/checkout now=. --repeats 2 --out rounds.json

Each (version, backend) runs in its own process with that version's ``ndpack`` first on the path
(two versions cannot share a process), compiles first (a packing of a fifth of ``--count``, at least
2,000 spheres, not timed: enough that cells split, so that numba-cuda, which compiles each kernel
at its first launch, compiles those too), then packs
``--repeats`` times. Versions alternate per backend so that a drifting machine favours neither.
Every packing is verified in float64; the table gives the median time, rounds, fill and the
ratio of each version's median to the first version's.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys

#: What a child process runs: pack, time, verify; one JSON line per repeat.
CHILD = r"""
import json, sys, time
import numpy as np
import ndpack as nd
mesh, count, backend, repeats = sys.argv[1], int(sys.argv[2]), sys.argv[3], int(sys.argv[4])
shape = nd.TriangleMesh.load(mesh) if mesh != "cube" else nd.Box(np.zeros(3), np.ones(3))
nd.pack(shape, max(2000, count // 5), mode="fast", backend=backend)
for repeat in range(repeats):
    started = time.perf_counter()
    packing = nd.pack(shape, count, mode="fast", backend=backend)
    seconds = time.perf_counter() - started
    report = packing.verify()
    print(json.dumps(dict(seconds=seconds, rounds=len(packing.stats.count), spheres=len(packing),
                          fill=packing.fill, valid=bool(report.ok), where=nd.__file__)), flush=True)
"""


def run(version_path, mesh, count, backend, repeats):
    environment = dict(os.environ)
    environment["PYTHONPATH"] = os.pathsep.join([os.path.abspath(version_path), environment.get("PYTHONPATH", "")])
    # Run from the version's folder: ``python -c`` puts the working folder first on the path.
    mesh = mesh if mesh == "cube" else os.path.abspath(mesh)
    done = subprocess.run([sys.executable, "-c", CHILD, mesh, str(count), backend, str(repeats)],
                          capture_output=True, text=True, env=environment, cwd=os.path.abspath(version_path))
    rows = [json.loads(line) for line in done.stdout.splitlines() if line.startswith("{")]
    if done.returncode or not rows:
        print(done.stderr[-2000:], file=sys.stderr)
    return rows


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--mesh", default="cube", help="a mesh file, or 'cube' for the unit cube")
    parser.add_argument("--count", type=int, default=100_000)
    parser.add_argument("--backends", nargs="+", default=["numba"])
    parser.add_argument("--versions", nargs="+", default=["now=."], help="NAME=PATH of a checkout, first the baseline")
    parser.add_argument("--repeats", type=int, default=2)
    parser.add_argument("--out", default=None)
    args = parser.parse_args()
    versions = [item.split("=", 1) for item in args.versions]
    results = []
    for position, backend in enumerate(args.backends):
        order = versions if position % 2 == 0 else versions[::-1]
        for name, path in order:
            for row in run(path, args.mesh, args.count, backend, args.repeats):
                results.append(dict(row, version=name, backend=backend))
                print(f"{backend:11s} {name:8s} {row['seconds']:7.2f} s  {row['rounds']:4d} rounds  "
                      f"fill {row['fill']:.5f}  valid {row['valid']}", flush=True)
    print(f"\n{'backend':11s} {'version':8s} {'median s':>9s} {'ratio':>6s} {'rounds':>6s} {'fill':>8s}")
    for backend in args.backends:
        baseline = None
        for name, _ in versions:
            rows = [r for r in results if r["backend"] == backend and r["version"] == name]
            if not rows:
                print(f"{backend:11s} {name:8s} failed")
                continue
            median = statistics.median(r["seconds"] for r in rows)
            baseline = baseline or median
            print(f"{backend:11s} {name:8s} {median:9.2f} {median / baseline:6.2f} {rows[0]['rounds']:6d} "
                  f"{rows[0]['fill']:8.5f}")
    if args.out:
        with open(args.out, "w") as file:
            json.dump(dict(mesh=args.mesh, count=args.count, results=results), file, indent=1)


if __name__ == "__main__":
    main()
