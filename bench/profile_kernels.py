"""Where a fast-mode packing's time goes, by device kernel and by driver phase.

    python bench/profile_kernels.py --backends warp numba-cuda --count 100000 [--mesh armadillo.obj]
        [--variants now no-ahead] [--repeats 2] [--host-profile] [--stages] [--spheres now.npz] [--warp-level 3]

Every kernel launch of the device store is made synchronous and timed (so its time is the
device's, launch included; copies queued before it are waited for first, and not counted).
The driver's phases are timed inclusively
(``refine`` contains ``reconverge``). Synchronising every launch
slows the run down: the total is not the unprofiled time. Compiles first (a 3-sphere packing).

``--variants`` compares, in one process, the code as it is (``now``) with a policy turned off:
``no-ahead`` does not polish ahead (``rounds.POLISH_AHEAD``, the backend's ``launch_bound``);
``spread-1`` moves each prototype on one thread of a launch, however few it moves (the
backend's ``move_spread``, see :func:`ndpack.backends.prototypes.lane_spread`); ``threads-2^k``
spreads a move launch over at most 2^k threads (``prototypes.SPREAD_THREADS``); ``split-R`` splits
cells down to R times the frontier on a GPU (``rounds.SPLIT_RATIO_AHEAD``); ``lanes-N`` walks a
mesh's tree cooperatively in move launches of at most N prototypes (``lanes-off``: never, in moves
or the set-up's converge; ``converge-off``: not in the set-up's converge; the backend's
``cooperative_most`` and ``cooperative_converge_most``, see :mod:`ndpack.backends.warp_lanes`);
``share-N``: the lanes agree on the best distance every N rounds (``cooperative_share``);
``block-N``: a move launch that is not cooperative runs in blocks of N threads (``move_block``);
``ahead-whole``: the polish ahead runs the whole polish schedule (``rounds.AHEAD_EPS_START``);
``reach-F``: the polish ahead reaches down to F of the frontier (``rounds.POLISH_AHEAD``).
Each variant's spheres are set beside the first variant's: their count and the largest change of
a radius, sorted.
Each variant is also timed unprofiled ``--repeats`` times (median). ``--host-profile`` prints
the host's cProfile of one unprofiled ``now`` run (by own time, then ndpack's functions by
inclusive time): where the host works and waits. ``--stages`` times the unprofiled runs' stages
(setting up, the rounds, the final check), each ended by a device synchronisation.
"""

from __future__ import annotations

import argparse
import collections
import cProfile
import functools
import json
import pstats
import statistics
import time

import numpy as np

import ndpack as nd
from ndpack.drivers.greedy import protosphere, rounds
from ndpack.backends import get_backend, prototypes

#: The backend attributes each variant sets.
VARIANTS = {"now": {}, "no-ahead": {"launch_bound": False}, "spread-1": {"move_spread": 1},
            **{f"lanes-{most}": {"cooperative_most": most} for most in (1024, 8192, 16384)},
            "lanes-off": {"cooperative_most": 0, "cooperative_converge_most": 0},
            "converge-off": {"cooperative_converge_most": 0},
            **{f"share-{rounds}": {"cooperative_share": rounds} for rounds in (1, 4, 16)},
            **{f"block-{threads}": {"move_block": threads} for threads in (64, 128, 256, 512)}}
#: Variants that set ``prototypes.SPREAD_THREADS`` instead: a move launch's most threads.
THREAD_VARIANTS = {f"threads-2^{bits}": 1 << bits for bits in (15, 16, 18, 19, 20)}
#: Variants that set the GPU's split ratio (``rounds.SPLIT_RATIO_AHEAD``) instead.
SPLIT_VARIANTS = {f"split-{ratio:g}": ratio for ratio in (2.0, 2.5, 3.0, 4.0)}
#: Variants that set where the polish ahead's schedule starts (``rounds.AHEAD_EPS_START``) instead.
AHEAD_VARIANTS = {"ahead-whole": np.inf}
#: Variants that set the polish ahead's reach (``rounds.POLISH_AHEAD``, a fraction of the frontier) instead.
REACH_VARIANTS = {f"reach-{fraction:g}": fraction for fraction in (0.64, 0.512, 0.4)}

#: Driver phases timed inclusively: (owner, attribute name).
PHASES = [
    (rounds.Fast, "choose"),
    (protosphere.RunState, "reconverge"),
    (protosphere.RunState, "polish"),
    (rounds.Fast, "refine"),
    (protosphere.RunState, "_distance"),
    (protosphere.RunState, "insert"),
    (protosphere.RunState, "revive"),
    (protosphere.RunState, "touched"),
    (rounds, "disjoint_greedy"),
]


class Recorder:
    def __init__(self):
        self.kernels = collections.defaultdict(lambda: [0, 0.0, 0, 0])  # calls, seconds, threads, max threads
        self.phases = collections.defaultdict(lambda: [0, 0.0])

    def kernel(self, name, seconds, threads):
        entry = self.kernels[name]
        entry[0] += 1
        entry[1] += seconds
        entry[2] += threads
        entry[3] = max(entry[3], threads)

    def phase(self, name, seconds):
        self.phases[name][0] += 1
        self.phases[name][1] += seconds


def _timed_phase(recorder, name, function):
    @functools.wraps(function)
    def wrapper(*args, **kwargs):
        started = time.perf_counter()
        try:
            return function(*args, **kwargs)
        finally:
            recorder.phase(name, time.perf_counter() - started)
    return wrapper


#: The stages of a packing timed in the unprofiled runs (``--stages``), each ended by a device
#: synchronisation, so that a stage's wall time includes the device work it queued: setting up
#: (placing and converging the prototypes), the rounds, and the final check in float64.
STAGES = [(protosphere.RunState, "__init__", "setup"), (protosphere, "_run_rounds", "rounds"),
          (protosphere, "_ensure_valid", "verify")]


def device_sync(backend):
    """A function that waits for ``backend``'s device queue (nothing on a CPU). Only that queue:
    asking numba-cuda whether a GPU is there starts its driver, a second in a run's first stage."""
    device = getattr(backend, "device", None)
    if getattr(backend, "name", "") == "warp" and getattr(device, "is_cuda", False):
        return lambda: backend.wp.synchronize_device(device)
    if getattr(backend, "name", "") == "numba-cuda":
        from numba import cuda

        return cuda.synchronize
    return lambda: None


def install_stages(seconds, sync=lambda: None):
    """Time :data:`STAGES` into ``seconds`` (a dict: stage -> [seconds, ...]), each ended by
    ``sync()`` (see :func:`device_sync`); returns an undo function."""
    saved = []
    for owner, attribute, stage in STAGES:
        original = getattr(owner, attribute)
        saved.append((owner, attribute, original))

        def timed(*args, _original=original, _stage=stage, **kwargs):
            started = time.perf_counter()
            try:
                return _original(*args, **kwargs)
            finally:
                sync()
                seconds.setdefault(_stage, []).append(time.perf_counter() - started)
        setattr(owner, attribute, functools.wraps(original)(timed))

    def undo():
        for owner, attribute, original in saved:
            setattr(owner, attribute, original)
    return undo


def launch_kind(name, args, cooperative=False):
    """A launch's kernel ``name``, with a move launch's kind: a polish, a move that polishes ahead,
    or a move (``args`` of ``move_ids`` end with polish, spread, polish_steps, polish_low, finite
    where it polishes ahead, and polish_from), and `` lanes`` where it is ``cooperative`` (a block of
    lanes per prototype, where the shape walks a tree)."""
    if name != "move_ids":
        return name
    kind = "move_ids[polish]" if args[-5] else "move_ids[move+ahead]" if args[-2] < 1e300 else "move_ids[move]"
    return kind + " lanes" if cooperative else kind


def _timed_launch(recorder, launch):
    @functools.wraps(launch)
    def wrapper(self, name, threads, *args, **options):  # options: lanes, most
        self.synchronize()  # what was queued before (copies) is not this kernel's
        started = time.perf_counter()
        launch(self, name, threads, *args, **options)
        self.synchronize()
        lanes, most = options.get("lanes", 1), options.get("most")
        most = self.backend.cooperative_most if most is None else most
        recorder.kernel(launch_kind(name, args, lanes > 1 and threads // lanes <= most), time.perf_counter() - started,
                        threads)
    return wrapper


def install(recorder):
    """Patch the phases and both device adapters' launches; returns an undo function."""
    from ndpack.backends import numba_cuda_backend, warp_backend

    saved = []
    for owner, name in PHASES:
        original = getattr(owner, name)
        saved.append((owner, name, original))
        setattr(owner, name, _timed_phase(recorder, name, original))
    for adapter in (warp_backend._WarpDevice, numba_cuda_backend._CudaDevice):
        saved.append((adapter, "launch", adapter.launch))
        adapter.launch = _timed_launch(recorder, adapter.launch)

    def undo():
        for owner, name, original in saved:
            setattr(owner, name, original)
    return undo


def _report(name, packing, wall, recorder, timed):
    rounds = len(packing.stats.time)
    print(f"== {name}: {len(packing.radii)} spheres, {rounds} rounds, fill {packing.fill:.5f}; unprofiled "
          f"{', '.join(f'{t:.2f}' for t in timed) or '-'} s; {wall:.2f} s with every launch synchronised")
    device = sum(entry[1] for entry in recorder.kernels.values())
    print(f"   device kernels {device:.2f} s in {sum(e[0] for e in recorder.kernels.values())} launches")
    print(f"   {'kernel':28s} {'calls':>6s} {'seconds':>8s} {'ms/call':>8s} {'threads':>10s} {'max':>8s}")
    for kernel, (calls, seconds, threads, most) in sorted(recorder.kernels.items(), key=lambda item: -item[1][1]):
        print(f"   {kernel:28s} {calls:6d} {seconds:8.3f} {1e3 * seconds / calls:8.3f} {threads:10d} {most:8d}")
    print(f"   {'phase (inclusive)':28s} {'calls':>6s} {'seconds':>8s}")
    for phase, (calls, seconds) in sorted(recorder.phases.items(), key=lambda item: -item[1][1]):
        print(f"   {phase:28s} {calls:6d} {seconds:8.3f}")
    return dict(spheres=len(packing.radii), rounds=rounds, fill=packing.fill, wall=wall, unprofiled=timed,
                median=statistics.median(timed) if timed else None, device=device,
                kernels=dict(recorder.kernels), phases=dict(recorder.phases))


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--backends", nargs="+", default=["warp"])
    parser.add_argument("--count", type=int, default=100_000)
    parser.add_argument("--mesh", default=None, help="a mesh file; default the unit cube (or --square)")
    parser.add_argument("--square", action="store_true", help="the unit square instead of the cube")
    parser.add_argument("--variants", nargs="+", default=["now"],
                        choices=[*VARIANTS, *THREAD_VARIANTS, *SPLIT_VARIANTS, *AHEAD_VARIANTS, *REACH_VARIANTS])
    parser.add_argument("--repeats", type=int, default=0, help="unprofiled runs per variant (median)")
    parser.add_argument("--host-profile", action="store_true", help="cProfile one unprofiled run of `now`")
    parser.add_argument("--stages", action="store_true",
                        help="time the unprofiled runs' stages (setup, rounds, verify), each ended by a device sync")
    parser.add_argument("--no-profiled", action="store_true",
                        help="only the unprofiled runs (--repeats of them): no run with every launch timed")
    parser.add_argument("--out", default=None, help="write the tables as JSON here")
    parser.add_argument("--spheres", default=None,
                        help="save the first variant's last unprofiled packing here (.npz: centers, radii), "
                             "to set beside another checkout's; BACKEND in the path is replaced by the backend's name")
    parser.add_argument("--warp-level", type=int, default=None,
                        help="Warp's CUDA optimisation level for ndpack's modules (kernels.compile.WARP_OPTIMIZATION; "
                             "default ndpack's)")
    args = parser.parse_args()
    if args.warp_level is not None:  # before any module is made: the level is part of its text
        from ndpack.kernels import compile as kernel_compile

        kernel_compile.WARP_OPTIMIZATION = args.warp_level
    dim = 2 if args.square else 3
    shape = nd.TriangleMesh.load(args.mesh) if args.mesh else nd.Box(np.zeros(dim), np.ones(dim))
    results = {}
    for name in args.backends:
        backend = get_backend(name)
        nd.pack(shape, 3, backend=backend, mode="fast")
        spread_threads, split_ahead = prototypes.SPREAD_THREADS, rounds.SPLIT_RATIO_AHEAD
        ahead_start = getattr(rounds, "AHEAD_EPS_START", None)  # None: a checkout from before it
        reach = protosphere.POLISH_AHEAD
        defaults = {key: getattr(backend, key) for variant in VARIANTS.values() for key in variant
                    if hasattr(backend, key)}
        first_radii = None
        for variant in args.variants:
            for key, value in defaults.items():
                setattr(backend, key, VARIANTS.get(variant, {}).get(key, value))
            prototypes.SPREAD_THREADS = THREAD_VARIANTS.get(variant, spread_threads)
            rounds.SPLIT_RATIO_AHEAD = SPLIT_VARIANTS.get(variant, split_ahead)
            if ahead_start is not None:
                rounds.AHEAD_EPS_START = AHEAD_VARIANTS.get(variant, ahead_start)
            protosphere.POLISH_AHEAD = REACH_VARIANTS.get(variant, reach)
            timed, stages = [], {}
            for _ in range(args.repeats):
                undo_stages = install_stages(stages, device_sync(backend)) if args.stages else (lambda: None)
                started = time.perf_counter()
                try:
                    last = nd.pack(shape, args.count, backend=backend, mode="fast")
                finally:
                    undo_stages()
                timed.append(time.perf_counter() - started)
                print(f"   {name} {variant}: {timed[-1]:.2f} s, {len(last.stats.time)} rounds, fill {last.fill:.5f}",
                      flush=True)
            if stages:
                print(f"== {name} {variant}: stages, median of {args.repeats} (s): "
                      + ", ".join(f"{stage} {statistics.median(values):.3f}" for stage, values in stages.items()))
            if args.host_profile and variant == "now":
                profile = cProfile.Profile()
                profile.enable()
                nd.pack(shape, args.count, backend=backend, mode="fast")
                profile.disable()
                print(f"== {name}: host profile of one unprofiled run (tottime)")
                pstats.Stats(profile).sort_stats("tottime").print_stats(25)
                pstats.Stats(profile).sort_stats("cumtime").print_stats("ndpack", 30)
            key = name if args.variants == ["now"] else f"{name} {variant}"
            same = {}
            if timed:  # the last unprofiled run's spheres against the first variant's
                radii = np.sort(last.radii)
                first_radii = radii if first_radii is None else first_radii
                same = dict(spheres_first=len(first_radii), most_radius_change=float(
                    np.abs(radii - first_radii).max()) if len(radii) == len(first_radii) else None)
                print(f"   {name} {variant} against {args.variants[0]}: {same}", flush=True)
                if args.spheres and variant == args.variants[0]:
                    np.savez(args.spheres.replace("BACKEND", name), centers=last.centers, radii=last.radii)
            if args.no_profiled:
                results[key] = dict(spheres=len(last.radii), rounds=len(last.stats.time), fill=last.fill, **same,
                                    unprofiled=timed, median=statistics.median(timed),
                                    stages={stage: statistics.median(values) for stage, values in stages.items()})
                continue
            recorder = Recorder()
            undo = install(recorder)
            started = time.perf_counter()
            try:
                packing = nd.pack(shape, args.count, backend=backend, mode="fast")
            finally:
                undo()
            wall = time.perf_counter() - started
            results[key] = dict(_report(key, packing, wall, recorder, timed), **same)
            if stages:
                results[key]["stages"] = {stage: statistics.median(values) for stage, values in stages.items()}
        for key, value in defaults.items():
            setattr(backend, key, value)
        prototypes.SPREAD_THREADS, rounds.SPLIT_RATIO_AHEAD = spread_threads, split_ahead
        if ahead_start is not None:
            rounds.AHEAD_EPS_START = ahead_start
        protosphere.POLISH_AHEAD = reach
    if args.out:
        with open(args.out, "w") as file:
            json.dump(results, file, indent=1)


if __name__ == "__main__":
    main()
