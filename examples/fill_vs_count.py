# %% [markdown]
# # Fill against sphere count
#
# Packs the unit square and the unit cube in the fast mode and plots how the uncovered fraction
# `1 - fill` falls with the sphere count `N`. For an Apollonian packing it falls as a power,
# `1 - fill ~ C N^-a`, with `a = (d - D) / D` and `D` the fractal dimension of what is left
# uncovered: about 0.528 in 2-D and 0.213 in 3-D (the values `docs/benchmarks.md` compares with,
# "Packing at scale", fifth measurement). The script fits `a` over the last two decades of `N`.
#
# A notebook in script form: run it whole, or cell by cell (`# %%`) in VS Code, Spyder or
# Jupyter (with jupytext).
#
#     python examples/fill_vs_count.py                          # 100,000 circles and spheres
#     python examples/fill_vs_count.py --n2 2000 --n3 2000 --backend numpy --out /tmp/fill

# %%
import argparse
import time
from pathlib import Path

import numpy as np

import ndpack as nd

#: The exponents the fits are compared with (docs/benchmarks.md).
THEORY = {2: 0.528, 3: 0.213}

parser = argparse.ArgumentParser(description="Fill against count in the unit square and cube, with fitted exponents.")
parser.add_argument("--n2", type=int, default=100_000, help="circles in the unit square (default 100,000)")
parser.add_argument("--n3", type=int, default=100_000, help="spheres in the unit cube (default 100,000)")
parser.add_argument("--backend", default=None, help="numpy, numba, numba-cuda or warp (default: the fastest here)")
parser.add_argument("--out", default="out", help="output folder (default ./out)")
args, _ = parser.parse_known_args()  # known args only: a notebook kernel adds its own
out = Path(args.out)
out.mkdir(parents=True, exist_ok=True)

# %% [markdown]
# ## Pack
#
# `Packing.stats` keeps the time, count and fill after every round: the whole curve comes from
# one run.

# %%
packings = {}
for dim, count in ((2, args.n2), (3, args.n3)):
    started = time.perf_counter()
    packing = nd.pack(nd.Box(np.zeros(dim), np.ones(dim)), n=count, mode="fast", seed=0, backend=args.backend)
    print(f"{dim}-D: {packing.summary()} ({packing.params['backend']}, {time.perf_counter() - started:.1f} s in all)")
    packings[dim] = packing


# %% [markdown]
# ## Fit the exponent
#
# Least squares of `log(1 - fill)` against `log N`, over `N` from a hundredth of the last count
# to the last, at 30 points evenly spaced in `log N` (interpolated between rounds), so that no
# part of the range weighs more because it took more rounds.

# %%
def fit_exponent(packing, decades=2.0, points=30):
    """The exponent ``a`` and prefactor ``C`` of ``1 - fill = C N^-a``, and the range fitted."""
    count = np.asarray(packing.stats.count, dtype=float)
    uncovered = 1.0 - np.asarray(packing.stats.fill)
    low = max(count[-1] / 10**decades, 10.0)
    keep = count >= low
    if keep.sum() < 2:
        raise ValueError(f"too few rounds above N = {low:.0f} to fit; pack more spheres")
    x, y = np.log(count[keep]), np.log(uncovered[keep])
    grid = np.linspace(x[0], x[-1], points)
    slope, intercept = np.polyfit(grid, np.interp(grid, x, y), 1)
    return -slope, np.exp(intercept), (count[keep][0], count[-1])


fits = {dim: fit_exponent(packing) for dim, packing in packings.items()}
for dim, (exponent, _, (low, high)) in fits.items():
    print(f"{dim}-D: a = {exponent:.3f} over N = {low:,.0f} to {high:,.0f} "
          f"(theory {THEORY[dim]}, {100 * (exponent / THEORY[dim] - 1):+.0f}%)")

# %% [markdown]
# ## Plot
#
# Left: the fill. Right: the uncovered fraction on log-log axes, with the fitted line (dashed)
# and the theory slope through the fit's last point (dotted).

# %%
import matplotlib  # noqa: E402

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

figure, (left, right) = plt.subplots(1, 2, figsize=(11, 4.5))
for dim, packing in packings.items():
    count = np.asarray(packing.stats.count, dtype=float)
    fill = np.asarray(packing.stats.fill)
    exponent, prefactor, (low, high) = fits[dim]
    name = "unit square" if dim == 2 else "unit cube"
    (line,) = left.semilogx(count, fill, label=f"{name}: {fill[-1]:.4f} at {int(count[-1]):,}")
    right.loglog(count, 1 - fill, color=line.get_color(), label=name)
    span = np.geomspace(low, high, 20)
    right.loglog(span, prefactor * span**-exponent, "--", color="black", linewidth=0.9)
    end = prefactor * high**-exponent
    right.loglog(span, end * (span / high) ** -THEORY[dim], ":", color=line.get_color(), linewidth=1.5)
    below = dim == 2  # the square's label below its curve, the cube's above
    right.annotate(f"a = {exponent:.3f} (theory {THEORY[dim]})", (low, prefactor * low**-exponent),
                   textcoords="offset points", xytext=(-6, -6) if below else (0, 10), fontsize=9,
                   ha="right" if below else "left", va="top" if below else "bottom", color=line.get_color())
left.set_xlabel("spheres N")
left.set_ylabel("fill")
left.legend()
left.grid(True, which="both", alpha=0.3)
right.set_xlabel("spheres N")
right.set_ylabel("uncovered fraction 1 - fill")
right.legend()
right.grid(True, which="both", alpha=0.3)
figure.suptitle(f"fast mode, {packings[2].params['backend']} backend, seed 0")
figure.tight_layout()
path = out / "fill_vs_count.png"
figure.savefig(path, dpi=120)
plt.close(figure)
print(f"wrote {path}")
