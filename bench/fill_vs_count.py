"""Fill against sphere count for the unit square and the unit cube (NumPy reference backend).

Packs the unit square with ``--n2`` circles and the unit cube with ``--n3`` spheres, records
``fill`` against ``count`` from ``Packing.stats`` (one entry per round), and fits the uncovered
fraction ``1 - fill ~ C * N**-a`` by least squares in log-log space over the tail (``N`` from
``--fit-min`` to the last count, at points evenly spaced in ``log N`` so the many late rounds do
not dominate). For Apollonian packings theory gives ``a = (d - D) / D`` with ``D`` the fractal
dimension of the residual set.

By default a third packing of the square with a finer grid (``--fine-grid2``) shows how much the
finite prototype grid bends the tail of the 2D curve; ``--fine-grid2 0`` skips it.

Writes ``<out>/fill_vs_count.json``, the full curves to ``<out>/fill_vs_count_curves.npz``
(``--replot`` redraws the figure from these two) and ``docs/img/fill_vs_count.png``. About 1.5 minutes on
2 cores with the defaults.

    python bench/fill_vs_count.py --n2 5000 --n3 3000 --seed 0 --out bench/results
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

import ndpack as nd

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import load_average, machine_info, write_json

ROOT = Path(__file__).resolve().parent.parent

#: fractal dimension of the residual set of the Apollonian packing
FRACTAL_DIM = {2: 1.3057, 3: 2.4739}
TABLE_COUNTS = [10, 20, 50, 100, 200, 500, 1000, 2000, 5000]
SLOPE_EDGES = [100, 300, 1000, 3000, 10000]


def theory_exponent(d: int) -> float:
    D = FRACTAL_DIM[d]
    return (d - D) / D


def fit_exponent(count: np.ndarray, fill: np.ndarray, n_min: int, n_points: int) -> dict:
    """Least-squares fit of log(1 - fill) = log C - a log N over N in [n_min, count[-1]]."""
    n_max = int(count[-1])
    if n_max <= n_min:
        raise ValueError(f"packing has {n_max} spheres, fewer than --fit-min {n_min}")
    targets = np.unique(np.round(np.geomspace(n_min, n_max, n_points)).astype(int))
    idx = np.searchsorted(count, targets)
    idx = np.unique(idx[idx < len(count)])
    x = np.log(count[idx].astype(float))
    y = np.log1p(-fill[idx])
    A = np.column_stack([x, np.ones_like(x)])
    (slope, intercept), *_ = np.linalg.lstsq(A, y, rcond=None)
    resid = y - A @ np.array([slope, intercept])
    dof = len(x) - 2
    s2 = float(resid @ resid) / dof
    se = float(np.sqrt(s2 / np.sum((x - x.mean()) ** 2)))
    return {
        "exponent": float(-slope),
        "stderr": se,
        "log_prefactor": float(intercept),
        "n_min": int(count[idx[0]]),
        "n_max": int(count[idx[-1]]),
        "points": int(len(x)),
    }


def local_slopes(count: np.ndarray, fill: np.ndarray) -> list[dict]:
    """Two-point exponents -dlog(1-fill)/dlog N between successive SLOPE_EDGES (and the end)."""
    n_max = int(count[-1])
    edges = [e for e in SLOPE_EDGES if e < n_max] + [n_max]
    out = []
    for a, b in zip(edges[:-1], edges[1:]):
        fa = fill[np.searchsorted(count, a)]
        fb = fill[np.searchsorted(count, b)]
        out.append({
            "from": int(a),
            "to": int(b),
            "exponent": float(-(np.log1p(-fb) - np.log1p(-fa)) / (np.log(b) - np.log(a))),
        })
    return out


def run_case(name: str, d: int, n: int, seed: int, grid, args) -> dict:
    shape = nd.Box([0.0] * d, [1.0] * d)
    print(f"[{name}] packing {n} spheres in the unit {'square' if d == 2 else 'cube'}"
          f" (grid={grid or 'default'}) ...", flush=True)
    t0 = time.perf_counter()
    p = nd.pack(shape, n=n, seed=seed, grid=grid, backend="numpy", mode="faithful", progress=False)
    wall = time.perf_counter() - t0
    ok = bool(p.verify().ok)
    count = np.asarray(p.stats.count)
    fill = np.asarray(p.stats.fill, dtype=float)
    times = np.asarray(p.stats.time, dtype=float)
    table = []
    for c in TABLE_COUNTS:
        i = np.searchsorted(count, c)
        if i < len(count) and count[i] == c:
            table.append({"count": c, "fill": float(fill[i]), "time_s": float(times[i])})
    fit = fit_exponent(count, fill, args.fit_min, args.fit_points)
    fit["theory"] = theory_exponent(d)
    fit["fractal_dimension"] = FRACTAL_DIM[d]
    print(f"[{name}] {len(p)} spheres, fill {p.fill:.5f}, stop {p.stop_reason!r}, "
          f"{wall:.1f} s, verified {ok}; exponent {fit['exponent']:.3f} "
          f"+- {fit['stderr']:.4f} (theory {fit['theory']:.3f})", flush=True)
    return {
        "name": name,
        "dim": d,
        "n_requested": n,
        "n_packed": len(p),
        "stop_reason": p.stop_reason,
        "fill": float(p.fill),
        "wall_s": wall,
        "verified": ok,
        "params": p.params,
        "table": table,
        "fit": fit,
        "local_exponents": local_slopes(count, fill),
        "final": {"count": int(count[-1]), "fill": float(fill[-1]), "time_s": float(times[-1])},
        "_curve": (count, fill),
    }


def plot(cases: list[dict], path: Path, seed: int) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    style = {
        "square": dict(color="C0", lw=2.6, zorder=2),
        "cube": dict(color="C3", lw=2.6, zorder=2),
        "square_fine": dict(color="C2", lw=1.4, ls=(0, (5, 2)), zorder=3),
    }
    fit_color = {"square": "k", "cube": "k", "square_fine": "0.5"}
    short = {"square": "2D", "cube": "3D", "square_fine": "2D fine grid"}
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(12.5, 5.2))
    for c in cases:
        count, fill = c["_curve"]
        g = c["params"]["grid"]
        glabel = "x".join(str(v) for v in g) if isinstance(g, (list, tuple)) else str(g)
        label = f"{'unit square (2D)' if c['dim'] == 2 else 'unit cube (3D)'}, grid {glabel}"
        st = style[c["name"]]
        ax1.semilogx(count, fill, label=label, **st)
        ax2.loglog(count, 1.0 - fill, label=label, **st)
        f = c["fit"]
        xs = np.geomspace(f["n_min"], f["n_max"], 50)
        ax2.loglog(xs, np.exp(f["log_prefactor"]) * xs ** -f["exponent"], ls="--", color=fit_color[c["name"]],
                   lw=1.0, zorder=4,
                   label=f"{short[c['name']]} fit: a = {f['exponent']:.3f} ± {f['stderr']:.4f}"
                   f" (N {f['n_min']}–{f['n_max']})")
        if c["name"] != "square_fine":
            # theory slope, anchored on the fitted line at the start of the fit range
            y0 = np.exp(f["log_prefactor"]) * f["n_min"] ** -f["exponent"]
            ax2.loglog(xs, y0 * (xs / f["n_min"]) ** -f["theory"], ls=":", color=st["color"],
                       lw=2.2, zorder=1,
                       label=f"{short[c['name']]} theory slope: a = {f['theory']:.3f} (D = {f['fractal_dimension']})")
    ax1.set_xlabel("number of spheres N")
    ax1.set_ylabel("fill (covered volume fraction)")
    ax1.set_title("Fill against count")
    ax1.grid(True, which="both", alpha=0.3)
    ax1.legend(loc="lower right", fontsize=9)
    ax2.set_xlabel("number of spheres N")
    ax2.set_ylabel("uncovered fraction 1 − fill")
    ax2.set_title("Uncovered fraction: 1 − fill ~ N^(−a)")
    ax2.grid(True, which="both", alpha=0.3)
    lo = min(float(np.min(1.0 - c["_curve"][1])) for c in cases)
    ax2.set_ylim(bottom=lo / 5)  # room for the legend below the curves
    ax2.legend(loc="lower left", fontsize=8)
    fig.suptitle(f"ndpack {nd.__version__} greedy ProtoSphere packing, NumPy backend, seed {seed}")
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=120)
    plt.close(fig)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--n2", type=int, default=5000, help="circles in the unit square")
    ap.add_argument("--n3", type=int, default=3000, help="spheres in the unit cube")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--grid2", type=int, default=None, help="grid of the 2D run (default: ndpack's)")
    ap.add_argument("--grid3", type=int, default=None, help="grid of the 3D run (default: ndpack's)")
    ap.add_argument("--fine-grid2", type=int, default=512,
                    help="grid of an extra 2D run showing the grid's effect; 0 skips it")
    ap.add_argument("--fit-min", type=int, default=100, help="smallest N of the fit")
    ap.add_argument("--fit-points", type=int, default=50, help="log-spaced points of the fit")
    ap.add_argument("--out", type=Path, default=ROOT / "bench" / "results")
    ap.add_argument("--plot", type=Path, default=ROOT / "docs" / "img" / "fill_vs_count.png")
    ap.add_argument("--replot", action="store_true",
                    help="only redraw the plot from <out>/fill_vs_count.json and its curves file")
    args = ap.parse_args(argv)
    out = args.out / "fill_vs_count.json"
    curves_path = args.out / "fill_vs_count_curves.npz"

    if args.replot:
        with open(out) as fh:
            saved = json.load(fh)
        curves = np.load(curves_path)
        cases = saved["cases"]
        for c in cases:
            c["_curve"] = (curves[c["name"] + "_count"], curves[c["name"] + "_fill"])
        plot(cases, args.plot, saved["parameters"]["seed"])
        print(f"wrote {args.plot}")
        return 0

    machine = machine_info()
    t0 = time.perf_counter()
    cases = [
        run_case("square", 2, args.n2, args.seed, args.grid2, args),
        run_case("cube", 3, args.n3, args.seed, args.grid3, args),
    ]
    if args.fine_grid2:
        cases.append(run_case("square_fine", 2, args.n2, args.seed, args.fine_grid2, args))
    total = time.perf_counter() - t0

    plot(cases, args.plot, args.seed)
    result = {
        "benchmark": "fill_vs_count",
        "machine": machine,
        "parameters": {k: (str(v) if isinstance(v, Path) else v) for k, v in vars(args).items()},
        "fit_method": ("ordinary least squares of log(1-fill) on log N at up to fit_points counts "
                       "log-spaced from fit_min to the last count; stderr from the residuals "
                       "(they are serially correlated, so it understates the uncertainty)"),
        "total_wall_s": total,
        "loadavg_at_end": load_average(),
        "cases": [{k: v for k, v in c.items() if not k.startswith("_")} for c in cases],
    }
    write_json(out, result)
    np.savez_compressed(curves_path, **{
        f"{c['name']}_{key}": arr for c in cases for key, arr in zip(("count", "fill"), c["_curve"])
    })

    print(f"\n{'case':<12} {'count':>6} {'fill':>9} {'1-fill':>9} {'time s':>8}")
    for c in cases:
        for row in c["table"]:
            print(f"{c['name']:<12} {row['count']:>6} {row['fill']:>9.5f} "
                  f"{1 - row['fill']:>9.2e} {row['time_s']:>8.2f}")
    for c in cases:
        f = c["final"]
        print(f"{c['name']:<12} {f['count']:>6} {f['fill']:>9.5f} {1 - f['fill']:>9.2e} "
              f"{f['time_s']:>8.2f}  (last round, stop {c['stop_reason']!r})")
    print(f"\n{'case':<12} {'exponent':>9} {'stderr':>7} {'theory':>7}  fit range")
    for c in cases:
        f = c["fit"]
        print(f"{c['name']:<12} {f['exponent']:>9.3f} {f['stderr']:>7.4f} {f['theory']:>7.3f}"
              f"  {f['n_min']}-{f['n_max']}")
    print(f"\ntotal {total:.1f} s; wrote {out}, {curves_path} and {args.plot}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
