"""Your own shape, two ways: a NumPy plug-in and a compiled scalar plug-in of the same cross.

The shape is a 3-D cross: three rounded bars along the axes. A rounded box has an exact
distance; the distance of the union is the minimum of the bars', which is exact outside and a
lower bound inside (1-Lipschitz either way), so ``exact_outside=True``.

1. ``@nd.plugin``: a vectorised NumPy function of ``(n, 3)`` points. Runs on the numpy backend
   only (ndpack falls back to it by itself).
2. ``@nd.scalar_plugin``: a function of one point in ndpack's kernel language. ndpack prints it
   for Numba (CPU and CUDA) and Warp, so it packs on every backend. Written with ``D``, the
   same code is a cross of ``D`` bars in any dimension.

The script checks that the two agree and are 1-Lipschitz, packs both, verifies both, renders
them side by side (``cross.png``), saves the packings (``cross_numpy.npz``, ``cross_scalar.npz``)
and shows the error a function outside the kernel language gets.

    python examples/custom_plugin.py                       # 2,000 spheres each into ./out
    python examples/custom_plugin.py -n 200 --backend numpy --out /tmp/cross
"""

import argparse
import math
import time
from pathlib import Path

import numpy as np

import ndpack as nd
import ndpack.pictures

LENGTH, WIDTH, ROUND = 1.0, 0.3, 0.08  # half-length and half-width of a bar, radius of its edges
BOUNDS = [[-1.05] * 3, [1.05] * 3]


@nd.plugin(dim=3, bounds=BOUNDS, exact_outside=True)
def cross(p):
    """The cross as a vectorised NumPy function: (n, 3) points -> (n,) distances."""
    best = np.full(len(p), np.inf)
    for k in range(3):
        half = np.full(3, WIDTH - ROUND)
        half[k] = LENGTH - ROUND
        q = np.abs(p) - half  # a rounded box: the box shrunk by ROUND, then offset by ROUND
        box = np.linalg.norm(np.maximum(q, 0.0), axis=1) + np.minimum(q.max(axis=1), 0.0) - ROUND
        best = np.minimum(best, box)
    return best


@nd.scalar_plugin(dim=3, bounds=BOUNDS, params=[LENGTH, WIDTH, ROUND], exact_outside=True)
def cross_scalar(p, params):
    """The same cross for one point, in the kernel language (D is the dimension)."""
    best = 1e30  # no infinity in the kernel language: a large number
    for k in range(D):  # noqa: F821 - D is a constant of the kernel language
        outside = 0.0
        inside = -1e30
        for i in range(D):  # noqa: F821
            half = params[0] if i == k else params[1]
            q = abs(p[i]) - (half - params[2])
            outside += max(q, 0.0) ** 2
            inside = max(inside, q)
        best = min(best, math.sqrt(outside) + min(inside, 0.0) - params[2])
    return best


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("-n", "--count", type=int, default=2000, help="spheres per packing (default 2,000)")
    parser.add_argument("--backend", default=None,
                        help="backend of the scalar plug-in: numpy, numba, numba-cuda or warp "
                        "(default: the fastest here)")
    parser.add_argument("--out", default="out", help="output folder (default ./out)")
    args = parser.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)

    # 1. The two definitions agree, and both are 1-Lipschitz (checked on random pairs of points).
    points = np.random.default_rng(0).uniform(-1.05, 1.05, (20_000, 3))
    difference = np.abs(cross.distance(points) - cross_scalar.distance(points)).max()
    print(f"largest difference between the two definitions: {difference:.1e}")
    print(f"largest slope found: NumPy {cross.check_lipschitz():.4f}, scalar {cross_scalar.check_lipschitz():.4f}")

    # 2. Pack both. The NumPy plug-in runs on the numpy backend; the scalar one on any.
    packings = {}
    for name, shape, backend in (("numpy", cross, "numpy"), ("scalar", cross_scalar, args.backend)):
        started = time.perf_counter()
        packing = nd.pack(shape, n=args.count, mode="fast", seed=0, backend=backend)
        elapsed = time.perf_counter() - started
        report = packing.verify()
        print(f"{name:6s} plug-in: {len(packing):,} spheres, fill {packing.fill:.4f} +- {packing.fill_error:.4f}, "
              f"{elapsed:.1f} s ({packing.params['backend']} backend), valid: {report.ok}")
        packing.save(out / f"cross_{name}.npz")
        packings[name] = packing

    # 3. Pictures, side by side.
    picture = out / "cross.png"
    draw(packings, picture)
    for path in (picture, out / "cross_numpy.npz", out / "cross_scalar.npz"):
        print(f"wrote {path}")

    # 4. A function outside the kernel language is refused, with the line that is wrong.
    try:
        @nd.scalar_plugin(dim=3, bounds=BOUNDS)
        def bad(p, params):
            return np.linalg.norm([p[0], p[1], p[2]]) - 1.0

    except nd.KernelError as error:
        print(f"refused, as it should be: {error}")


def draw(packings, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    figure, axes = plt.subplots(1, len(packings), figsize=(5 * len(packings), 5.3))
    for ax, (name, packing) in zip(axes, packings.items()):
        ax.imshow(ndpack.pictures.render(packing, view=(30, 25), size=(600, 600)))
        ax.set_axis_off()
        ax.set_title(f"{name} plug-in: {len(packing):,} spheres, fill {packing.fill:.3f}")
    figure.tight_layout()
    figure.savefig(path, dpi=110)
    plt.close(figure)


if __name__ == "__main__":
    main()
