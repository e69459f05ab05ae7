"""The fast mode's conflict check (``disjoint_greedy``), on the inputs real packings give it.

    python bench/conflicts.py --against /path/to/old/checkout --out bench/results/conflicts_2core_issue47.json
    python bench/conflicts.py --packings-only --repo /path/to/old/checkout  # end to end, another checkout
    python bench/conflicts.py --cases cube-200000 armadillo-200000 --against /path/to/old/checkout --repeats 3 \
        --compile --out bench/results/conflicts_2core_issue48.json  # the 3-D path of issue 48

Two parts:

* End to end: each packing (a case and a mode; the faithful mode for the periodic cases only)
  in a fresh process with ``--repo``'s ndpack first on the path, after a warm-up packing of a
  few spheres (compilation): the seconds, the spheres, and the seconds spent in the conflict
  check. The case of issue 47 is a fast-mode packing of discs in a 2-D periodic unit box with
  radii 0.01-0.2: its first round's 32,761 prototypes, all capped at 0.2, were nearly all within
  0.4 of each other, and the check listed hundreds of millions of their pairs (about a minute,
  against seconds for the faithful mode).
* Same inputs: the arguments of every call of the check during fast packings of this checkout
  (the periodic box, the unit cube, a 4-D shell, a 12-D shell on a grid of 2), timed with this
  checkout's ``disjoint_greedy`` and with ``--against``'s (its ``conflicts.py`` loaded by path),
  interleaved, medians of ``--repeats``; the two must return the same positions. A call the other
  version takes more than ``--slow`` seconds for is timed once. Per size of call (candidates), the
  calls' median seconds each way; where this checkout has the grid path of issue 48
  (``_greedy_on_grid``), how many calls take it.
* With ``--compile``: this checkout's first call in a fresh process with an empty Numba cache
  (compiling), then in another with that cache (loading), ``import numba`` apart.

The cases of issue 48 are fast-mode packings in 3-D of 200,000 spheres (the unit cube and the
armadillo, :data:`ARMADILLO`): their calls, up to 65,536 candidates, take the common path (no
period, not crowded), where the k-d tree's construction and pair search cost most.
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import statistics
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent

PACKINGS = {
    "periodic-72": "a 2-D periodic unit box, 72 discs of radii 0.01-0.2 (issue 47)",
    "periodic-300": "a 2-D periodic unit box, up to 300 discs of radii 0.01-0.2",
    "cube-20000": "the unit cube, 20,000 spheres",
    "shell4-5000": "a 4-D unit ball less the ball of radius 1/2, 5,000 spheres",
    "shell12-2000": "a 12-D unit ball less the ball of radius 1/2, 2,000 spheres on a grid of 2",
    "cube-200000": "the unit cube, 200,000 spheres (issue 48)",
    "armadillo-200000": "the armadillo mesh, 200,000 spheres (issue 48)",
}
#: The cases run unless ``--cases`` says (issue 47's: those of issue 48 take minutes).
DEFAULT_CASES = ["periodic-72", "periodic-300", "cube-20000", "shell4-5000", "shell12-2000"]
#: The armadillo of the shared test meshes (its README), beside this checkout.
ARMADILLO = HERE.parent.parent / "shared" / "data" / "meshes" / "armadillo.obj"
#: Sizes of calls (candidates) the same-inputs part sums apart: from each bound to the next.
SIZES = (65, 1000, 4000, 16000)


def packing_args(case: str):
    """The shape and the keyword arguments of ``nd.pack`` for ``case``."""
    import numpy as np

    import ndpack as nd

    if case.startswith("periodic"):
        return nd.Periodic(nd.Box([0, 0], [1, 1])), dict(n=int(case.split("-")[1]), seed=0, min_radius=0.01,
                                                         max_radius=0.2)
    if case in ("cube-20000", "cube-200000"):
        return nd.Box(np.zeros(3), np.ones(3)), dict(n=int(case.split("-")[1]))
    if case == "armadillo-200000":
        return nd.TriangleMesh.load(str(ARMADILLO)), dict(n=200000)
    if case == "shell4-5000":
        return nd.Ball(np.zeros(4), 1.0) - nd.Ball(np.zeros(4), 0.5), dict(n=5000)
    if case == "shell12-2000":
        return nd.Ball(np.zeros(12), 1.0) - nd.Ball(np.zeros(12), 0.5), dict(n=2000, grid=2)
    raise ValueError(case)


def watched(calls: list):
    """Wrap the driver's ``disjoint_greedy`` so that every call's arguments and seconds land in
    ``calls``; returns a function that undoes it."""
    import ndpack.drivers.greedy.rounds as rounds

    plain = rounds.disjoint_greedy

    def check(centers, radii, margin, period=None):
        started = time.perf_counter()
        kept = plain(centers, radii, margin, period)
        calls.append((centers, radii, margin, period, time.perf_counter() - started))
        return kept

    rounds.disjoint_greedy = check
    return lambda: setattr(rounds, "disjoint_greedy", plain)


def one(case: str, mode: str) -> dict:
    """Run in this process: the case's packing in ``mode``, measured."""
    import ndpack as nd

    shape, kwargs = packing_args(case)
    nd.pack(shape, **{**kwargs, "n": 3}, mode=mode, backend="numba", progress=False)
    calls = []
    watched(calls)
    started = time.perf_counter()
    packing = nd.pack(shape, **kwargs, mode=mode, backend="numba", progress=False)
    seconds = time.perf_counter() - started
    return dict(case=case, mode=mode, seconds=round(seconds, 3), spheres=len(packing), valid=bool(packing.verify().ok),
                conflict_seconds=round(sum(call[-1] for call in calls), 4), conflict_calls=len(calls),
                most_candidates=max((len(call[1]) for call in calls), default=0), where=nd.__file__)


def packings(repo: str, cases, modes) -> list:
    """Each case's packing in each mode (the faithful one for the periodic cases only)."""
    sys.path.insert(0, str(HERE))
    from _common import run_with

    rows = []
    for case in cases:
        for mode in modes if case.startswith("periodic") else [mode for mode in modes if mode == "fast"]:
            done = run_with(repo, [str(HERE / "conflicts.py"), "--one", case, mode])
            row = json.loads(done.stdout) if done.returncode == 0 else dict(
                case=case, mode=mode, error=(done.stderr.strip().splitlines() or ["killed"])[-1])
            print(row, flush=True)
            rows.append(row)
    return rows


def same_inputs(against: str, cases, repeats: int, slow: float) -> list:
    """This checkout's ``disjoint_greedy`` against ``against``'s, on the calls of ``cases``."""
    import numpy as np

    import ndpack as nd
    from ndpack.drivers.greedy import conflicts

    spec = importlib.util.spec_from_file_location(
        "other_conflicts", Path(against) / "ndpack" / "drivers" / "greedy" / "conflicts.py")
    other = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(other)
    rows = []
    for case in cases:
        shape, kwargs = packing_args(case)
        calls = []
        undo = watched(calls)
        nd.pack(shape, **kwargs, mode="fast", backend="numba", progress=False)
        undo()
        times = {"now": [], "other": []}
        largest = max(range(len(calls)), key=lambda i: len(calls[i][1]))
        largest_times = {"now": [], "other": []}
        each = {"now": np.zeros((repeats, len(calls))), "other": np.zeros((repeats, len(calls)))}
        other_first = {}  # the other's seconds on each call, the first time
        for repeat in range(repeats):
            total = {"now": 0.0, "other": 0.0}
            order = (("now", conflicts), ("other", other))
            for i, (centers, radii, margin, period, _) in enumerate(calls):
                kept = {}
                for name, module in order if repeat % 2 else order[::-1]:
                    if name == "other" and repeat and other_first[i] > slow:
                        seconds = other_first[i]
                    else:
                        started = time.perf_counter()
                        kept[name] = module.disjoint_greedy(centers, radii, margin, period)
                        seconds = time.perf_counter() - started
                        if name == "other" and not repeat:
                            other_first[i] = seconds
                    total[name] += seconds
                    each[name][repeat, i] = seconds
                    if i == largest:
                        largest_times[name].append(seconds)
                if len(kept) == 2 and not np.array_equal(kept["now"], kept["other"]):
                    raise AssertionError(f"{case}: call {i} of {len(radii)} candidates differs")
            for name in total:
                times[name].append(total[name])
        row = dict(case=case, calls=len(calls), candidates=int(sum(len(call[1]) for call in calls)),
                   now_seconds=round(statistics.median(times["now"]), 5),
                   other_seconds=round(statistics.median(times["other"]), 5),
                   largest_call_candidates=len(calls[largest][1]),
                   largest_call_now_seconds=round(statistics.median(largest_times["now"]), 5),
                   largest_call_other_seconds=round(statistics.median(largest_times["other"]), 5), same_positions=True,
                   by_size=by_size(calls, {name: np.median(seconds, axis=0) for name, seconds in each.items()}))
        if hasattr(conflicts, "_greedy_on_grid"):
            row["grid_calls"] = sum(len(radii) > conflicts.FIRST_BLOCK and period is None
                                    and conflicts._greedy_on_grid(centers, radii, margin) is not None
                                    for centers, radii, margin, period, _ in calls)
        print(row, flush=True)
        rows.append(row)
    return rows


def by_size(calls, seconds) -> list:
    """Per size of call (:data:`SIZES`): how many calls, and each version's seconds
    (``seconds[name]`` (calls,), medians of the repeats) in all and the median call's."""
    import numpy as np

    sizes = np.array([len(call[1]) for call in calls])
    rows = []
    for low, high in zip(SIZES, [*SIZES[1:], None]):
        among = (sizes >= low) & (sizes < (high or np.inf))
        if among.any():
            rows.append(dict(candidates=f"{low}-{high - 1}" if high else f"{low}+", calls=int(among.sum()),
                             **{f"{name}_seconds": round(float(times[among].sum()), 5)
                                for name, times in seconds.items()},
                             **{f"{name}_median_call_us": round(float(np.median(times[among])) * 1e6, 1)
                                for name, times in seconds.items()}))
    return rows


#: A fresh process's first call of the check (3-D, 5,000 candidates): ``import numba`` and the call timed apart.
FIRST_CALL = """
import json, time
import numpy as np
started = time.perf_counter()
import numba
imported = time.perf_counter() - started
from ndpack.drivers.greedy.conflicts import disjoint_greedy
rng = np.random.default_rng(0)
centers, radii = rng.random((5000, 3)), np.sort(0.006 + 0.002 * rng.random(5000))[::-1]
started = time.perf_counter()
disjoint_greedy(centers, radii, 1e-9)
seconds = time.perf_counter() - started
print(json.dumps(dict(import_numba_seconds=round(imported, 3), first_call_seconds=round(seconds, 3))))
"""


def compile_times(repo: str) -> dict:
    """``repo``'s first call in a fresh process with an empty Numba cache (compiling), then in
    another with that cache (loading it)."""
    import tempfile

    sys.path.insert(0, str(HERE))
    from _common import last_json, run_with

    with tempfile.TemporaryDirectory() as cache:
        cold = last_json(run_with(repo, ["-c", FIRST_CALL], env={"NUMBA_CACHE_DIR": cache}))
        warm = last_json(run_with(repo, ["-c", FIRST_CALL], env={"NUMBA_CACHE_DIR": cache}))
    row = dict(compiling=cold, cached=warm)
    print(row, flush=True)
    return row


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--cases", nargs="+", default=DEFAULT_CASES, choices=list(PACKINGS))
    parser.add_argument("--modes", nargs="+", default=["fast", "faithful"])
    parser.add_argument("--repo", default=str(HERE.parent), help="the checkout whose ndpack packs (default: this one)")
    parser.add_argument("--against", help="another checkout whose disjoint_greedy to time on the same inputs")
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--slow", type=float, default=5.0, help="time a call this slow (seconds) once only")
    parser.add_argument("--packings-only", action="store_true")
    parser.add_argument("--compile", action="store_true", help="time the first call, compiling and from the cache")
    parser.add_argument("--out", help="write the results here as JSON")
    parser.add_argument("--one", nargs=2, metavar=("CASE", "MODE"), help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.one:
        print(json.dumps(one(*args.one)))
        return
    result = dict(repo=args.repo, cases={case: PACKINGS[case] for case in args.cases},
                  packings=packings(args.repo, args.cases, args.modes))
    if args.compile:
        result.update(first_call=compile_times(args.repo))
    if args.against and not args.packings_only:
        result.update(against=args.against, same_inputs=same_inputs(args.against, args.cases, args.repeats, args.slow))
    if args.out:
        sys.path.insert(0, str(HERE))
        from _common import machine_info, write_json

        write_json(Path(args.out), dict(machine=machine_info(), **result))


if __name__ == "__main__":
    main()
