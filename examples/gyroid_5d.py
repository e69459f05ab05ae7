"""A user's plug-in defined once, packed on every backend: a 5-D gyroid-like shell.

The distance is a plain scalar function of one point, written in ndpack's kernel language
(arithmetic, math functions, loops, indexing). ndpack compiles it for Numba on the CPU, Numba
CUDA and NVIDIA Warp, and runs its Numba form for the NumPy reference.

    python examples/gyroid_5d.py            # all installed backends, 200 spheres each, into ./out
    python examples/gyroid_5d.py -n 2000 --backend numba --out /tmp/gyroid
"""

import argparse
import math
import time
from pathlib import Path

import ndpack as nd


@nd.scalar_plugin(dim=5, bounds=[[-1.0] * 5, [1.0] * 5], params=[3.0, 0.35])
def gyroid(p, params):
    """A thickened 5-D gyroid-like level set, cut to the unit ball."""
    k = params[0]
    s = 0.0
    for i in range(D):  # noqa: F821 - D, the dimension, is a constant of the kernel language
        s += math.sin(k * p[i]) * math.cos(k * p[(i + 1) % D])  # noqa: F821
    # |grad s| <= k * sqrt(2 D), so dividing by it keeps the function 1-Lipschitz.
    sheet = (abs(s) - params[1]) / (k * math.sqrt(2.0 * D))  # noqa: F821
    r2 = 0.0
    for i in range(D):  # noqa: F821
        r2 += p[i] * p[i]
    return max(sheet, math.sqrt(r2) - 1.0)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("-n", type=int, default=200, help="spheres per backend")
    parser.add_argument("--backend", action="append", help="backend(s) to run (default: every installed one)")
    parser.add_argument("--out", default="out", help="output folder (default ./out): a packing per backend")
    args = parser.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    status = nd.backends.available()
    names = args.backend or [name for name, state in status.items() if state.startswith("ok")]
    gyroid.check_lipschitz(samples=4000)
    for name in names:
        started = time.perf_counter()
        packing = nd.pack(gyroid, args.n, grid=10, backend=name)
        report = packing.verify()
        print(f"{name:11s} {len(packing.radii):6d} spheres  fill {packing.fill:.4f}  "
              f"largest r {packing.radii.max():.4f}  {time.perf_counter() - started:6.1f} s  valid: {report.ok}")
        print(f"wrote {packing.save(out / f'gyroid_{name}.npz')}")


if __name__ == "__main__":
    main()
