"""Where a GPU packing's device waits for the host: one packing's kernels and copies as the device
ran them, and the host's driver steps at the same moments.

    python3 bench/gpu_timeline.py --backend warp --mesh armadillo.obj --count 100000 --out RESULT.json

For the GPU machine, whose Python has PyTorch (not a dependency of ndpack): its profiler reads
CUPTI's record of every kernel, copy and fill in the process, Warp's and numba-cuda's included,
and the host's steps are marked with ``torch.profiler.record_function`` around the driver's and the
device store's methods (the marks and the tracing slow a run down: compare within traced runs).
The device is idle between its activities; each idle moment is charged to the innermost host
step under way then. So the table
says which of the host's steps keep the device waiting, and for how long: what a round on the
device would remove. The work model (``bench/work_model.py``) counts launches
and synchronisations on the CPU; this measures their cost on the GPU.

Printed: the whole call, the device's busy and idle time, idle time by host step, the device's
time by kernel, and the longest idle gaps with the activities around them. ``--out`` keeps the
tables and the machine.
"""

from __future__ import annotations

import argparse
import bisect
import collections
import contextlib
import functools
import json
import re
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import machine_info, write_json

import ndpack as nd

#: The host's steps marked: (owner's module path, owner, attribute, mark).
STEPS = [
    ("ndpack.drivers.greedy.protosphere", "RunState", "__init__", "set-up"),
    ("ndpack.drivers.greedy.protosphere", None, "cell_bounds", "set-up: cell bounds"),
    ("ndpack.drivers.greedy.protosphere", "RunState", "_restarts", "set-up: restarts"),
    ("ndpack.drivers.greedy.protosphere", None, "best_starts", "set-up: best starts"),
    ("ndpack.drivers.greedy.protosphere", "RunState", "_step_in", "set-up: step in"),
    ("ndpack.backends.warp_backend", None, "converge_by_move", "set-up: converge"),
    ("ndpack.backends.numba_cuda_backend", None, "converge_by_move", "set-up: converge"),
    ("ndpack.drivers.greedy.protosphere", "RunState", "insert", "insert"),
    ("ndpack.drivers.greedy.protosphere", "RunState", "touched", "touched"),
    ("ndpack.drivers.greedy.protosphere", "RunState", "reconverge", "reconverge"),
    ("ndpack.drivers.greedy.protosphere", None, "_ensure_valid", "final check"),
    ("ndpack.verify", None, "overlapping_pairs", "final check: overlaps"),
    ("ndpack.drivers.greedy.protosphere", None, "ensure_possible", "final check: possible"),
    ("ndpack.drivers.greedy.centre_distances", "CentreDistances", "collect", "last centres' distances"),
    ("ndpack.drivers.greedy.rounds", "Fast", "choose", "choose"),
    ("ndpack.drivers.greedy.rounds", "Fast", "refine", "refine"),
    ("ndpack.drivers.greedy.rounds", None, "disjoint_greedy", "conflicts"),
    ("ndpack.drivers.greedy.rounds", None, "_snug", "snug"),
    ("ndpack.drivers.greedy.centre_distances", "CentreDistances", "catch_up", "check ahead"),
    ("ndpack.backends.prototypes", "DevicePrototypes", "window", "window"),
    ("ndpack.backends.prototypes", "DevicePrototypes", "touched", "store touched"),
    ("ndpack.backends.prototypes", "DevicePrototypes", "split_candidates", "split candidates"),
    ("ndpack.backends.prototypes", "DevicePrototypes", "split_cells", "split cells"),
    ("ndpack.backends.prototypes", "DevicePrototypes", "tighten_reach", "tighten"),
    ("ndpack.backends.prototypes", "DevicePrototypes", "select", "select"),
    ("ndpack.backends.prototypes", "DevicePrototypes", "lower_clearance", "lower clearance"),
    ("ndpack.backends.prototypes", "DevicePrototypes", "_neighbours", "neighbours"),
    ("ndpack.backends.prototypes", "DevicePrototypes", "move", "move"),
    ("ndpack.backends.warp_backend", "_WarpDevice", "fetch", "fetch (sync)"),
    ("ndpack.backends.numba_cuda_backend", "_CudaDevice", "fetch", "fetch (sync)"),
    ("ndpack.backends.warp_backend", "_WarpDevice", "launch", "launch"),
    ("ndpack.backends.numba_cuda_backend", "_CudaDevice", "launch", "launch"),
    ("ndpack.backends.warp_backend", "_WarpDevice", "upload", "upload"),
    ("ndpack.backends.numba_cuda_backend", "_CudaDevice", "upload", "upload"),
]
#: The device's activities in the trace.
DEVICE = ("kernel", "gpu_memcpy", "gpu_memset")


@contextlib.contextmanager
def marked():
    """Mark :data:`STEPS` with ``record_function`` while in the block."""
    import importlib

    from torch.profiler import record_function

    saved = []
    for module_name, owner_name, attribute, mark in STEPS:
        module = importlib.import_module(module_name)
        owner = module if owner_name is None else getattr(module, owner_name)
        original = getattr(owner, attribute)

        @functools.wraps(original)
        def wrapped(*args, _original=original, _mark=mark, **kwargs):
            with record_function(_mark):
                return _original(*args, **kwargs)

        setattr(owner, attribute, wrapped)
        saved.append((owner, attribute, original))
    try:
        yield
    finally:
        for owner, attribute, original in reversed(saved):
            setattr(owner, attribute, original)


def short(name: str) -> str:
    """A kernel's name without its compiler's decoration (Warp's ``_cuda_kernel_forward``, numba-cuda's
    mangling)."""
    name = re.sub(r"_[0-9a-f]{6,}_cuda_kernel_forward$|_cuda_kernel_forward$", "", name)
    found = re.search(r"cudapy\d*[\w]*?(\d+)([A-Za-z_][A-Za-z0-9_]*)", name)
    if found and name.startswith("_Z"):
        length = int(found.group(1))
        return found.group(2)[:length]
    return name[:60]


def innermost_segments(host: list, first: float, last: float) -> list:
    """The host's time from ``first`` to ``last`` (us) cut where its innermost step changes: (start,
    end, step) in order, ``(between steps)`` where none is under way. ``host``: the marks, sorted by
    start; one thread's, so nested."""
    segments, stack, cursor = [], [], first

    def emit(until):
        nonlocal cursor
        if until > cursor:
            segments.append((cursor, until, stack[-1][1] if stack else "(between steps)"))
            cursor = until

    for e in sorted(host, key=lambda e: (e["ts"], -e["dur"])):  # a parent before a child that starts with it
        while stack and stack[-1][0] <= e["ts"]:
            emit(stack[-1][0])
            stack.pop()
        emit(e["ts"])
        stack.append((e["ts"] + e["dur"], e["name"]))
    while stack:
        emit(stack[-1][0])
        stack.pop()
    emit(last)
    return segments


def analyse(trace: dict, wall_s: float) -> dict:
    """The tables of a Chrome trace of one packing (:func:`main`)."""
    events = [e for e in trace["traceEvents"] if e.get("ph") == "X"]
    device = sorted((e for e in events if e.get("cat") in DEVICE), key=lambda e: e["ts"])
    host = sorted((e for e in events if e.get("cat") == "user_annotation"), key=lambda e: e["ts"])
    if not device:
        raise SystemExit("the trace holds no device activity: CUPTI saw no kernels")
    first = min(e["ts"] for e in host) if host else device[0]["ts"]
    last = max(e["ts"] + e["dur"] for e in host) if host else device[-1]["ts"] + device[-1]["dur"]
    # Idle intervals: between the end of the device's work so far and its next activity.
    idle, end = [], first
    by_kernel = collections.defaultdict(lambda: [0, 0.0])
    for e in device:
        if e["ts"] > end:
            idle.append((end, e["ts"], e))
        end = max(end, e["ts"] + e["dur"])
        entry = by_kernel[short(e["name"]) if e["cat"] == "kernel" else e["cat"]]
        entry[0] += 1
        entry[1] += e["dur"]
    if last > end:
        idle.append((end, last, None))
    segments = innermost_segments(host, first, last)
    seg_starts = [segment[0] for segment in segments]

    def step_at(t):
        k = bisect.bisect_right(seg_starts, t) - 1
        return segments[k][2] if k >= 0 else "(between steps)"

    by_step = collections.Counter()
    k = 0
    for start, stop, _ in idle:  # both sorted and disjoint: one pass
        while k < len(segments) and segments[k][1] <= start:
            k += 1
        m = k
        while m < len(segments) and segments[m][0] < stop:
            by_step[segments[m][2]] += min(stop, segments[m][1]) - max(start, segments[m][0])
            m += 1
    gaps = sorted(((stop - start, start, following) for start, stop, following in idle), key=lambda g: -g[0])
    idle_us = sum(stop - start for start, stop, _ in idle)
    busy_us = (last - first) - idle_us
    return dict(
        wall_s=wall_s, traced_s=(last - first) * 1e-6, device_busy_s=busy_us * 1e-6, device_idle_s=idle_us * 1e-6,
        activities=len(device),
        idle_by_host_step_s={name: us * 1e-6 for name, us in by_step.most_common()},
        device_by_kernel={name: dict(count=count, seconds=us * 1e-6)
                          for name, (count, us) in sorted(by_kernel.items(), key=lambda kv: -kv[1][1])},
        longest_gaps=[dict(us=length, at_s=(start - first) * 1e-6, step=step_at(start + length / 2),
                           next=short(following["name"]) if following else "(end)")
                      for length, start, following in gaps[:25]],
    )


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--backend", default="warp", choices=["warp", "numba-cuda"])
    parser.add_argument("--mesh", default=None, help="a mesh file; default the unit cube")
    parser.add_argument("--count", type=int, default=100_000)
    parser.add_argument("--out", default=None)
    args = parser.parse_args(argv)
    from torch.profiler import ProfilerActivity, profile

    shape = nd.TriangleMesh.load(args.mesh) if args.mesh else nd.Box([0, 0, 0], [1, 1, 1])
    backend = nd.backends.get_backend(args.backend)
    nd.pack(shape, 3, mode="fast", backend=backend, progress=False)  # compile
    nd.pack(shape, args.count, mode="fast", backend=backend, progress=False)  # warm: arrays, pools, caches
    with marked(), profile(activities=[ProfilerActivity.CPU, ProfilerActivity.CUDA]) as prof:
        started = time.perf_counter()
        packing = nd.pack(shape, args.count, mode="fast", backend=backend, progress=False)
        wall = time.perf_counter() - started
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "trace.json"
        prof.export_chrome_trace(str(path))
        trace = json.loads(path.read_text())
    result = analyse(trace, wall)
    result.update(backend=args.backend, shape=args.mesh or "unit cube", count=args.count,
                  spheres=len(packing), rounds=len(packing.stats.count), fill=float(packing.fill))
    print(f"{args.backend}, {result['shape']}, {len(packing):,} spheres in {result['rounds']} rounds: "
          f"{wall:.2f} s (marked and traced); device busy {result['device_busy_s']:.3f} s, idle "
          f"{result['device_idle_s']:.3f} s over {result['activities']:,} activities")
    print("device idle, by the host's innermost step then (s):")
    for name, seconds in result["idle_by_host_step_s"].items():
        print(f"  {name:<22} {seconds:8.3f}")
    print("device time by kernel (s):")
    for name, entry in list(result["device_by_kernel"].items())[:20]:
        print(f"  {name:<28} {entry['count']:6d} {entry['seconds']:8.3f}")
    print("longest idle gaps (us, when, the host's step, the next activity):")
    for gap in result["longest_gaps"][:12]:
        print(f"  {gap['us']:8.0f} at {gap['at_s']:.3f} s  {gap['step']:<20} -> {gap['next']}")
    if args.out:
        write_json(Path(args.out), dict(machine=machine_info(), **result))


if __name__ == "__main__":
    main()
