"""Write docs/gallery.md and its pictures (docs/img/gallery/*.png).

    python docs/make_gallery.py                      # numba backend, about 3 minutes on 2 cores
    python docs/make_gallery.py --backend warp
    python docs/make_gallery.py --out /tmp/gallery --max-spheres 100   # a quick check (the tests)

Every packing uses seed 0 and the fast mode, and is verified before it is drawn. The cow comes
from /work/shared/data/meshes/cow.obj when it is there, else from tests/data/meshes/cow.ply
(the same surface, welded, in float32). Pictures over 290 kB are saved with
256 colours.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(ROOT))  # the checkout's ndpack, even when another is installed

import numpy as np  # noqa: E402

import ndpack as nd  # noqa: E402
import ndpack.pictures  # noqa: E402
from ndpack.io.named_shapes import from_spec  # noqa: E402

IMAGES = HERE / "img" / "gallery"  # main() points it under --out
#: The most spheres any packing gets (--max-spheres); None: as written below.
MAX_SPHERES = None
COW = Path("/work/shared/data/meshes/cow.obj")
COW_SMALL = ROOT / "tests" / "data" / "meshes" / "cow.ply"
SIZE = 600  # pixels, width and height
DPI = 100  # save_figure at figsize 6 x 6 gives about 600 x 600 pixels

#: Each entry: file, title, caption, code shown (the snippet that made the picture, in short).
ENTRIES = []


#: Pictures above this size are saved with 256 colours (dithered): a shaded render of thousands
#: of spheres is 300-340 kB in full colour, about 110 kB in 256.
MAX_BYTES = 290_000


def rendered(packing, file, **options):
    """``ndpack.pictures.render`` into ``IMAGES / file``, kept under :data:`MAX_BYTES`."""
    from PIL import Image

    path = IMAGES / file
    picture = Image.fromarray(ndpack.pictures.render(packing, size=(SIZE, SIZE), **options))
    picture.save(path, optimize=True)
    if path.stat().st_size > MAX_BYTES:
        picture.quantize(256, dither=Image.Dither.FLOYDSTEINBERG).save(path, optimize=True)
    return path


def entry(file, title, caption, code):
    ENTRIES.append(dict(file=file, title=title, caption=caption, code=code.strip("\n")))


def packed(shape, n, backend, label):
    started = time.perf_counter()
    packing = nd.pack(shape, n=min(n, MAX_SPHERES or n), mode="fast", seed=0, backend=backend)
    report = packing.verify()
    if not report.ok:
        raise SystemExit(f"{label}: the packing failed verification: {report.summary()}")
    print(f"{label}: {packing.summary()} ({time.perf_counter() - started:.1f} s, {packing.params['backend']})",
          flush=True)
    return packing


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--backend", default="numba", help="backend for every packing (default numba)")
    parser.add_argument("--out", type=Path, default=HERE, help="folder of gallery.md and img/gallery/ (default docs/)")
    parser.add_argument("--max-spheres", type=int, default=None, help="at most this many spheres a packing")
    args = parser.parse_args(argv)
    global IMAGES, MAX_SPHERES
    IMAGES, MAX_SPHERES = args.out / "img" / "gallery", args.max_spheres
    IMAGES.mkdir(parents=True, exist_ok=True)
    started = time.perf_counter()
    backend = args.backend

    # 2-D: the unit square.
    square = packed(nd.Box([0, 0], [1, 1]), 5000, backend, "square")
    ndpack.pictures.save_figure(square, IMAGES / "square.png", dpi=DPI)
    entry("square.png", "The unit square, 5,000 circles",
          f"Fill {square.fill:.4f}. Colour is the radius, on a log scale.",
          """
square = nd.pack(nd.Box([0, 0], [1, 1]), n=5000, mode="fast")
ndpack.pictures.save_figure(square, "square.png")
""")

    # 2-D: a ring (a 256-gon with a hole), the built-in `annulus`.
    ring = packed(from_spec("annulus"), 3000, backend, "annulus")
    ndpack.pictures.save_figure(ring, IMAGES / "annulus.png", dpi=DPI)
    entry("annulus.png", "A ring, 3,000 circles",
          f"Fill {ring.fill:.4f}. The built-in `annulus`: a 256-gon with a 256-gon hole "
          "(`nd.Polygon`). The black line is the outline, drawn from the distance.",
          """
ring = nd.pack(ndpack.io.named_shapes.from_spec("annulus"), n=3000, mode="fast")   # ndpack pack annulus
ndpack.pictures.save_figure(ring, "annulus.png")
""")

    # 3-D: the demo part, whole and cut.
    demo = packed(from_spec("demo"), 5000, backend, "demo part")
    rendered(demo, "demo.png", view=(-50, 65))
    rendered(demo, "demo_cut.png", view=(-50, 65), clip=([0, 0, 0], [0, 0, 1]))
    entry("demo.png", "The demo part, 5,000 spheres",
          f"Fill {demo.fill:.4f}. A rounded block minus a bore and a spherical pocket, built by CSG "
          "(`ndpack pack` packs it when given no shape). Shaded by `ndpack.pictures.render`.",
          """
block = nd.RoundedBox([-1, -0.6, -0.4], [1, 0.6, 0.4], 0.15)
part = block - nd.Cylinder([0.45, 0, -1], [0.45, 0, 1], 0.25) - nd.Ball([-0.5, 0, 0.45], 0.35)
demo = nd.pack(part, n=5000, mode="fast")
ndpack.pictures.render(demo, "demo.png", size=(600, 600), view=(-50, 65))
""")
    entry("demo_cut.png", "The demo part, cut at z = 0",
          "The same packing without the spheres whose centre lies above z = 0 (`clip=(point, normal)` "
          "drops the side the normal points to): the large spheres inside, and the bore.",
          """
ndpack.pictures.render(demo, "demo_cut.png", size=(600, 600), view=(-50, 65), clip=([0, 0, 0], [0, 0, 1]))
""")

    # A triangle mesh: the cow.
    cow_file = COW if COW.exists() else COW_SMALL
    cow_mesh = nd.TriangleMesh.load(cow_file)
    cow = packed(cow_mesh, 3000, backend, "cow")
    rendered(cow, "cow.png", up="y", view=(-35, 20))
    entry("cow.png", "A triangle mesh: the cow, 3,000 spheres",
          f"Fill {cow.fill:.4f}. `cow.obj` (5,804 triangles) has faces that cross in its head, so its "
          f"inside is told by the winding number (`mesh.sign_method` is `{cow_mesh.sign_method}`; see "
          "[meshes.md](meshes.md)). Its up is y: `up='auto'` (the default) finds it standing on its hooves, "
          "the axis OBJ files have up by convention; `up='y'` says it.",
          """
cow = nd.pack(nd.TriangleMesh.load("cow.obj"), n=3000, mode="fast")
ndpack.pictures.render(cow, "cow.png", size=(600, 600), up="y", view=(-35, 20))
""")

    # 4-D: a ball with a hole, sliced.
    shell = nd.Ball(np.zeros(4), 1.0) - nd.Ball(np.zeros(4), 0.5)
    ball4 = packed(shell, 3000, backend, "4-D ball with a hole")
    ndpack.pictures.save_figure(ball4, IMAGES / "ball4d_slice.png", at=[0, 0, 0, 0], dpi=DPI)
    rendered(ball4, "ball4d_3d.png", at=[0, 0, 0, 0.3])
    entry("ball4d_slice.png", "4-D: a ball with a hole, 3,000 spheres, sliced by a plane",
          f"Fill {ball4.fill:.4f}. The unit 4-ball minus the ball of radius 0.5. The plane x2 = x3 = 0 "
          "cuts each 4-D sphere in a circle of radius sqrt(r² - h²), h its centre's distance from the "
          "plane; the hole shows as the empty middle.",
          """
shell = nd.Ball(np.zeros(4), 1.0) - nd.Ball(np.zeros(4), 0.5)
ball4 = nd.pack(shell, n=3000, mode="fast")
ndpack.pictures.save_figure(ball4, "ball4d_slice.png", at=[0, 0, 0, 0])   # axes=(0, 1) by default
""")
    entry("ball4d_3d.png", "4-D: the same packing, 3-D slice x3 = 0.3",
          "A 3-D slice is drawn shaded, each 4-D sphere as the 3-D ball it cuts from the slice.",
          """
ndpack.pictures.render(ball4, "ball4d_3d.png", size=(600, 600), at=[0, 0, 0, 0.3])   # axes=(0, 1, 2)
""")

    # Fill against count, from the packings' per-round statistics.
    packings = [square, ring, demo, cow, ball4]
    labels = ["square (2-D)", "ring (2-D)", "demo part (3-D)", "cow (3-D mesh)", "ball with a hole (4-D)"]
    ndpack.pictures.save_fill_figure(packings, IMAGES / "fill.png", labels=labels, dpi=DPI, figsize=(10, 4.2))
    entry("fill.png", "Fill against count",
          "Fill and uncovered fraction after each round of the packings above "
          "(`Packing.stats`). The uncovered fraction falls about as a power of the count; its exponent "
          "shrinks with the dimension.",
          """
ndpack.pictures.save_fill_figure([square, ring, demo, cow, ball4], "fill.png", labels=[...])
""")

    write_markdown(args.out / "gallery.md", backend)
    elapsed = time.perf_counter() - started
    for path in sorted(IMAGES.glob("*.png")):
        print(f"{path}: {path.stat().st_size / 1e3:.0f} kB")
    print(f"wrote {args.out / 'gallery.md'} in {elapsed:.0f} s")
    return 0


def write_markdown(path, backend):
    lines = [
        "# Gallery",
        "",
        "Made by `python docs/make_gallery.py` (do not edit by hand): every packing in the fast mode,",
        f"seed 0, `{backend}` backend, verified in float64 before it was drawn. The code under each",
        "picture is the gist; the script has all of it. It assumes `import numpy as np`,",
        "`import ndpack as nd`, `import ndpack.pictures` and `import ndpack.io.named_shapes`.",
        "",
    ]
    for item in ENTRIES:
        lines += [
            f"## {item['title']}",
            "",
            f"![{item['title']}](img/gallery/{item['file']})",
            "",
            item["caption"],
            "",
            "```python",
            item["code"],
            "```",
            "",
        ]
    path.write_text("\n".join(lines).rstrip("\n") + "\n")


if __name__ == "__main__":
    sys.exit(main())
