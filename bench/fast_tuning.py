"""The fast mode's tuning constants, A/B over seeds: time, fill, rounds and prototype steps.

    python bench/fast_tuning.py --mesh armadillo.obj --count 100000 --seeds 0 1 2 \\
        --variants before:0/0/64/0 cut:2e-5/1e-4/64/0 now:2e-5/1e-4/1024/0.0625 --out tuning.json

A variant is ``NAME:POLISH_FLOOR/MOVE_FLOOR/SMALL_ROUND/SMALL_ROUND_SHARE[/POLISH_FROM]``: where the
fast mode cuts the polish and move schedules (``FAST_POLISH_EPS_END``, ``FAST_EPS_END``; 0 keeps
them whole; a polish floor above 0.05 leaves no polish step), how many late finds join the next
round (at most ``SMALL_ROUND``, at most that share of the spheres so far, at least
``SMALL_ROUND_FIRST``; a share of 1e9 makes ``SMALL_ROUND`` flat), and optionally the polish's
first ``eps`` (its schedule's steps above it dropped). ``--fill-at`` adds the fill after the first
spheres, in insertion order. Variants alternate within each seed, one process,
after a 3-sphere warm-up that compiles. Fill and rounds are exact; times on a shared machine are
not (compare means over seeds within one run). Prototype steps count each moved prototype's
schedule length (restarts and polish apart), the work a CPU does.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

import ndpack as nd
from ndpack.drivers.greedy import protosphere, rounds
from ndpack.backends import prototypes

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import machine_info, write_json


def count_steps(counter):
    """Wrap both stores' ``move`` to add each call's prototypes times steps to ``counter``."""
    for store in (prototypes.HostPrototypes, prototypes.DevicePrototypes):
        original = store.move

        def move(self, ids, centers, radii, steps, starts=None, polish=False, _original=original):
            counter["polish" if polish else "move"] += len(ids) * len(steps)
            return _original(self, ids, centers, radii, steps, starts, polish)
        store.move = move


SCHEDULES = protosphere.schedules


def polish_from(start):
    """:func:`ndpack.drivers.greedy.protosphere.schedules` with the polish's steps above ``start`` dropped."""
    def schedules(mode, iterations):
        steps, polish = SCHEDULES(mode, iterations)
        return steps, polish[polish <= start]
    return schedules


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--mesh", default=None, help="a mesh file; default the unit cube")
    parser.add_argument("--count", type=int, default=100_000)
    parser.add_argument("--seeds", nargs="+", type=int, default=[0, 1])
    parser.add_argument("--variants", nargs="+", default=["before:0/0/64/0", "now:2e-5/1e-4/1024/0.0625"])
    parser.add_argument("--backend", default="numba")
    parser.add_argument("--fill-at", nargs="*", type=int, default=[])
    parser.add_argument("--out", default=None)
    args = parser.parse_args()
    shape = nd.TriangleMesh.load(args.mesh) if args.mesh else nd.Box(np.zeros(3), np.ones(3))
    variants = {}
    for item in args.variants:
        name, values = item.split(":")
        polish, move, small, share, *start = values.split("/")
        variants[name] = (float(polish), float(move), int(small), float(share), float(start[0]) if start else np.inf)
    counter = {"move": 0, "polish": 0}
    count_steps(counter)
    nd.pack(shape, 3, backend=args.backend, mode="fast")
    runs = []
    for seed in args.seeds:
        for name, (polish, move, small, share, start) in variants.items():
            protosphere.FAST_POLISH_EPS_END, protosphere.FAST_EPS_END = polish, move
            rounds.SMALL_ROUND, rounds.SMALL_ROUND_SHARE = small, share
            protosphere.schedules = polish_from(start)
            counter.update(move=0, polish=0)
            started = time.perf_counter()
            packing = nd.pack(shape, args.count, backend=args.backend, mode="fast", seed=seed, progress=False)
            run = dict(variant=name, seed=seed, seconds=time.perf_counter() - started, fill=packing.fill,
                       rounds=len(packing.stats.time), move_steps=counter["move"], polish_steps=counter["polish"])
            volumes = np.cumsum(nd.ball_volume(packing.dim, packing.radii)) / packing.volume
            run.update({f"fill_at_{k}": float(volumes[k - 1]) for k in args.fill_at if k <= len(volumes)})
            runs.append(run)
            print(f"{name:10s} seed {seed}  {run['seconds']:6.2f} s  fill {run['fill']:.5f}  "
                  f"rounds {run['rounds']:3d}  "
                  f"move steps {run['move_steps'] / 1e6:5.1f}M  polish steps {run['polish_steps'] / 1e6:5.1f}M",
                  flush=True)
    print(f"\n{'variant':10s} {'mean s':>7s} {'fill':>8s} {'rounds':>6s} {'move M':>7s} {'polish M':>8s}")
    for name in variants:
        mine = [r for r in runs if r["variant"] == name]
        keys = ["seconds", "fill", "rounds", "move_steps", "polish_steps"] + [f"fill_at_{k}" for k in args.fill_at]
        mean = {key: float(np.mean([r[key] for r in mine if key in r])) for key in keys}
        print(f"{name:10s} {mean['seconds']:7.2f} {mean['fill']:8.5f} {mean['rounds']:6.1f} "
              f"{mean['move_steps'] / 1e6:7.1f} {mean['polish_steps'] / 1e6:8.1f}"
              + "".join(f"  fill at {k}: {mean[f'fill_at_{k}']:.5f}" for k in args.fill_at))
    if args.out:
        write_json(Path(args.out), dict(machine=machine_info(), args=vars(args), runs=runs))


if __name__ == "__main__":
    main()
