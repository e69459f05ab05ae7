"""Digests of 14 packings (7 cases on numpy and on numba), to compare machines and thread counts.

The same seed must give the same spheres on any x86-64 machine whatever its thread count
(docs/reliability.md). Run this on two machines, or here under settings that play another one,
and compare the JSON files: every digest must be equal.

    python bench/reproducible.py --out bench/results/reproducible_2core.json
    NUMBA_NUM_THREADS=1 NPY_DISABLE_CPU_FEATURES="X86_V3 X86_V4 AVX512_ICL AVX512_SPR" \\
        OPENBLAS_CORETYPE=Haswell python bench/reproducible.py --out other.json
"""

from __future__ import annotations

import argparse
import hashlib
import json
from pathlib import Path

import ndpack as nd
from ndpack.io.shape_sources import load_shape

COW = Path(__file__).resolve().parents[1] / "ndpack" / "samples" / "cow.ply"
#: (shape, count, options): 2-D to 5-D, faithful and fast, CSG, a mesh, a periodic box with a
#: radius range.
CASES = [
    ("box:dim=4", 500, {}),
    ("demo", 1000, {}),
    ("annulus:dim=5", 200, {}),
    ("annulus", 400, {}),
    ("box:dim=2", 300, {"periodic": True, "min_radius": 0.01, "max_radius": 0.2}),
    ("box:dim=3", 600, {"mode": "fast"}),
    ("cow", 400, {}),
]


def digests(backends) -> dict:
    """``{"backend:shape:count": "digest count fill"}`` for every case on each backend."""
    found = {}
    for backend in backends:
        for spec, count, options in CASES:
            options = dict(options)
            shape = nd.TriangleMesh.load(COW) if spec == "cow" else load_shape(spec)
            if options.pop("periodic", False):
                shape = nd.Periodic(shape)
            packing = nd.pack(shape, n=count, seed=0, backend=backend, progress=False, **options)
            digest = hashlib.sha256(packing.centers.tobytes() + packing.radii.tobytes()).hexdigest()[:12]
            found[f"{backend}:{spec}:{count}"] = f"{digest} {len(packing)} {packing.fill:.6f}"
    return found


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--backends", default="numpy,numba", help="comma-separated (default numpy,numba)")
    parser.add_argument("--out", help="write the digests here as JSON")
    args = parser.parse_args()
    found = digests(args.backends.split(","))
    text = json.dumps(found, indent=1)
    print(text)
    if args.out:
        Path(args.out).write_text(text + "\n")


if __name__ == "__main__":
    main()
