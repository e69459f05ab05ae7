"""Time to 10,000 and 100,000 spheres on each backend, compile time apart (issue 3).

Cases: the unit cube (3D) and a 6-D spherical shell (the unit ball minus the ball of radius 0.5;
a plain ball is filled by its first sphere). For each backend the shape is compiled by a tiny
warm-up packing first (reported as ``compile_s``); then one packing runs to the largest count,
capped by ``--budget`` seconds, and the time at which each count was reached is read from its
per-round statistics. Every packing is verified in float64.

    python bench/backends.py                                    # this machine, CPU backends
    python bench/backends.py --backends numba numba-cuda warp --threads 16 --out $OUT/backends.json

Writes JSON (``bench/results/backends_<host>.json`` unless ``--out``) after every run, so a
run cut short keeps what it measured.
"""

from __future__ import annotations

import argparse
import os
import socket
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import machine_info, write_json

import ndpack as nd


def cases():
    return {
        "cube3d": nd.Box(np.zeros(3), np.ones(3)),
        "shell6d": nd.Ball(np.zeros(6), 1.0) - nd.Ball(np.zeros(6), 0.5),
    }


def versions() -> dict:
    found = {}
    for module in ("numba", "numba_cuda", "warp"):
        try:
            found[module] = __import__(module).__version__
        except Exception:  # noqa: BLE001 - record what is missing, do not stop
            found[module] = None
    try:
        from numba import cuda

        if cuda.is_available():
            name = cuda.get_current_device().name
            found["gpu"] = name.decode() if isinstance(name, bytes) else str(name)
    except Exception:  # noqa: BLE001 - no GPU is a fact to record, not a failure
        pass
    return found


def time_to(packing, counts):
    """Seconds from the start of the packing (after compilation) to each count, or None."""
    totals, times = packing.stats.count, packing.stats.time
    out = {}
    for count in counts:
        reached = np.flatnonzero(totals >= count)
        out[str(count)] = float(times[reached[0]]) if len(reached) else None
    return out


def run(case, shape, backend, counts, batch, budget):
    started = time.perf_counter()
    nd.pack(shape, 3, backend=backend, batch=1)  # compiles every kernel for this shape
    compile_s = time.perf_counter() - started
    started = time.perf_counter()
    packing = nd.pack(shape, max(counts), backend=backend, batch=batch, mode="faithful", time_budget=budget)
    wall = time.perf_counter() - started
    report = packing.verify()
    return {
        "case": case, "backend": backend, "batch": batch, "compile_s": compile_s, "wall_s": wall,
        "spheres": len(packing.radii), "fill": packing.fill, "valid": bool(report.ok),
        "stop_reason": packing.stop_reason, "time_to": time_to(packing, counts),
        "fill_at": {str(c): float(packing.stats.fill[np.flatnonzero(packing.stats.count >= c)[0]])
                    for c in counts if (packing.stats.count >= c).any()},
    }


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--backends", nargs="+", default=["numpy", "numba"])
    parser.add_argument("--cases", nargs="+", default=list(cases()))
    parser.add_argument("--counts", nargs="+", type=int, default=[10_000, 100_000])
    parser.add_argument("--batch", nargs="+", type=int, default=[1], help="batch sizes to run")
    parser.add_argument("--budget", type=float, default=60.0, help="seconds per packing at most")
    parser.add_argument("--threads", type=int, default=None, help="numba threads")
    parser.add_argument("--out", type=Path, default=None)
    args = parser.parse_args()
    if args.threads:
        import numba

        numba.set_num_threads(args.threads)
    out = args.out or Path(__file__).parent / "results" / f"backends_{socket.gethostname()}.json"
    result = {"machine": machine_info(), "versions": versions(), "args": vars(args) | {"out": str(out)},
              "threads": int(__import__("numba").get_num_threads()), "runs": []}
    for case in args.cases:
        shape = cases()[case]
        for backend in args.backends:
            for batch in args.batch:
                try:
                    entry = run(case, shape, backend, args.counts, batch, args.budget)
                except Exception as error:  # noqa: BLE001 - one failing backend must not lose the rest
                    entry = {"case": case, "backend": backend, "batch": batch,
                             "error": f"{type(error).__name__}: {error}"}
                result["runs"].append(entry)
                write_json(out, result)
                print(_line(entry), flush=True)
    print(f"wrote {out}")


def _line(entry):
    if "error" in entry:
        return f"{entry['case']:8s} {entry['backend']:11s} batch {entry['batch']:4d}  ERROR {entry['error'][:200]}"
    times = "  ".join(f"t({k})={'-' if v is None else f'{v:.2f}s'}" for k, v in entry["time_to"].items())
    return (f"{entry['case']:8s} {entry['backend']:11s} batch {entry['batch']:4d}  compile {entry['compile_s']:.1f}s  "
            f"{entry['spheres']:7d} spheres in {entry['wall_s']:.1f}s  {times}  fill {entry['fill']:.4f}  "
            f"valid {entry['valid']}  ({entry['stop_reason']})")


if __name__ == "__main__":
    os.environ.setdefault("NDPACK_BACKEND", "numpy")  # only for the warm-up's fallback; runs name theirs
    main()
