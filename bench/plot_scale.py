"""Plots of the scale benchmarks (``bench/scale.py`` results with a ``curve``): the uncovered
fraction ``1 - fill`` against the count, with the fitted and the theoretical exponent, and the
time to each count.

    python bench/plot_scale.py bench/results/scale_boxes_h100_warp.json ... --out docs/img/scale

writes ``<out>_fill.png`` and ``<out>_time.png``.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

THEORY = {"unit square": 0.5275, "unit cube": 0.2126}


def load_runs(paths):
    """Every run with a curve, labelled ``case (backend, machine)``."""
    runs = []
    for path in paths:
        results = json.loads(Path(path).read_text())
        for run in results["runs"]:
            if run.get("curve", {}).get("count"):
                run["label"] = f"{run['case']} ({run['backend']})"
                runs.append(run)
    return runs


def plot_fill(runs, path, machine=""):
    fig, ax = plt.subplots(figsize=(7, 4.8))
    for run in runs:
        count = np.asarray(run["curve"]["count"], float)
        uncovered = 1 - np.asarray(run["curve"]["fill"])
        keep = count >= 100
        (line,) = ax.loglog(count[keep], uncovered[keep], label=run["label"])
        theory = THEORY.get(run["case"])
        if theory and keep.sum() > 2:
            # The theoretical slope through the curve's last point, dashed, to compare the bends.
            end_count, end_uncovered = count[keep][-1], uncovered[keep][-1]
            xs = np.array([end_count / 100, end_count])
            ax.loglog(xs, end_uncovered * (xs / end_count) ** -theory, "--", color=line.get_color(), lw=1)
            fitted = run.get("exponent")
            ax.annotate(f"a = {fitted:.3f} (theory {theory:.3f})" if fitted else f"theory {theory:.3f}",
                        (xs[0], end_uncovered * 100**theory), textcoords="offset points", xytext=(0, -22), fontsize=8,
                        color=line.get_color())
    finish(fig, ax, path, "uncovered fraction 1 - fill",
           f"Fast mode: fill against count{machine} (dashed: the Apollonian slope)")


def plot_time(runs, path, machine=""):
    fig, ax = plt.subplots(figsize=(7, 4.8))
    for run in runs:
        count = np.asarray(run["curve"]["count"], float)
        seconds = np.asarray(run["curve"]["seconds"])
        keep = count >= 1000
        ax.loglog(count[keep], seconds[keep], label=run["label"])
    finish(fig, ax, path, "seconds since nd.pack started (compile apart)", f"Fast mode: time to each count{machine}")


def finish(fig, ax, path, ylabel, title):
    """Label a log-log plot against the sphere count, and save it."""
    ax.set_xlabel("spheres")
    ax.set_ylabel(ylabel)
    ax.set_title(title, fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("results", nargs="+", help="bench/scale.py JSON files")
    parser.add_argument("--out", default="docs/img/scale", help="path prefix of the two PNGs")
    parser.add_argument("--machine", default="", help="named in the titles, e.g. 'H100'")
    args = parser.parse_args()
    runs = load_runs(args.results)
    machine = f", {args.machine}" if args.machine else ""
    if not runs:
        parser.error("none of these results has a curve: run bench/scale.py again (it records one per run)")
    plot_fill([r for r in runs if r["case"] in THEORY or "armadillo" in r["case"]], f"{args.out}_fill.png", machine)
    plot_time(runs, f"{args.out}_time.png", machine)
    print(f"wrote {args.out}_fill.png and {args.out}_time.png")


if __name__ == "__main__":
    main()
