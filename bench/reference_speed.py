"""Speed of the NumPy reference backend: 1,000 circles in the unit square and 1,000 spheres in
the unit cube, median wall time of one run per seed (0, 1, 2), with the rounds and the fill.

Wall time is measured around ``nd.pack`` (it includes setting up the grid and the final float64
verification); ``stats.time[-1]`` (the time of the last round) is recorded beside it. A tiny
untimed packing first warms up imports and caches.

    python bench/reference_speed.py --out bench/results
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

import ndpack as nd

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import load_average, machine_info, write_json

ROOT = Path(__file__).resolve().parent.parent


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--n", type=int, default=1000, help="spheres per packing")
    ap.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    ap.add_argument("--out", type=Path, default=ROOT / "bench" / "results")
    args = ap.parse_args(argv)

    machine = machine_info()
    shapes = {
        "square (2D)": nd.Box([0.0, 0.0], [1.0, 1.0]),
        "cube (3D)": nd.Box([0.0, 0.0, 0.0], [1.0, 1.0, 1.0]),
    }
    for shape in shapes.values():  # warm-up, untimed
        nd.pack(shape, n=5, seed=0, backend="numpy", progress=False)

    cases = []
    for name, shape in shapes.items():
        runs = []
        for seed in args.seeds:
            t0 = time.perf_counter()
            p = nd.pack(shape, n=args.n, seed=seed, backend="numpy", mode="faithful", progress=False)
            wall = time.perf_counter() - t0
            runs.append({
                "seed": seed,
                "wall_s": wall,
                "last_round_s": float(p.stats.time[-1]),
                "spheres": len(p),
                "rounds": int(len(p.stats.count)),
                "fill": float(p.fill),
                "stop_reason": p.stop_reason,
                "verified": bool(p.verify().ok),
            })
            print(f"  {name} seed {seed}: {wall:.2f} s, {runs[-1]['rounds']} rounds, "
                  f"fill {p.fill:.5f}", flush=True)
        cases.append({
            "shape": name,
            "dim": int(p.centers.shape[1]),
            "n": args.n,
            "params": p.params,
            "median_wall_s": statistics.median(r["wall_s"] for r in runs),
            "min_wall_s": min(r["wall_s"] for r in runs),
            "max_wall_s": max(r["wall_s"] for r in runs),
            "median_rounds": statistics.median(r["rounds"] for r in runs),
            "median_fill": statistics.median(r["fill"] for r in runs),
            "runs": runs,
        })

    out = args.out / "reference_speed.json"
    write_json(out, {
        "benchmark": "reference_speed",
        "machine": machine,
        "parameters": {"n": args.n, "seeds": args.seeds, "backend": "numpy"},
        "cases": cases,
        "loadavg_at_end": load_average(),
    })

    print(f"\n{'shape':<12} {'N':>5} {'median s':>9} {'min-max s':>12} {'rounds':>7} {'fill':>8}")
    for c in cases:
        print(f"{c['shape']:<12} {c['n']:>5} {c['median_wall_s']:>9.2f} "
              f"{c['min_wall_s']:>5.2f}-{c['max_wall_s']:<5.2f} {c['median_rounds']:>7g} "
              f"{c['median_fill']:>8.5f}")
    print(f"\nwrote {out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
