"""Where the fast round's polished prototypes come from, and what polishing ahead would cost.

    python bench/polish_origin.py --mesh armadillo.obj --count 30000 --below 0.8 0.64 0.6

A fast round polishes the candidates it chooses before they become spheres, in launches of
their own (on a GPU each costs its slowest prototype's 60 steps, however few prototypes it
holds). This counts, over one packing (numba, fast mode):

- the prototypes polished, and how many of them had moved in the last round's re-convergence
  (touched by its spheres, or new in split cells): those a polish chained to that move would
  reach;
- their clearance against the last round's frontier (quantiles);
- for each fraction ``q`` of ``--below``: the unpolished prototypes with clearance at least ``q``
  times the last frontier, summed over the rounds: the work of polishing ahead, in the last
  round's launch, everything that the next window could hold.

It watches the driver by wrapping ``RunState.reconverge``, ``RunState.polish`` and
``Fast.choose`` (a measurement, not an interface); the packing itself is unchanged.
"""

from __future__ import annotations

import argparse

import numpy as np

import ndpack as nd
from ndpack.drivers.greedy import protosphere, rounds


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--mesh", default=None, help="a mesh file; default the unit cube")
    parser.add_argument("--count", type=int, default=30_000)
    parser.add_argument("--below", type=float, nargs="+", default=[0.8, 0.64, 0.6])
    args = parser.parse_args()
    shape = nd.TriangleMesh.load(args.mesh) if args.mesh else nd.Box(np.zeros(3), np.ones(3))

    moved, polished, ahead = set(), [], {q: 0 for q in args.below}
    frontier = [np.nan]  # the last round's, none before the first
    reconverge, polish, choose = protosphere.RunState.reconverge, protosphere.RunState.polish, rounds.Fast.choose

    def watched_reconverge(state, ids, *rest, **options):
        moved.update(ids.tolist())
        return reconverge(state, ids, *rest, **options)

    def watched_polish(state, ids):
        clearance = state.prototypes.gather(ids)[1]
        polished.append((len(ids), sum(i in moved for i in ids.tolist()), clearance / frontier[0]))
        return polish(state, ids)

    def watched_choose(strategy, state, *rest):
        if np.isfinite(strategy.frontier):
            for q in args.below:
                ahead[q] += len(state.prototypes.select(low=q * strategy.frontier, unpolished=True)[0])
        chosen = choose(strategy, state, *rest)
        frontier[0] = strategy.frontier
        moved.clear()
        return chosen

    protosphere.RunState.reconverge, protosphere.RunState.polish = watched_reconverge, watched_polish
    rounds.Fast.choose = watched_choose
    packing = nd.pack(shape, args.count, backend="numba", mode="fast")
    total = sum(count for count, _, _ in polished)
    from_moves = sum(hits for _, hits, _ in polished)
    ratios = np.concatenate([ratio for _, _, ratio in polished])
    ratios = ratios[np.isfinite(ratios)]
    print(f"{len(packing)} spheres, {len(packing.stats.count)} rounds, {len(polished)} polish launches")
    print(f"polished {total}; moved in the last round's re-convergence {from_moves} ({from_moves / total:.1%})")
    quantiles = np.quantile(ratios, [0, 0.01, 0.1, 0.5, 0.9, 1])
    print("clearance / last frontier, quantiles 0 1 10 50 90 100%:", " ".join(f"{q:.3f}" for q in quantiles))
    for q, count in ahead.items():
        print(f"unpolished above {q:g} x the last frontier, summed over rounds: {count} "
              f"({count / total:.1f}x polished)")


if __name__ == "__main__":
    main()
