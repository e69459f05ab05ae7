"""A manifold3d part packed with spheres: a filleted plate with bores and a pocket.

The profile is a manifold3d cross-section whose corners are rounded by offsetting in and out
(a fillet made by offset), extruded, then cut by cylinders (bores) and a box (pocket). ndpack
takes the manifold3d solid directly and mixes it with its own shapes (here: a half-space that
trims the top).

    python examples/manifold_part.py                     # 10,000 spheres, picture into ./out
    python examples/manifold_part.py --out docs/img      # the picture of docs/meshes.md
    python examples/manifold_part.py -n 500 --backend numpy --out /tmp/part
"""

import argparse
import time
from pathlib import Path

import manifold3d as m3d
import ndpack as nd


def part(fillet: float = 0.4, segments: int = 64) -> m3d.Manifold:
    """The plate: 6 x 4 x 1.5 with rounded corners, two bores and a pocket (manifold3d CSG)."""
    profile = m3d.CrossSection.square([6.0, 4.0])
    notch = m3d.CrossSection.square([2.0, 1.2]).translate([2.0, -0.01])
    profile = (profile - notch).offset(-fillet, m3d.JoinType.Round, circular_segments=segments)
    profile = profile.offset(fillet, m3d.JoinType.Round, circular_segments=segments)
    plate = profile.extrude(1.5)
    for x, y, radius in ((1.2, 2.0, 0.6), (4.8, 2.0, 0.6)):
        plate -= m3d.Manifold.cylinder(2.0, radius, radius, segments).translate([x, y, -0.25])
    plate -= m3d.Manifold.cube([2.0, 1.6, 1.0]).translate([2.0, 2.0, 0.8])
    return plate


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("-n", type=int, default=10_000, help="spheres to pack")
    parser.add_argument("--backend", default=None, help="backend (default: the fastest here)")
    parser.add_argument("--out", default="out", help="output folder (default ./out)")
    args = parser.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)

    solid = part()
    trimmed = solid - nd.HalfSpace([0, 0, -1], -1.4)  # remove z > 1.4: a manifold3d solid minus an ndpack shape
    started = time.perf_counter()
    packing = nd.pack(trimmed, n=args.n, batch=64, seed=0, backend=args.backend)
    elapsed = time.perf_counter() - started
    report = packing.verify()
    print(f"{len(packing.radii)} spheres, fill {packing.fill:.4f}, {elapsed:.1f} s "
          f"({packing.params['backend']}), valid: {report.ok}")
    print(f"wrote {draw(packing, out / 'manifold_part.png')}")


def draw(packing, path):
    """Two exact slices: across the bores (z = 0.7) and along the pocket (y = 2.8)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    figure, (top, side) = plt.subplots(1, 2, figsize=(13, 4.4), gridspec_kw={"width_ratios": [1.15, 1]})
    packing.plot(ax=top, axes=(0, 1), at=[0, 0, 0.7])
    top.set_title(f"{len(packing.radii):,} spheres, fill {packing.fill:.3f}: slice z = 0.7")
    packing.plot(ax=side, axes=(0, 2), at=[0, 2.8, 0])
    side.set_title("slice y = 2.8, through the pocket")
    figure.tight_layout()
    figure.savefig(path, dpi=110)
    plt.close(figure)
    return path


if __name__ == "__main__":
    main()
