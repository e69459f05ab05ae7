"""Packings at scale in 3-D to 5-D, this checkout's code against an earlier commit's, in one run.

    python bench/index_speed.py --before e557e8c~1 --repeats 3 \\
        --out bench/results/index_speed_2core_issue47.json [--load 2] [--cases 5d 4d armadillo]
        [--backend warp] [--mode fast]
    python bench/index_speed.py --queries 5 --at 60000 --before e557e8c~1

The first form packs each case (``--backend``, numba by default; ``--mode``, auto by default;
seed 0) in a fresh process per run, with this checkout and with each of ``--before`` (a commit,
checked out in a temporary worktree, or a folder that holds a checkout), interleaved,
``--repeats`` rounds; a warm-up packing in the same process compiles (or loads) the kernels
first. Every packing is verified; each version's sphere hashes are recorded. With ``--load N``,
N spinning processes run beside the whole sweep (bench/_load.py).

The second form (``--queries DIM``) times the sphere index alone: it records the neighbour
queries (``near_spheres``) of the ``DIM``-D ball with a hole once its packing passes ``--at``
spheres, then times those same queries (median of 3, after one untimed call) with each version's
kernels, and checks that both versions' tables are equal.
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

from _common import last_json, load_average, machine_info, run_with, write_json
from _load import busy

ROOT = Path(__file__).resolve().parent.parent
MESH = ROOT.parent / "shared" / "data" / "meshes" / "armadillo.obj"

#: name -> (label, shape expression, count); numpy is ``np`` and ndpack ``nd`` where they run.
CASES = {
    "5d": ("5-D ball with a hole, 100,000", "nd.Ball(np.zeros(5), 1.0) - nd.Ball(np.zeros(5), 0.5)", 100_000),
    "4d": ("4-D ball with a hole, 100,000", "nd.Ball(np.zeros(4), 1.0) - nd.Ball(np.zeros(4), 0.5)", 100_000),
    # The hole off centre, as in bench/scale.py's nd case and bench/threads.py.
    "5d-offset": ("5-D ball with an off-centre hole, 100,000",
                  "nd.Ball(np.zeros(5), 1.0) - nd.Ball(np.full(5, 0.3), 0.4)", 100_000),
    "4d-offset": ("4-D ball with an off-centre hole, 100,000",
                  "nd.Ball(np.zeros(4), 1.0) - nd.Ball(np.full(4, 0.3), 0.4)", 100_000),
    "armadillo": ("armadillo, 100,000", f"nd.TriangleMesh.load({str(MESH)!r})", 100_000),
}

#: One timed packing, printed as JSON on the last line.
PACK = """
import hashlib, json, time
import numpy as np
import ndpack as nd
shape = {shape}
nd.pack(shape, n=200, mode="fast", backend={backend!r}, progress=False)  # compile or load the kernels
started = time.perf_counter()
packing = nd.pack(shape, n={count}, mode={mode!r}, backend={backend!r}, seed=0, progress=False)
seconds = time.perf_counter() - started
digest = hashlib.sha256(packing.centers.tobytes() + packing.radii.tobytes()).hexdigest()[:16]
print(json.dumps(dict(seconds=seconds, spheres=len(packing), fill=float(packing.fill),
                      verified=bool(packing.verify().ok), hash=digest)))
"""

#: Record the near_spheres calls of a packing past ``at`` spheres (three calls of > 2,000 boxes).
RECORD = """
import pickle, numpy as np, ndpack as nd
from ndpack.backends.numba_backend import NumbaBackend
dim, at = {dim}, {at}
original, calls = NumbaBackend.near_spheres, []
class Enough(Exception):
    pass
def recording(self, lower, upper, reach, centers, radii, return_bound=False):
    if len(radii) >= at and len(lower) > 2000:
        calls.append([np.array(a) for a in (lower, upper, reach, centers, radii)])
        if len(calls) == 3:
            raise Enough
    return original(self, lower, upper, reach, centers, radii, return_bound)
NumbaBackend.near_spheres = recording
try:
    nd.pack(nd.Ball(np.zeros(dim), 1.0) - nd.Ball(np.zeros(dim), 0.5), n=4 * at, mode="auto", backend="numba",
            seed=0, progress=False)
except Enough:
    pass
pickle.dump(calls, open({path!r}, "wb"))
"""

#: Time the recorded calls with one version's kernels.
QUERY = """
import json, pickle, statistics, time, zlib
from ndpack.backends.numba_backend import NumbaBackend
rows = []
for lower, upper, reach, centers, radii in pickle.load(open({path!r}, "rb")):
    backend = NumbaBackend()
    backend.near_spheres(lower, upper, reach, centers, radii)  # compile, index, table width
    times = []
    for _ in range(3):
        started = time.perf_counter()
        table, bound = backend.near_spheres(lower, upper, reach, centers, radii, return_bound=True)
        times.append(time.perf_counter() - started)
    rows.append(dict(boxes=len(lower), spheres=len(radii), seconds=statistics.median(times),
                     mean_row=float((table < len(radii)).sum(axis=1).mean()),
                     table=zlib.crc32(table.tobytes()), bound=zlib.crc32(bound.tobytes())))
print(json.dumps(rows))
"""


def run(code: str, checkout: Path) -> dict:
    """Run ``code`` with ``checkout``'s ndpack; its last printed line, as JSON."""
    return last_json(run_with(checkout, ["-c", code]))


def worktree(revision: str, folder: Path) -> Path:
    """``revision`` checked out (detached) in ``folder``."""
    subprocess.run(["git", "-C", str(ROOT), "worktree", "add", "--detach", "-f", str(folder), revision],
                   check=True, capture_output=True)
    return folder


def packings(args, versions) -> dict:
    results = {name: {version: [] for version in versions} for name in args.cases}
    for repeat in range(args.repeats):
        for name in args.cases:
            label, shape, count = CASES[name]
            for version, checkout in versions.items():
                result = run(PACK.format(shape=shape, count=count, backend=args.backend, mode=args.mode), checkout)
                results[name][version].append(result)
                print(f"{label} [{version}, run {repeat + 1}]: {result}", flush=True)
    rows = []
    for name in args.cases:
        row = dict(case=CASES[name][0], backend=args.backend, mode=args.mode)
        for version in versions:
            runs = results[name][version]
            row[version] = dict(median_s=statistics.median(r["seconds"] for r in runs),
                                seconds=[r["seconds"] for r in runs], fill=runs[0]["fill"],
                                spheres=runs[0]["spheres"], verified=all(r["verified"] for r in runs),
                                hashes=sorted({r["hash"] for r in runs}))
        for version in versions:
            if version != "after":
                row[f"speedup_over_{version}"] = row[version]["median_s"] / row["after"]["median_s"]
        rows.append(row)
    return dict(rows=rows)


def queries(args, versions) -> dict:
    path = str(Path(tempfile.mkdtemp()) / "calls.pkl")
    done = run_with(ROOT, ["-c", RECORD.format(dim=args.queries, at=args.at, path=path)])
    if done.returncode:
        raise RuntimeError(done.stderr[-3000:])
    timed = {version: run(QUERY.format(path=path), checkout) for version, checkout in versions.items()}
    rows = []
    for call, after in enumerate(timed["after"]):
        row = dict(call=call, boxes=after["boxes"], spheres=after["spheres"], mean_row=after["mean_row"],
                   after_s=after["seconds"])
        for version in [v for v in timed if v != "after"][:1]:
            before = timed[version][call]
            row.update(before_s=before["seconds"], speedup=before["seconds"] / after["seconds"],
                       same_tables=before["table"] == after["table"] and before["bound"] == after["bound"])
        rows.append(row)
        print(row, flush=True)
    return dict(dim=args.queries, at=args.at, rows=rows)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--before", nargs="+", default=[],
                        help="earlier commits (or folders holding one's checkout) to compare with, in the same run")
    parser.add_argument("--mode", default="auto", help="the packings' mode (an earlier commit's auto may differ)")
    parser.add_argument("--cases", nargs="+", default=["5d", "4d", "armadillo"], choices=list(CASES))
    parser.add_argument("--backend", default="numba", help="the packings' backend (numba, warp, numba-cuda)")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--load", type=int, default=0, help="spinning processes beside the runs")
    parser.add_argument("--queries", type=int, metavar="DIM", help="time the sphere index's queries alone")
    parser.add_argument("--at", type=int, default=60_000, help="spheres before the queries are recorded")
    parser.add_argument("--out", type=Path)
    args = parser.parse_args()
    versions = {"after": ROOT}
    with tempfile.TemporaryDirectory() as scratch:
        made = []
        for revision in args.before:
            if Path(revision).is_dir():
                versions[Path(revision).name] = Path(revision).resolve()
            else:
                versions[revision] = worktree(revision, Path(scratch) / f"before{len(made)}")
                made.append(versions[revision])
        try:
            with busy(args.load):
                load = load_average()
                result = queries(args, versions) if args.queries else packings(args, versions)
        finally:
            for folder in made:
                subprocess.run(["git", "-C", str(ROOT), "worktree", "remove", "--force", str(folder)],
                               capture_output=True)
    result.update(machine=machine_info(), load_processes=args.load, load_average_start=load,
                  versions={name: str(path) for name, path in versions.items()},
                  command="python bench/index_speed.py " + " ".join(sys.argv[1:]))
    print(json.dumps(result["rows"], indent=1))
    if args.out:
        write_json(args.out, result)


if __name__ == "__main__":
    main()
