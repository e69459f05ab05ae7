"""``nd.cover`` at 1% of the diagonal on two commits, in one run: the time a change saved (issue 23).

Each commit is checked out in a temporary git worktree and timed in its own process (so that
each imports its own ndpack): a warm-up covering, then ``--repeats`` timed ones of each mesh; the
median is reported. The kernels each commit compiles are cached on disk as usual.

    python bench/cover_before_after.py --before 535e0df --out bench/results/cover_before_after_2core.json
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
MESH_DIR = ROOT.parent / "shared" / "data" / "meshes"

CHILD = r"""
import json, sys, time
import numpy as np
sys.path.insert(0, sys.argv[1])
import ndpack as nd
out = {}
for name in sys.argv[4:]:
    mesh = nd.TriangleMesh.load(f"{sys.argv[2]}/{name}.obj")
    tolerance = 0.01 * mesh.diagonal
    nd.cover(mesh, protrusion=tolerance, progress=False)
    times = []
    for _ in range(int(sys.argv[3])):
        started = time.perf_counter()
        covering = nd.cover(mesh, protrusion=tolerance, progress=False)
        times.append(time.perf_counter() - started)
    out[name] = dict(times=times, median=float(np.median(times)), spheres=len(covering),
                     covered=bool(covering.report.covered))
print(json.dumps(out))
"""


def time_checkout(root: Path, meshes, repeats: int) -> dict:
    done = subprocess.run([sys.executable, "-c", CHILD, str(root), str(MESH_DIR), str(repeats), *meshes],
                          capture_output=True, text=True, cwd=tempfile.gettempdir(), check=True)
    return json.loads(done.stdout.strip().splitlines()[-1])


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--before", required=True, help="the earlier commit")
    parser.add_argument("--meshes", nargs="+", default=["cow", "armadillo"])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--out", type=Path, required=True)
    args = parser.parse_args(argv)
    head = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True, cwd=ROOT,
                          check=True).stdout.strip()
    rows = {}
    with tempfile.TemporaryDirectory() as folder:
        worktree = Path(folder) / "before"
        subprocess.run(["git", "worktree", "add", "--detach", "-q", str(worktree), args.before], cwd=ROOT, check=True)
        try:
            for label, root in ((args.before, worktree), (head, ROOT)):
                rows[label] = time_checkout(root, args.meshes, args.repeats)
                print(label, json.dumps(rows[label]), flush=True)
        finally:
            subprocess.run(["git", "worktree", "remove", "--force", str(worktree)], cwd=ROOT, check=True)
    args.out.write_text(json.dumps(rows, indent=1))
    for name in args.meshes:
        before, after = rows[args.before][name]["median"], rows[head][name]["median"]
        print(f"{name}: {before:.1f} s at {args.before}, {after:.1f} s at {head} ({before / after:.1f}x)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
