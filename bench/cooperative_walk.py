"""How much a cooperative tree walk shortens a nearest-element query's chain, counted on the CPU.

    python bench/cooperative_walk.py [--mesh ../shared/data/meshes/armadillo.obj] [--count 3000]
        [--out bench/results/cooperative_walk_2core_armadillo.json]

The query points are the centres of a fast-mode packing of ``--count`` spheres (numba, seed 0):
points near the medial axis, where the walks are longest. For each, the serial walk of
``nearest_element`` (:mod:`ndpack.meshes.kernels`) is counted in nodes visited, and the walk of
:mod:`ndpack.backends.warp_lanes` in rounds (each lane pops at most one node a round; children are
pushed nearer last; the best distance is shared at the end of each round) for 8 to 64 lanes, with
the limit a converge step has (the last step's element: the distance itself, widened by 1e-6) and
with none (a prototype's first evaluation). A GPU thread's chain is about its nodes; a block's,
its rounds (each costs a few shared-memory synchronisations more than a node). Both walks are
re-implemented here in plain Numba over the same parameter block, and must agree on the distance.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numba
import numpy as np

import ndpack as nd
from ndpack.kernels.compiled import compiled_program

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import machine_info, write_json

LANES = (8, 16, 32, 64)


@numba.njit(cache=True)
def _triangle_squared(q, prm, t):
    """Squared distance from q to the triangle at t (Ericson's regions)."""
    a, b, c = prm[t:t + 3], prm[t + 3:t + 6], prm[t + 6:t + 9]
    ab, ac, ap = b - a, c - a, q - a
    d1, d2 = ab @ ap, ac @ ap
    if d1 <= 0 and d2 <= 0:
        return ap @ ap
    bp = q - b
    d3, d4 = ab @ bp, ac @ bp
    if d3 >= 0 and d4 <= d3:
        return bp @ bp
    vc = d1 * d4 - d3 * d2
    if vc <= 0 and d1 >= 0 and d3 <= 0:
        r = ap - d1 / (d1 - d3) * ab
        return r @ r
    cp = q - c
    d5, d6 = ab @ cp, ac @ cp
    if d6 >= 0 and d5 <= d6:
        return cp @ cp
    vb = d5 * d2 - d1 * d6
    if vb <= 0 and d2 >= 0 and d6 <= 0:
        r = ap - d2 / (d2 - d6) * ac
        return r @ r
    va = d3 * d6 - d5 * d4
    if va <= 0 and d4 - d3 >= 0 and d5 - d6 >= 0:
        r = bp - (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b)
        return r @ r
    den = 1.0 / (va + vb + vc)
    r = ap - ab * (vb * den) - ac * (vc * den)
    return r @ r


@numba.njit(cache=True)
def _box_squared(q, prm, b):
    s = 0.0
    for i in range(3):
        t = max(prm[b + i] - q[i], q[i] - prm[b + 3 + i], 0.0)
        s += t * t
    return s


@numba.njit(cache=True)
def _expand(q, prm, o, node, best, out):
    """Test ``node`` against ``best``: out = (best, found, far child, near child), -1 where none."""
    nodes, elements, stride = int(prm[o + 7]), int(prm[o + 8]), int(prm[o + 10])
    b = nodes + 8 * node
    out[0], out[1], out[2], out[3] = best, -1.0, -1.0, -1.0
    if _box_squared(q, prm, b) >= best:
        return
    if int(prm[b + 7]) > 0:
        start = int(prm[b + 6])
        for k in range(start, start + int(prm[b + 7])):
            d = _triangle_squared(q, prm, elements + stride * k)
            if d < out[0]:
                out[0], out[1] = d, k
        return
    left, right = node + 1, int(prm[b + 6])
    near_left, near_right = _box_squared(q, prm, nodes + 8 * left), _box_squared(q, prm, nodes + 8 * right)
    first, second = (right, left) if near_left <= near_right else (left, right)
    near_first, near_second = (near_right, near_left) if near_left <= near_right else (near_left, near_right)
    if near_first < best:
        out[2] = first
    if near_second < best:
        out[3] = second


@numba.njit(cache=True)
def serial(q, prm, o, limit):
    """(best squared distance, nodes visited) of the serial walk."""
    best, visited, top = limit, 0, 1
    pending = np.zeros(256, np.int64)
    out = np.zeros(4)
    while top > 0:
        top -= 1
        visited += 1
        _expand(q, prm, o, pending[top], best, out)
        best = out[0]
        for slot in (2, 3):
            if out[slot] >= 0:
                pending[top] = int(out[slot])
                top += 1
    return best, visited


@numba.njit(cache=True)
def cooperative(q, prm, o, limit, lanes):
    """(best squared distance, rounds, deepest stack) of the walk of ``lanes`` lanes."""
    best, rounds, deepest, top = limit, 0, 1, 1
    pending = np.zeros(1 << 16, np.int64)
    children = np.zeros((lanes, 2), np.int64)
    out = np.zeros(4)
    while top > 0:
        rounds += 1
        popped = min(lanes, top)
        shared = best
        for j in range(popped):
            _expand(q, prm, o, pending[top - 1 - j], shared, out)
            best = min(best, out[0])
            children[j, 0], children[j, 1] = out[2], out[3]
        top -= popped
        for slot in range(2):  # the far children first, then the near: near ones pop first
            for j in range(popped):
                if children[j, slot] >= 0:
                    pending[top] = children[j, slot]
                    top += 1
        deepest = max(deepest, top)
    return best, rounds, deepest


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--mesh", default="../shared/data/meshes/armadillo.obj")
    parser.add_argument("--count", type=int, default=3000)
    parser.add_argument("--out", default=None)
    args = parser.parse_args()
    shape = nd.TriangleMesh.load(args.mesh)
    prm = np.asarray(compiled_program(shape).params, dtype=np.float64)
    o = int(prm[1])
    if o < 0 or prm.size <= o + 10:
        raise SystemExit(f"{args.mesh} is not one mesh")
    scale, centre = prm[o + 2], prm[o + 3:o + 6]
    points = nd.pack(shape, args.count, mode="fast", backend="numba", seed=0, progress=False).centers
    result = dict(machine=machine_info(), mesh=args.mesh, points=len(points), lanes=list(LANES), limits={})
    for limit_name in ("last step's element", "none"):
        rows = []
        for x in points:
            q = (x - centre) / scale
            exact, _ = serial(q, prm, o, 1e30)
            limit = exact * 1.000001 + 1e-30 if limit_name != "none" else 1e30
            found, nodes = serial(q, prm, o, limit)
            row = [nodes]
            for lanes in LANES:
                shared, rounds, deepest = cooperative(q, prm, o, limit, lanes)
                if shared != found:
                    raise AssertionError(f"the walks disagree at {x}: {shared} against {found}")
                row += [rounds, deepest]
            rows.append(row)
        rows = np.array(rows, dtype=float)
        worst = rows[np.argmax(rows[:, 0])]
        summary = dict(serial_nodes_mean=rows[:, 0].mean(), serial_nodes_most=rows[:, 0].max())
        for k, lanes in enumerate(LANES):
            summary[f"{lanes}: rounds_mean"] = rows[:, 1 + 2 * k].mean()
            summary[f"{lanes}: rounds_most"] = rows[:, 1 + 2 * k].max()
            summary[f"{lanes}: rounds_at_worst_point"] = worst[1 + 2 * k]
            summary[f"{lanes}: deepest_stack"] = rows[:, 2 + 2 * k].max()
        result["limits"][limit_name] = summary
        print(f"limit: {limit_name}: serial nodes mean {summary['serial_nodes_mean']:.1f}, "
              f"most {summary['serial_nodes_most']:.0f}")
        for lanes in LANES:
            print(f"   {lanes:2d} lanes: rounds mean {summary[f'{lanes}: rounds_mean']:.1f}, most "
                  f"{summary[f'{lanes}: rounds_most']:.0f}, at the serial worst "
                  f"{summary[f'{lanes}: rounds_at_worst_point']:.0f}; deepest stack "
                  f"{summary[f'{lanes}: deepest_stack']:.0f}")
    if args.out:
        write_json(Path(args.out), result)


if __name__ == "__main__":
    main()
