"""A 4-D ball with a hole, packed with 4-D spheres, and looked at through slices.

The shape is the unit 4-ball minus the ball of radius ``--hole`` (0.5) about the origin, built by
CSG. A packing in 4-D cannot be drawn whole; its slices can. A 4-ball of radius ``r`` whose
centre lies at distance ``h`` from a slice meets it in a ball of radius ``sqrt(r**2 - h**2)``, so:

- ``ball4d_slices.png``: 2-D slices (planes x0-x1) at x2 = x3 = 0, at x3 = 0.5, at x3 = 0.8:
  the hole shrinks and vanishes as the plane leaves the centre (``ndpack.pictures.plot``, ``at=``);
- ``ball4d_slice.svg``: the first of those, as a vector file (``ndpack.pictures.save_figure``);
- ``ball4d_3d.png``: the 3-D slices x3 = 0 and x3 = 0.6, shaded (``ndpack.pictures.render`` with
  ``at=``); each picture is framed to its own slice, which is smaller at x3 = 0.6;
- ``ball4d.npz``: the packing.

    python examples/ball_4d.py                          # 5,000 spheres into ./out
    python examples/ball_4d.py -n 300 --backend numpy --out /tmp/ball4d
"""

import argparse
import time
from pathlib import Path

import numpy as np

import ndpack as nd
import ndpack.pictures


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("-n", "--count", type=int, default=5000, help="spheres to pack (default 5,000)")
    parser.add_argument("--hole", type=float, default=0.5, help="radius of the hole (default 0.5; 0 for none)")
    parser.add_argument("--backend", default=None, help="numpy, numba, numba-cuda or warp (default: the fastest here)")
    parser.add_argument("--out", default="out", help="output folder (default ./out)")
    args = parser.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)

    shape = nd.Ball(np.zeros(4), 1.0)
    if args.hole > 0:
        shape = shape - nd.Ball(np.zeros(4), args.hole)
    started = time.perf_counter()
    packing = nd.pack(shape, n=args.count, mode="fast", seed=0, backend=args.backend)
    elapsed = time.perf_counter() - started
    report = packing.verify()
    print(f"{shape!r}")
    print(f"{len(packing):,} spheres in 4-D, fill {packing.fill:.4f}, radii {packing.radii.min():.4f} to "
          f"{packing.radii.max():.4f}, {elapsed:.1f} s ({packing.params['backend']} backend), valid: {report.ok}")

    files = [slices(packing, out / "ball4d_slices.png", heights=(0.0, 0.5, 0.8))]
    files.append(ndpack.pictures.save_figure(packing, out / "ball4d_slice.svg", at=[0, 0, 0, 0]))
    files.append(renders(packing, out / "ball4d_3d.png", heights=(0.0, 0.6)))
    files.append(packing.save(out / "ball4d.npz"))
    for path in files:
        print(f"wrote {path}")


def slices(packing, path, heights):
    """2-D slices x0-x1 through (0, 0, 0, h) for each h, side by side."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    figure, axes = plt.subplots(1, len(heights), figsize=(5.2 * len(heights), 4.6))
    for ax, height in zip(np.atleast_1d(axes), heights):
        ndpack.pictures.plot(packing, ax=ax, at=[0, 0, 0, height])
        ax.set_title(f"slice x2 = 0, x3 = {height}")
    figure.tight_layout()
    figure.savefig(path, dpi=120)
    plt.close(figure)
    return path


def renders(packing, path, heights):
    """Shaded 3-D slices x0-x1-x2 through (0, 0, 0, h) for each h, side by side."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    figure, axes = plt.subplots(1, len(heights), figsize=(4.5 * len(heights), 4.8))
    for ax, height in zip(np.atleast_1d(axes), heights):
        # render() returns the picture as an array when no path is given.
        image = ndpack.pictures.render(packing, at=[0, 0, 0, height], view=(35, 25), size=(540, 540))
        ax.imshow(image)
        ax.set_axis_off()
        ax.set_title(f"3-D slice x3 = {height} (outer radius {np.sqrt(1 - height**2):.2f})")
    figure.tight_layout()
    figure.savefig(path, dpi=120)
    plt.close(figure)
    return path


if __name__ == "__main__":
    main()
