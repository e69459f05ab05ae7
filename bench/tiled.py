"""One domain in tiles against one run: ``nd.pack_tiled`` on k workers, ``nd.pack`` alone.

    python bench/tiled.py --count 50000 --workers 1 2 --out bench/results/tiled_2core.json
    python bench/tiled.py --count 1000000 --workers 4 16 --backend numba --out tiled_cpu.json
    python bench/tiled.py --count 1000000 --workers 2 4 --backend warp --device cuda:0 --out tiled_gpu.json

Packs the unit cube (``--periodic``: the periodic unit box) to ``--count`` spheres, once alone
(``nd.pack`` on the same backend and device; numba on every core; left out with ``--no-alone``)
and once per ``--workers`` with ``nd.pack_tiled`` (its default tiles: 4 slabs per worker; on a
GPU the workers are processes sharing it). Each packing is checked again in float64 as a whole
(``nd.verify``, timed apart). Per run it records the seconds, the fill and its ratio to the
run alone at the same count, and where a tiled run's time went: the global phase, the phases
of the tiles (wall), the work inside the tiles (summed over workers), how busy the workers were
in the phases (``busy_share``: the rest is waiting at the phases' ends for the slowest tile),
the share of the spheres made in the halos (``halo_share``), and the host's own time (finding
each tile's obstacles, merging, the final check). Peak memory of this process is recorded too.
The JSON is written after each run; a run stopped by SIGINT (``timeout -s INT``) keeps what it
packed (``stop_reason == "interrupted"``) and is recorded as such.
"""

from __future__ import annotations

import argparse
import resource
import time
from pathlib import Path

import numpy as np

import ndpack as nd

from _common import machine_info, write_json


def _row(label, packing, seconds, verify_seconds, valid, alone=None):
    row = dict(run=label, spheres=len(packing), seconds=round(seconds, 3), fill=packing.fill,
               stop_reason=packing.stop_reason, verify_seconds=round(verify_seconds, 3), valid=bool(valid),
               spheres_per_second=round(len(packing) / seconds, 1))
    if alone is not None:
        row["fill_ratio"] = packing.fill / alone.fill
    tiled = packing.params.get("tiled")
    if tiled:
        row.update({key: tiled[key] for key in ("tiles", "workers", "halo", "global_spheres", "global_seconds",
                                                "phase_seconds", "tile_seconds", "busy_share", "halo_share")})
        row["bands"] = len(tiled["bands"])
        row["host_seconds"] = round(tiled["seconds"] - tiled["global_seconds"] - tiled["phase_seconds"], 3)
    return row


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--count", type=int, default=50_000)
    parser.add_argument("--workers", type=int, nargs="+", default=[1, 2])
    parser.add_argument("--backend", default="numba")
    parser.add_argument("--device", default=None)
    parser.add_argument("--periodic", action="store_true", help="the periodic unit box instead of the cube")
    parser.add_argument("--no-alone", action="store_true", help="skip the run alone (for counts it cannot reach)")
    parser.add_argument("--out", type=Path, default=Path("bench/results/tiled_2core.json"))
    args = parser.parse_args()
    shape = nd.Box(np.zeros(3), np.ones(3))
    if args.periodic:
        shape = nd.Periodic(shape)
    options = dict(backend=args.backend, **({"device": args.device} if args.device else {}))
    nd.pack(shape, n=2000, progress=False, **options)  # compile once, into the on-disk cache
    rows, alone = [], None

    def save():  # after each run: a step cut short by its time limit keeps the runs that finished
        peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024  # MiB (Linux reports KiB)
        write_json(args.out, dict(machine=machine_info(), count=args.count, backend=args.backend, device=args.device,
                                  periodic=args.periodic, peak_rss_mib=round(peak, 1), rows=rows))

    if not args.no_alone:
        started = time.perf_counter()
        alone = nd.pack(shape, n=args.count, seed=0, progress=False, **options)
        seconds = time.perf_counter() - started
        checked = time.perf_counter()
        valid = nd.verify(alone, shape).ok
        rows.append(_row("alone", alone, seconds, time.perf_counter() - checked, valid))
        print(f"alone: {len(alone):,} spheres in {seconds:.1f} s, fill {alone.fill:.4f}, valid {valid}", flush=True)
        save()
    for workers in args.workers:
        started = time.perf_counter()
        packing = nd.pack_tiled(shape, n=args.count, workers=workers, seed=0, progress=False, **options)
        seconds = time.perf_counter() - started
        checked = time.perf_counter()
        valid = nd.verify(packing, shape).ok
        row = _row(f"tiled, {workers} workers", packing, seconds, time.perf_counter() - checked, valid, alone)
        rows.append(row)
        print(f"{row['run']}: {len(packing):,} spheres in {seconds:.1f} s, fill {packing.fill:.4f}"
              + (f" ({row['fill_ratio']:.4f} of alone)" if alone is not None else "")
              + f", valid {valid}; global {row.get('global_spheres', 0):,} spheres {row.get('global_seconds', 0)} s, "
              f"phases {row.get('phase_seconds', 0)} s, busy {row.get('busy_share', 0):.2f}, "
              f"halo share {row.get('halo_share', 0):.2f}, host {row.get('host_seconds', 0)} s, "
              f"stopped by {packing.stop_reason}", flush=True)
        save()


if __name__ == "__main__":
    main()
