"""Six meshes and a scan stored z-up, packed and rendered standing: docs/img/standing.png.

Each mesh of ``../shared/data/meshes`` (the checkout's sibling) and a copy of the Stanford bunny
turned z-up and saved as OBJ (a y-up format, so its file convention would lay it on its side) is
packed and rendered as a user would, ``ndpack pack MESH -n 3000 -o NAME.npz`` then ``ndpack render
NAME.npz -o NAME.png``, with the up the render chose (``up="auto"``: the base, see
``ndpack.pictures.view``). The renders go to ``--out``; a contact sheet of the seven, each titled
with the axis chosen, to ``--sheet``.

    python bench/standing.py                     # renders into /tmp/standing, the sheet into docs/img
    python bench/standing.py -n 1000 --size 300 --out /tmp/quick --sheet /tmp/quick/sheet.png
"""

from __future__ import annotations

import argparse
import os
import re
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
MESHES = ROOT.parent / "shared" / "data" / "meshes"
NAMES = ("armadillo", "cow", "spot", "stanford-bunny", "fandisk", "rocker-arm")


def z_up_copy(folder: Path) -> Path:
    """The bunny turned so that its up (+y) is +z (a rotation about x), saved as OBJ."""
    import trimesh

    mesh = trimesh.load(MESHES / "stanford-bunny.obj", force="mesh")
    x, y, z = mesh.vertices.T
    mesh.vertices = np.column_stack([x, -z, y])
    path = folder / "bunny-zup.obj"
    mesh.export(path)
    return path


def ndpack(*arguments: str) -> str:
    """Run the ``ndpack`` command of this checkout; its output."""
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(filter(None, [str(ROOT), os.environ.get("PYTHONPATH")]))}
    result = subprocess.run([sys.executable, "-m", "ndpack.cli", *arguments], capture_output=True, text=True, env=env)
    if result.returncode != 0:
        raise SystemExit(f"ndpack {' '.join(arguments)} failed:\n{result.stdout}\n{result.stderr}")
    return result.stdout


def sheet(renders: list[tuple[str, Path, str]], path: Path, columns: int = 4) -> Path:
    """The renders side by side, each titled with its name and the axis that stands up."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.image
    import matplotlib.pyplot as plt

    rows = -(-len(renders) // columns)
    figure, axes = plt.subplots(rows, columns, figsize=(2.4 * columns, 2.6 * rows))
    for ax in axes.flat:
        ax.axis("off")
    for ax, (name, image, up) in zip(axes.flat, renders):
        ax.imshow(matplotlib.image.imread(image))
        ax.set_title(f"{name}: {up} up", fontsize=9)
    figure.tight_layout()
    figure.savefig(path, dpi=100)
    plt.close(figure)
    from PIL import Image

    with Image.open(path) as image:  # 256 colours, dithered: a third of the bytes, the same to the eye
        image.convert("RGB").quantize(256, dither=Image.Dither.FLOYDSTEINBERG).save(path, optimize=True)
    return path


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("-n", "--count", type=int, default=3000, help="spheres a mesh (default 3,000)")
    parser.add_argument("--size", type=int, default=500, help="render width and height in pixels (default 500)")
    parser.add_argument("--out", default="/tmp/standing", help="folder of the packings and renders")
    parser.add_argument("--sheet", default=str(ROOT / "docs" / "img" / "standing.png"), help="the contact sheet")
    args = parser.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    renders = []
    with tempfile.TemporaryDirectory() as scratch:
        sources = [(name, MESHES / f"{name}.obj") for name in NAMES]
        sources.append(("bunny stored z-up", z_up_copy(Path(scratch))))
        for name, source in sources:
            stem = out / re.sub(r"\W+", "-", name)
            ndpack("pack", str(source), "-n", str(args.count), "-o", f"{stem}.npz")
            printed = ndpack("render", f"{stem}.npz", "-o", f"{stem}.png", "--size", f"{args.size}x{args.size}")
            up = re.search(r"^up: +(\S+) \((.*)\); turn it", printed, re.MULTILINE)
            print(f"{name:18s} up {up[1]:3s} ({up[2]})")
            renders.append((name, Path(f"{stem}.png"), up[1]))
    print(f"wrote {sheet(renders, Path(args.sheet))}")


if __name__ == "__main__":
    main()
