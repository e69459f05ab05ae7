"""Default threads against one, quiet and busy, before and after issue 47's serial small launches.

    python bench/threads.py --out bench/results/threads_2core.json [--load 2] [--repeats 3]

Each case packs in a fresh process (numba backend, seed 0, verified), with Numba's default
threads or ``NUMBA_NUM_THREADS=1``, and with launches sized to the work (``after``: the backend's
measured threshold) or every launch on Numba's threads (``before``: ``NDPACK_PARALLEL_FROM=0``,
the code before issue 47). With ``--load N``, N spinning processes run beside the whole sweep
(bench/_load.py). The variants run interleaved, ``--repeats`` rounds of all of them, and the table
gives each one's median seconds; every run of a case must give the same spheres (a hash of them).
``--launches`` times single converge launches instead, on one thread and on all, from a few
microseconds' work to a few hundred milliseconds': where the threads start to pay, beside the
overhead the backend measures (``NumbaBackend._probe``) and weighs against a launch's work.
``--versions`` also takes fixed thresholds (seconds of work on one thread), which the default
measures instead.
"""

from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

from _common import last_json, load_average, machine_info, run_with, write_json
from _load import busy

#: name -> (shape expression, count, mode); numpy is ``np`` and ndpack ``nd`` where they run.
CASES = {
    "cube minus ball, 1000, faithful": ("nd.Box([0, 0, 0], [1, 1, 1]) - nd.Ball([1, 1, 1], 0.6)", 1000, "faithful"),
    "4-ball two holes, 1000, faithful": ("nd.Ball(np.zeros(4), 1.0) - nd.Ball(np.full(4, 0.3), 0.4)"
                                         " - nd.Ball(np.full(4, -0.4), 0.3)", 1000, "faithful"),
    "unit cube, 2000, auto": ("nd.Box([0, 0, 0], [1, 1, 1])", 2000, "auto"),
    "quick start box:dim=4, 500, auto": ("nd.Box(np.zeros(4), np.ones(4))", 500, "auto"),
}

#: One packing, timed after a small one of the same shape (which loads the compiled kernels).
CHILD = """
import hashlib, json, sys, time
import numba
import numpy as np
import ndpack as nd
from ndpack.backends import numba_backend

shape = eval(sys.argv[1])
count, mode = int(sys.argv[2]), sys.argv[3]
nd.pack(shape, n=20, mode=mode, backend="numba", seed=1, progress=False)
numba_backend.trace = []
started = time.perf_counter()
packing = nd.pack(shape, n=count, mode=mode, backend="numba", seed=0, progress=False)
seconds = time.perf_counter() - started
launches = numba_backend.trace
print(json.dumps({
    "seconds": seconds, "fill": packing.fill, "count": len(packing), "valid": bool(packing.verify().ok),
    "spheres": hashlib.sha1(packing.centers.tobytes() + packing.radii.tobytes()).hexdigest()[:16],
    "threads": numba.get_num_threads(), "layer": numba.threading_layer(),
    "mode": packing.params.get("mode"),
    "launches": len(launches), "parallel_launches": sum(not launch[3] for launch in launches),
    "overheads": nd.backends.get_backend("numba")._overheads,
    "kernel_seconds": sum(launch[4] for launch in launches),
    "parallel_seconds": sum(launch[4] for launch in launches if not launch[3]),
}))
"""


def run_one(case: str, threads: str, version: str) -> dict:
    """One packing of ``case`` in a fresh process: ``before``, ``after``, or a fixed threshold
    (seconds of work on one thread, ``NDPACK_PARALLEL_FROM``)."""
    expression, count, mode = CASES[case]
    # NUMBA_NUM_THREADS, where set, is the default threads.
    env = {"NDPACK_PARALLEL_FROM": None if version == "after" else "0" if version == "before" else version}
    if threads == "1":
        env["NUMBA_NUM_THREADS"] = "1"
    row = last_json(run_with(Path(__file__).resolve().parents[1], ["-c", CHILD, expression, str(count), mode],
                             env=env, timeout=1800))
    row["load_average"] = load_average()
    return row


def launch_sweep(repeats: int) -> tuple[list[dict], list[float]]:
    """One converge launch of ``count`` prototypes (3-D, 50 neighbours each), on one thread and on
    all, median seconds of ``repeats`` each (interleaved), for growing counts and steps."""
    import numba
    import numpy as np

    import ndpack as nd
    from ndpack.backends.numba_backend import RATES, SHAPE_UNITS, NumbaBackend

    backend = NumbaBackend()
    shape = nd.Box([0, 0, 0], [1, 1, 1]) - nd.Ball([1, 1, 1], 0.6)
    namespace, params, h = backend._kernels(shape)
    entry, everyone = namespace["converge_all"], numba.get_num_threads()
    rng = np.random.default_rng(0)
    rows = []
    for count, steps in [(1, 0), (4, 0), (16, 0), (4, 10), (16, 10), (8, 50), (16, 50), (64, 50), (256, 50),
                         (1024, 50), (4096, 50)]:
        points = rng.random((count, 3))
        centers, radii = rng.random((50, 3)), np.full(50, 0.01)
        neighbours = np.tile(np.arange(50, dtype=np.int64), (count, 1))
        tries = 8 if steps else 0
        starts = rng.random((max(tries, 1), count, 3))
        args = (points, starts, tries, points - 0.05, points + 0.05, np.full(count, -np.inf), params, centers, radii,
                neighbours, np.full(steps, 0.1), h, np.empty_like(points), np.empty(count))
        entry(*args)
        times = {1: [], everyone: []}
        shares = []
        for _ in range(repeats):
            for threads in times:
                numba.set_num_threads(threads)
                cpu, started = time.process_time(), time.perf_counter()
                entry(*args)
                seconds = time.perf_counter() - started
                times[threads].append(seconds)
                if threads == everyone:
                    shares.append((time.process_time() - cpu) / (seconds * threads))
        numba.set_num_threads(everyone)
        units = count * (steps + 1 + tries) * (50 + SHAPE_UNITS)
        one, many = statistics.median(times[1]), statistics.median(times[everyone])
        rows.append({"count": count, "steps": steps, "units": units, "estimate": units * RATES["converge_all"],
                     "one_thread": one, "all_threads": many, "threads": everyone, "speedup": one / many,
                     "share": statistics.median(shares)})
        print(f"{count:5d} x {steps:2d} steps: one thread {1e6 * one:9.1f} us, {everyone} threads {1e6 * many:9.1f} us"
              f" ({one / many:.2f}x), share {statistics.median(shares):.2f}", flush=True)
    probes = [backend._probe(3, everyone) for _ in range(repeats)]
    print(f"probe (the overhead of a launch on {everyone} threads): median {1e6 * statistics.median(probes):.1f} us,"
          f" max {1e6 * max(probes):.1f} us")
    return rows, probes


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--load", type=int, default=0, help="spinning processes beside the runs")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--cases", nargs="+", default=list(CASES), choices=list(CASES))
    parser.add_argument("--threads", nargs="+", default=["default", "1"])
    parser.add_argument("--versions", nargs="+", default=["before", "after"],
                        help="before (NDPACK_PARALLEL_FROM=0), after (the default) or a fixed threshold")
    parser.add_argument("--launches", action="store_true", help="time single launches instead (see above)")
    parser.add_argument("--out", type=Path, default=Path("bench/results/threads_2core.json"))
    args = parser.parse_args()
    if args.launches:
        machine = machine_info()
        with busy(args.load):
            rows, probes = launch_sweep(max(args.repeats, 5) * 4)
        write_json(args.out, {"machine": machine, "load": args.load, "launches": rows, "probes": probes})
        return
    variants = [(case, threads, version) for case in args.cases for threads in args.threads
                for version in args.versions]
    runs = {variant: [] for variant in variants}
    started = time.perf_counter()
    machine = machine_info()
    with busy(args.load):
        for repeat in range(args.repeats):
            for variant in variants:  # interleaved: each round runs every variant once
                case, threads, version = variant
                row = run_one(case, threads, version)
                runs[variant].append(row)
                print(f"[{repeat}] {case} | threads {threads} | {version}: {row['seconds']:.2f} s, "
                      f"{row['parallel_launches']}/{row['launches']} launches parallel, overhead "
                      f"{1e6 * max(row['overheads'], default=0):.0f} us, "
                      f"load {row['load_average']}",
                      flush=True)
            write_results(args, machine, runs, started, table=False)  # so far: a run cut short keeps its rounds
    write_results(args, machine, runs, started)


def write_results(args, machine, runs, started, table: bool = True) -> None:
    """The JSON of the runs so far, and their table (printed, with ``table``)."""
    rows = []
    lines = [f"\nload {args.load} | case | threads | version | median s | runs s | parallel launches | fill"]
    for (case, threads, version), found in runs.items():
        if not found:
            continue
        spheres = {row["spheres"] for row in found}
        assert all(row["valid"] for row in found), (case, threads, version)
        median = statistics.median(row["seconds"] for row in found)
        rows.append({"case": case, "threads": threads, "version": version, "load": args.load,
                     "median_seconds": round(median, 3), "seconds": [round(row["seconds"], 3) for row in found],
                     "spheres": sorted(spheres), "fill": found[0]["fill"], "numba_threads": found[0]["threads"],
                     "layer": found[0]["layer"], "mode": found[0]["mode"], "runs": found})
        each = ", ".join(f"{row['seconds']:.2f}" for row in found)
        lines.append(f"| {case} | {threads} | {version} | {median:.2f} | {each} | "
                     f"{found[0]['parallel_launches']}/{found[0]['launches']} | {found[0]['fill']:.4f}")
    if table:
        print("\n".join(lines))
    for case in args.cases:  # one packing whatever the threads and the version
        hashes = {h for row in rows if row["case"] == case for h in row["spheres"]}
        assert len(hashes) <= 1, (case, hashes)
    write_json(args.out, {"machine": machine, "load": args.load, "repeats": args.repeats,
                          "wall_seconds": round(time.perf_counter() - started, 1), "rows": rows})

if __name__ == "__main__":
    main()
