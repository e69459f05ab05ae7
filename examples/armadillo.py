"""A triangle mesh packed with spheres, rendered, and saved for other tools.

Loads a mesh file (any format trimesh reads: OBJ, STL, PLY, OFF, GLB), packs it in the fast
mode, renders the spheres shaded (``ndpack.pictures.render``) and writes the spheres in every
3-D format ndpack has:

- ``armadillo.png``: the shaded render, and ``armadillo_cut.png``: the same, cut in half;
- ``armadillo.npz``: everything (reload with ``nd.Packing.load``);
- ``armadillo.vtp``: VTK points with a radius, for ParaView's glyph filter;
- ``armadillo.glb``: one icosphere per sphere, for Blender or any glTF viewer;
- ``armadillo.sph``: a sphere tree (the sphere-tree toolkit's format);
- ``armadillo_curobo.json``: cuRobo ``collision_spheres``.

The default mesh is the 100k-triangle armadillo of ``/work/shared/data/meshes`` when it is there,
else the decimated copy in ``tests/data/meshes`` (20k triangles).

    python examples/armadillo.py                              # 10,000 spheres into ./out
    python examples/armadillo.py -n 300 --grid 16 --backend numpy --out /tmp/armadillo
    python examples/armadillo.py --mesh part.stl --name part
"""

import argparse
import time
from pathlib import Path

import ndpack as nd
import ndpack.io
import ndpack.pictures

SHARED = Path("/work/shared/data/meshes/armadillo.obj")
SMALL = Path(__file__).resolve().parent.parent / "tests" / "data" / "meshes" / "armadillo-20k.ply"


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--mesh", default=str(SHARED if SHARED.exists() else SMALL), help="mesh file to pack")
    parser.add_argument("-n", "--count", type=int, default=10_000, help="spheres to pack (default 10,000)")
    parser.add_argument("--grid", type=int, default=None,
                        help="grid cells along the longest side (default: about 32,768 cells)")
    parser.add_argument("--backend", default=None, help="numpy, numba, numba-cuda or warp (default: the fastest here)")
    parser.add_argument("--azimuth", type=float, default=210.0,
                        help="camera azimuth in degrees (default 210: from the front, left)")
    parser.add_argument("--size", type=int, default=800, help="picture width and height in pixels (default 800)")
    parser.add_argument("--name", default="armadillo", help="file name stem of the outputs (default armadillo)")
    parser.add_argument("--out", default="out", help="output folder (default ./out)")
    args = parser.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)

    started = time.perf_counter()
    mesh = nd.TriangleMesh.load(args.mesh)
    print(f"{args.mesh}: {mesh!r}, sign by {mesh.sign_method} ({time.perf_counter() - started:.1f} s to load)")
    for note in mesh.notes:
        print(f"  repaired: {note}")

    started = time.perf_counter()
    packing = nd.pack(mesh, n=args.count, mode="fast", grid=args.grid, seed=0, backend=args.backend)
    elapsed = time.perf_counter() - started
    report = packing.verify()
    print(f"{len(packing):,} spheres, fill {packing.fill:.4f}, {elapsed:.1f} s "
          f"({packing.params['backend']} backend), {report.summary()}")

    # Standing on its base (the armadillo on its feet, y up; a part on its flat face): the
    # picture says which axis it stood up and why.
    view = dict(view=(args.azimuth, 15), size=(args.size, args.size))
    picture = ndpack.pictures.picture(packing, out / f"{args.name}.png", **view)
    print(f"up: {picture.up}")
    # Leave out the spheres whose centre lies beyond the plane through the middle, facing the camera.
    _, _, towards = ndpack.pictures.camera_axes(*view["view"])
    up = picture.up
    facing = ndpack.pictures.view.screen_frame(up.axis, up.sign).T @ towards  # in the mesh's coordinates
    cut = ndpack.pictures.picture(packing, out / f"{args.name}_cut.png", clip=(packing.centers.mean(axis=0), facing),
                                  up=up, **view)
    files = [
        picture.path,
        cut.path,
        packing.save(out / f"{args.name}.npz"),
        packing.save(out / f"{args.name}.vtp"),
        packing.save(out / f"{args.name}.glb", subdivisions=1),
        packing.save(out / f"{args.name}.sph"),
        packing.save(out / f"{args.name}_curobo.json", format="curobo", link=args.name),
    ]
    for path in files:
        print(f"wrote {path} ({path.stat().st_size / 1e6:.2f} MB)")
    print("every format ndpack writes:")
    print(ndpack.io.table())


if __name__ == "__main__":
    main()
