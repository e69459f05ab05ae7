"""A cut through two beds of equal spheres in the periodic unit cube (docs/dem.md): the greedy
driver's (``nd.pack`` with equal radius bounds: one sphere after another in the largest gap, until
none fits) beside a dense random bed (``nd.pack_dense``, the same radius asked at a solid fraction
of 0.64: jammed where it cannot reach it). Seed 0, numba.

    python bench/dense_figure.py --out docs/img/dem-dense-cut.png
"""

from __future__ import annotations

import argparse

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

import ndpack as nd

RADIUS = 0.03


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", default="dem-dense-cut.png")
    args = parser.parse_args()
    cube = nd.Periodic(nd.Box(np.zeros(3), np.ones(3)))
    greedy = nd.pack(cube, n=100_000, min_radius=RADIUS, max_radius=RADIUS, seed=0, progress=False)
    dense = nd.pack_dense(cube, RADIUS, solid_fraction=0.64, seed=0, progress=False)
    figure, panels = plt.subplots(1, 2, figsize=(11.5, 5.2))
    for ax, packing, title in ((panels[0], greedy, "nd.pack (equal radii)"),
                               (panels[1], dense, "nd.pack_dense")):
        packing.plot(cube, ax=ax, axes=(0, 1), at=[0.5, 0.5, 0.5])
        ax.set_title(f"{title}: {len(packing):,} spheres, fill {packing.fill:.3f}", fontsize=9)
    figure.suptitle(f"Equal spheres (r = {RADIUS}) in the periodic unit cube, cut at z = 0.5", fontsize=11)
    figure.tight_layout()
    figure.savefig(args.out, dpi=110)
    print(f"wrote {args.out}: greedy {len(greedy)} spheres, fill {greedy.fill:.4f}; dense {len(dense)}, "
          f"fill {dense.fill:.4f}, scale {dense.params['scale']:.4f}")


if __name__ == "__main__":
    main()
