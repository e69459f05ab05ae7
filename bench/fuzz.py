"""Fuzzing ndpack: random shape trees in 2-D to 6-D, packed small on each backend and judged
against an independent reference (issue 21; the generator and the check are tests/fuzz_*.py).

Each run names a backend, a mode and the share of the trees it packs (``numpy:fast:1`` packs
every tree); the CUDA simulator (``numba-cuda``) packs a few trees at most 4 spheres on a grid
of 4 cells, since it is slow. Cases run one at a time in a worker process: a case that outlives
``--timeout`` seconds (compiles included) is killed and counted as a timeout, and ``nd.pack``'s
own ``time_budget`` stops slow ones first. Writes every case's record to ``--out`` and prints
a markdown table per backend and mode.

    nice -n 10 python bench/fuzz.py --trees 1000 --seed 0 --out bench/results/fuzz_2core.json
"""

from __future__ import annotations

import argparse
import collections
import multiprocessing
import os
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
# This checkout's ndpack and the generator beside its tests, whatever is installed.
sys.path[:0] = [str(ROOT), str(ROOT / "tests"), str(ROOT / "bench")]

import numpy as np  # noqa: E402
from tqdm import tqdm  # noqa: E402

from _common import machine_info, write_json  # noqa: E402
from fuzz_check import OUTCOMES  # noqa: E402

DEFAULT_RUNS = ["numpy:fast:1", "numpy:faithful:1", "numba:fast:0.35", "numba:faithful:0.35", "warp:fast:0.35",
                "warp:faithful:0.35", "numba-cuda:fast:0.008"]
#: Each backend's place in the seed of the draw that picks its trees.
BACKENDS = ("numba", "numba-cuda", "numpy", "warp")
#: The simulator's cases: spheres, cells along the longest side, time budget (seconds).
SIMULATOR_N, SIMULATOR_GRID, SIMULATOR_BUDGET = 4, 4, 120.0


def _worker(connection, simulator: bool):
    """Run the cases sent down ``connection`` until None arrives."""
    if simulator:
        os.environ["NUMBA_ENABLE_CUDASIM"] = "1"
    import fuzz_check
    import fuzz_shapes

    while (job := connection.recv()) is not None:
        seed, index, backend, mode, budget, extended = job
        case = fuzz_shapes.case(seed, index, extended=extended)
        if simulator:
            case.n, case.grid, budget = min(case.n, SIMULATOR_N), SIMULATOR_GRID, SIMULATOR_BUDGET
        connection.send(fuzz_check.run_case(case, backend, mode, budget))


class Worker:
    """A worker process, restarted after a case that had to be killed."""

    def __init__(self, simulator: bool):
        self.simulator, self.process = simulator, None

    def run(self, job, timeout: float) -> dict | None:
        if self.process is None:
            context = multiprocessing.get_context("spawn")
            self.connection, child = context.Pipe()
            self.process = context.Process(target=_worker, args=(child, self.simulator), daemon=True)
            self.process.start()
        self.connection.send(job)
        if self.connection.poll(timeout):
            try:
                return self.connection.recv()
            except EOFError:  # the worker died (a segfault, memory): a crash of that case
                self.stop()
                return {"outcome": "crash", "error": "worker died", "message": "the worker process exited"}
        self.stop()
        return None

    def stop(self):
        if self.process is not None:
            self.process.kill()
            self.process.join()
            self.process = None


def jobs(trees, seed: int, runs: list[str], budget: float, extended: bool = True):
    """(seed, index, backend, mode, budget, extended) for each case, tree by tree (``trees``: the
    indices; ``extended``: with plug-ins and open meshes, see tests/fuzz_shapes.py)."""
    plans = []
    for run in runs:
        backend, mode, share = run.split(":")
        plans.append((backend, mode, float(share)))
    for index in trees:
        for number, (backend, mode, share) in enumerate(plans):
            # One draw per tree and backend, so that a backend's modes pack the same trees.
            draw = np.random.default_rng([seed, index, 1 + BACKENDS.index(backend)]).random()
            if draw < share:
                yield seed, index, backend, mode, budget, extended


def table(records: list[dict]) -> str:
    """Markdown: per backend and mode, how many cases ended in each outcome."""
    groups = collections.defaultdict(list)
    for record in records:
        groups[(record["backend"], record["mode"])].append(record)
    lines = ["| backend | mode | cases | " + " | ".join(OUTCOMES) + " | median s | max s |",
             "|---" * (len(OUTCOMES) + 5) + "|"]
    for (backend, mode), group in sorted(groups.items()):
        counts = collections.Counter(r["outcome"] for r in group)
        seconds = [r["seconds"] for r in group]
        lines.append(f"| {backend} | {mode} | {len(group)} | " + " | ".join(str(counts[o]) for o in OUTCOMES)
                     + f" | {np.median(seconds):.2f} | {max(seconds):.1f} |")
    return "\n".join(lines)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--trees", type=int, default=1000)
    parser.add_argument("--only", type=int, nargs="+", help="run only these trees (to re-run failures)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--runs", nargs="+", default=DEFAULT_RUNS, help="backend:mode:share of the trees")
    parser.add_argument("--budget", type=float, default=20.0, help="nd.pack's time_budget per case (seconds)")
    parser.add_argument("--timeout", type=float, default=240.0, help="kill a case after this many seconds")
    parser.add_argument("--out", type=Path, default=ROOT / "bench" / "results" / "fuzz.json")
    parser.add_argument("--no-extended", dest="extended", action="store_false",
                        help="no plug-ins or open meshes: the trees as drawn before they were added")
    args = parser.parse_args(argv)

    import ndpack

    todo = list(jobs(args.only or range(args.trees), args.seed, args.runs, args.budget, args.extended))
    workers = {False: Worker(False), True: Worker(True)}
    records, started = [], time.perf_counter()
    try:
        for job in tqdm(todo, unit="case", dynamic_ncols=True):
            seed, index, backend, mode, _, _ = job
            record = workers[backend == "numba-cuda"].run(job, args.timeout)
            if record is None:
                record = {"outcome": "timeout", "seconds": args.timeout, "killed": True}
            record.update(seed=seed, index=index, backend=backend, mode=mode)
            record.setdefault("seconds", 0.0)
            records.append(record)
            if record["outcome"] not in ("valid", "clear error"):
                tqdm.write(f"{backend} {mode} tree {index}: {record['outcome']}: {record.get('error', '')} "
                           f"{record.get('message', '')[:200]}")
    finally:
        for worker in workers.values():
            worker.stop()
        summary = table(records) if records else ""
        write_json(args.out, {
            "command": "python bench/fuzz.py " + " ".join(argv if argv is not None else sys.argv[1:]),
            "machine": machine_info(), "ndpack_path": ndpack.__file__, "versions": versions(),
            "trees": args.trees, "only": args.only, "seed": args.seed, "runs": args.runs, "budget": args.budget,
            "timeout": args.timeout,
            "extended": args.extended,
            "wall_seconds": round(time.perf_counter() - started, 1), "summary": summary, "records": records,
        })
    print(summary)
    print(f"\n{len(records)} cases of {args.trees} trees in {time.perf_counter() - started:.0f} s; "
          f"records in {args.out}")


def versions() -> dict:
    """Versions of the libraries the cases use."""
    from importlib.metadata import PackageNotFoundError, version

    found = {}
    for name in ("numpy", "scipy", "numba", "numba-cuda", "warp-lang", "trimesh", "manifold3d", "shapely", "libigl"):
        try:
            found[name] = version(name)
        except PackageNotFoundError:
            found[name] = None
    return found


if __name__ == "__main__":
    main()
