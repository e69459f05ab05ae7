"""The unit square packed with many circles: an Apollonian-like packing, drawn three ways.

Packs the unit square in the fast mode (many circles a round, the prototype grid refined where
the gaps have become small), then writes:

- ``square.png`` and ``square.svg``: the circles, coloured by radius (``ndpack.pictures.save_figure``;
  above 5,000 circles the SVG holds them as one embedded image, the axes stay vector);
- ``square_gap.png``: a close-up of the gap between the largest circle, a corner circle and the
  bottom edge, where the small circles are;
- ``square_fill.png``: fill and uncovered fraction against the circle count
  (``ndpack.pictures.save_fill_figure``);
- ``square.npz``: the packing, to reload with ``nd.Packing.load``.

    python examples/apollonian_square.py                        # 20,000 circles into ./out
    python examples/apollonian_square.py -n 500 --backend numpy --out /tmp/square
"""

import argparse
import time
from pathlib import Path

import ndpack as nd
import ndpack.pictures


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("-n", "--count", type=int, default=20_000, help="circles to pack (default 20,000)")
    parser.add_argument("--backend", default=None, help="numpy, numba, numba-cuda or warp (default: the fastest here)")
    parser.add_argument("--out", default="out", help="output folder (default ./out)")
    args = parser.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)

    square = nd.Box([0, 0], [1, 1])
    started = time.perf_counter()
    packing = nd.pack(square, n=args.count, mode="fast", seed=0, backend=args.backend)
    elapsed = time.perf_counter() - started
    report = packing.verify()

    files = [
        ndpack.pictures.save_figure(packing, out / "square.png", dpi=150),
        ndpack.pictures.save_figure(packing, out / "square.svg"),
        close_up(packing, out / "square_gap.png"),
        ndpack.pictures.save_fill_figure(packing, out / "square_fill.png"),
        packing.save(out / "square.npz"),
    ]
    print(f"{len(packing):,} circles, fill {packing.fill:.5f}, largest radius {packing.radii.max():.4f}, "
          f"smallest {packing.radii.min():.2e}")
    rounds = len(packing.stats.count)
    print(f"{elapsed:.1f} s ({packing.params['backend']} backend, {rounds} rounds), valid: {report.ok}")
    for path in files:
        print(f"wrote {path}")


def close_up(packing, path, x=(0.15, 0.27), y=(-0.002, 0.07)):
    """A close-up: ``ndpack.pictures.plot`` on our own axes, then zoomed in."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    figure, ax = plt.subplots(figsize=(7, 4))
    ndpack.pictures.plot(packing, ax=ax)
    ax.set_xlim(*x)
    ax.set_ylim(*y)
    ax.set_title(f"close-up: x in [{x[0]}, {x[1]}], y in [0, {y[1]}]")
    figure.savefig(path, dpi=150, bbox_inches="tight")
    plt.close(figure)
    return path


if __name__ == "__main__":
    main()
