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
its rounds (each costs a few shared-memory synchronisations more than a node). The walks are
:data:`WALK`, compiled with the mesh program's own functions; all must agree on the distance.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

import ndpack as nd
from ndpack.kernels.compiled import compiled_program

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import machine_info, write_json

LANES = (8, 16, 32, 64)
#: The emulated stack's room (the GPU's holds 1,024 and then walks alone; the deepest seen is 542).
STACK = 8192

#: The walk of ndpack.backends.warp_lanes with ``lanes`` lanes, in Numba's dialect of a mesh
#: program's functions (its own ``box_squared_distance`` and ``element_query``): each round the
#: lanes pop up to one node each, test it against the best distance as the round began, push the
#: far children, then the near ones (which so pop first), and share the best. Returns (the best
#: squared distance, rounds, the deepest stack). With one lane a round is a node of the serial
#: walk, ``nearest_element``'s. ``bench/work_model.py`` counts the GPU's rounds with it too.
WALK = f"""
def lanes_walk(q, prm, o, limit, lanes):
    nodes = int(prm[o + 7])
    elements = int(prm[o + 8])
    stride = int(prm[o + 10])
    size = 2 * D + 2
    pending = np.empty({STACK}, np.int64)
    children = np.empty((lanes, 2), np.int64)
    pending[0] = 0
    top = 1
    best = limit
    rounds = 0
    deepest = 1
    while top > 0:
        rounds += 1
        popped = min(lanes, top)
        shared = best
        for j in range(popped):
            node = pending[top - 1 - j]
            children[j, 0] = -1
            children[j, 1] = -1
            b = nodes + size * node
            if box_squared_distance(q, prm, b) < shared:
                count = int(prm[b + 2 * D + 1])
                if count > 0:
                    start = int(prm[b + 2 * D])
                    for k in range(start, start + count):
                        best = min(best, element_query(q, prm, elements + stride * k, 0))
                else:
                    left = node + 1
                    right = int(prm[b + 2 * D])
                    near_left = box_squared_distance(q, prm, nodes + size * left)
                    near_right = box_squared_distance(q, prm, nodes + size * right)
                    if near_left <= near_right:
                        far, near, far_d, near_d = right, left, near_right, near_left
                    else:
                        far, near, far_d, near_d = left, right, near_left, near_right
                    if far_d < shared:
                        children[j, 0] = far
                    if near_d < shared:
                        children[j, 1] = near
        top -= popped
        for slot in range(2):
            for j in range(popped):
                if children[j, slot] >= 0:
                    if top == {STACK}:
                        raise ValueError("the emulated walk's stack is full: raise STACK")
                    pending[top] = children[j, slot]
                    top += 1
        deepest = max(deepest, top)
    return best, float(rounds), float(deepest)
"""


def walk_of(program):
    """``lanes_walk`` (:data:`WALK`) compiled with a mesh ``program``'s functions, by Numba."""
    from ndpack.backends import numba_common
    from ndpack.kernels import compile as kernel_compile

    return kernel_compile.numba_namespace(program, "cpu", WALK, numba_common._jit)["lanes_walk"]


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--mesh", default="../shared/data/meshes/armadillo.obj")
    parser.add_argument("--count", type=int, default=3000)
    parser.add_argument("--out", default=None)
    args = parser.parse_args()
    shape = nd.TriangleMesh.load(args.mesh)
    flat = compiled_program(shape)
    walk = walk_of(flat.program)
    prm = np.asarray(flat.params, dtype=np.float64)
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
            exact = walk(q, prm, o, 1e30, 1)[0]
            limit = exact * 1.000001 + 1e-30 if limit_name != "none" else 1e30
            found, nodes, _ = walk(q, prm, o, limit, 1)  # one lane: the serial walk
            row = [nodes]
            for lanes in LANES:
                shared, rounds, deepest = walk(q, prm, o, limit, lanes)
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
