"""What one prototype step costs on a device, and what it is made of.

    python bench/step_cost.py --backends warp numba-cuda --mesh armadillo.obj --count 100000

Packs the shape in the fast mode, keeping the largest polish launch made after half the
spheres, then launches the same prototypes again (``move_ids`` alone, synchronised, median of
``--repeats``) while changing one thing at a time:

- the number of steps (1, 15, 30 and the polish's 60): the slope is a step's cost on the
  launch's slowest lanes, the intercept the launch's fixed cost;
- no spheres (one far away stands in): the step's shape query alone (without ``--mesh``, the
  unit cube: an analytic shape, whose query is a few operations);
- the prototypes repeated 4 and 16 times in one launch: the same time means the launch is
  bound by latency (its slowest lane), not by the device's throughput;
- 1, 2, 4, 8 and 32 threads per prototype (the first moves it, the rest idle: its warp's other lanes
  wait for no divergent walk), for all the prototypes and for 1,500 of them (a round's choice
  polishes about as many); the other rows use the backend's own spread
  (:func:`ndpack.backends.prototypes.lane_spread`).

Each launch moves prototypes of a finished packing, so the packing is discarded.
"""

from __future__ import annotations

import argparse
import json
import statistics

import numpy as np

import ndpack as nd
from ndpack.drivers.greedy import protosphere
from ndpack.backends import prototypes
from ndpack.backends import get_backend
from profile_kernels import Recorder, install  # bench/, beside this script


def _capture(shape, backend, count):
    """Pack; return the run's state and the ids of its largest polish after count / 2 spheres."""
    seen = {}
    original = protosphere.RunState.polish

    def polish(self, ids):
        if self.count >= count // 2 and len(ids) > len(seen.get("ids", ())):
            seen["ids"], seen["state"] = np.array(ids), self
        return original(self, ids)

    protosphere.RunState.polish = polish
    try:
        nd.pack(shape, count, backend=backend, mode="fast")
    finally:
        protosphere.RunState.polish = original
    return seen["state"], seen["ids"]


def _snapshot(store):
    """A function that puts the device store's prototypes (points, clearances, polish flags,
    reach) back as they are now: every timed launch starts from the same state. (Before the
    seventh steps each launch started from the last one's result, and the launch without spheres
    moved every prototype away from them for the rows after it.)"""
    device, count = store.device, len(store)
    points, clearance, polished, reach = device.fetch((store.d_points, count), (store.d_clearance, count),
                                                      (store.d_polished, count), (store.d_reach, count))

    def restore():
        device.write(store.d_points, 0, points, "point")
        device.write(store.d_clearance, 0, clearance, "float")
        device.write(store.d_polished, 0, polished, "index")
        device.write(store.d_reach, 0, reach, "float")
        device.synchronize()
    return restore


def _timed_move(store, ids, centers, radii, steps, repeats):
    """Median seconds of the move_ids launch alone, timed as bench/profile_kernels.py times
    every launch (the neighbour table's launches apart), each from the same state."""
    times = []
    restore = _snapshot(store)
    for _ in range(repeats):
        recorder = Recorder()
        undo = install(recorder)
        try:
            store.move(ids, centers, radii, steps, polish=True)
        finally:
            undo()
            restore()
        times.append(recorder.kernels["move_ids[polish]"][1])
    return statistics.median(times)


def measure(shape, name, count, repeats):
    backend = get_backend(name)
    state, ids = _capture(shape, backend, count)
    store, (centers, radii) = state.prototypes, state.spheres
    polish = state.polish_steps
    rows = {}
    for steps in (1, 15, 30, len(polish)):
        rows[f"{steps} steps"] = _timed_move(store, ids, centers, radii, polish[:steps], repeats)
    far = np.full((1, state.dim), 1e6)
    rows[f"{len(polish)} steps, no spheres"] = _timed_move(store, ids, far, np.ones(1), polish, repeats)
    for times in (4, 16):
        rows[f"{len(polish)} steps, ids x{times}"] = _timed_move(store, np.tile(ids, times), centers, radii, polish,
                                                                repeats)
    few = np.sort(np.random.default_rng(0).choice(ids, min(1500, len(ids)), replace=False))
    policy, most = prototypes.lane_spread, store.spread
    prototypes.lane_spread = lambda count, most: most  # exactly the spread asked for
    try:
        for subset, label in ((ids, "all"), (few, f"{len(few)}")):
            for spread in (1, 2, 4, 8, 32):
                store.spread = spread
                rows[f"{len(polish)} steps, {label}, spread {spread}"] = _timed_move(
                    store, subset, centers, radii, polish, repeats)
    finally:
        prototypes.lane_spread, store.spread = policy, most
    print(f"== {name}: {len(ids)} prototypes, {len(radii)} spheres, median of {repeats}")
    for label, seconds in rows.items():
        print(f"   {label:28s} {1e3 * seconds:8.3f} ms")
    slope = (rows[f"{len(polish)} steps"] - rows["1 steps"]) / (len(polish) - 1)
    print(f"   a step on the slowest lanes  {1e6 * slope:8.1f} us")
    return dict(prototypes=len(ids), spheres=len(radii), milliseconds={k: 1e3 * v for k, v in rows.items()},
                step_microseconds=1e6 * slope)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--backends", nargs="+", default=["warp"])
    parser.add_argument("--mesh", default=None, help="a mesh file; default the unit cube")
    parser.add_argument("--count", type=int, default=100_000)
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--out", default=None, help="write the results as JSON here")
    args = parser.parse_args()
    shape = nd.TriangleMesh.load(args.mesh) if args.mesh else nd.Box(np.zeros(3), np.ones(3))
    results = {name: measure(shape, name, args.count, args.repeats) for name in args.backends}
    if args.out:
        with open(args.out, "w") as file:
            json.dump(results, file, indent=1)


if __name__ == "__main__":
    main()
