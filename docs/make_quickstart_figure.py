"""Write docs/img/quickstart_ball4.png: the quick start's 4-D example, as its code makes it.

    python docs/make_quickstart_figure.py

Left, ``ndpack.pictures.render`` of the 3-D slice w = 0; right, ``save_figure``'s circles in the
plane z = w = 0, where the two holes show. The packing is the quick start's (seed 0, the default
mode: fast, above 100 spheres in any dimension).
"""

from __future__ import annotations

import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))  # the checkout's ndpack, even when another is installed

import matplotlib  # noqa: E402

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import ndpack as nd  # noqa: E402
import ndpack.pictures  # noqa: E402


def main() -> None:
    ball = nd.Ball(np.zeros(4), 1.0) - nd.Ball([0.4, 0, 0, 0], 0.35) - nd.Ball([-0.5, 0.3, 0, 0], 0.25)
    packing = nd.pack(ball, n=3000)
    assert packing.verify().ok
    figure, (left, right) = plt.subplots(1, 2, figsize=(11, 5), dpi=100)
    left.imshow(ndpack.pictures.render(packing, at=[0, 0, 0, 0], size=(600, 600)))
    left.set_axis_off()
    left.set_title("the 3-D slice w = 0 (render)")
    ndpack.pictures.plot(packing, shape=ball, ax=right, at=[0, 0, 0, 0])
    right.set_title("the plane z = w = 0 (save_figure): the holes")
    figure.suptitle(packing.summary().split(", smallest")[0])
    figure.tight_layout()
    out = HERE / "img" / "quickstart_ball4.png"
    figure.savefig(out)
    print(out)


if __name__ == "__main__":
    main()
