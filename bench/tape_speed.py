"""The tape interpreter against specialised code: distances per second and packing time.

A shape runs on the compiled backends either as a tape (its numbers, read by the one compiled
interpreter of its dimension: nothing to compile for a new shape) or as a specialised program
(code generated for its tree: compiled for every new tree). Both are timed here on the same
inputs, in one process, compile apart (each is warmed up first):

- distances: the backend's own kernel over points already in its memory (numba: the parallel
  evaluation loop; Warp: ``distance_all``; numba-cuda: ``clearance_all`` with no spheres);
- packing: ``nd.pack(shape, n, mode="fast")`` on the backend.

Shapes: one ball (shallow), the demo part (three leaves), a deep tree (24 leaves under
rotations, scales and offsets, nested four levels) and a mesh (the 20k-triangle armadillo).

    python bench/tape_speed.py --backends numba warp:cpu --out bench/results/tape_speed_2core.json
    python bench/tape_speed.py --backends numba warp:cuda:0 numba-cuda --points 4000000   # GPU machine
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import machine_info, write_json

import ndpack as nd
from ndpack.backends import get_backend
from ndpack.kernels.compiled import compiled_program
from ndpack.io.named_shapes import BUILTIN

ROOT = Path(__file__).resolve().parents[1]


def deep_tree() -> nd.Oracle:
    """24 leaves of every kind of node: unions of rotated, scaled, offset parts, cut and merged."""
    rng = np.random.default_rng(0)
    parts = []
    for k in range(6):
        ball = nd.Ball(rng.uniform(-0.3, 0.3, 3), rng.uniform(0.2, 0.4))
        box = nd.Box(rng.uniform(-0.5, -0.2, 3), rng.uniform(0.2, 0.5, 3))
        capsule = nd.Capsule(rng.uniform(-0.4, 0.4, 3), rng.uniform(-0.4, 0.4, 3), 0.1)
        cylinder = nd.Cylinder([0, 0, -0.5], [0, 0, 0.5], rng.uniform(0.05, 0.15))
        part = ((ball | box).offset(0.02) - capsule).smooth_union(cylinder, 0.05)
        angle = rng.uniform(0, np.pi)
        parts.append(part.rotate(nd.rotation(3, angle)).scale_by(rng.uniform(0.6, 1.2))
                     .translate(rng.uniform(-1, 1, 3)))
    return nd.Union(*parts) & nd.Box([-1.5] * 3, [1.5] * 3)


def shapes() -> dict:
    return {
        "ball": nd.Ball([0.0, 0.0, 0.0], 1.0),
        "demo": BUILTIN["demo"](),
        "deep": deep_tree(),
        "mesh": nd.TriangleMesh.load(ROOT / "tests" / "data" / "meshes" / "armadillo-20k.ply"),
    }


def distances_per_second(backend, shape, points, repeats) -> float:
    """Median rate of the backend's distance kernel over ``points`` held in its memory."""
    name = backend.name
    if name == "numba":
        from ndpack.kernels.compile import numba_evaluator

        flat = compiled_program(shape)
        evaluate = numba_evaluator(flat.program)

        def run():
            evaluate(points, flat.params)
    elif name == "warp":
        wp = backend.wp
        module, params, _ = backend._module(shape)
        d_points = backend._points(module, points)
        out = wp.empty(len(points), dtype=module.F, device=backend.device)

        def run():
            wp.launch(module.distance_all, dim=len(points), inputs=[d_points, params, out], device=backend.device)
            wp.synchronize_device(backend.device)
    elif name == "numba-cuda":
        cuda = backend.cuda
        namespace, params, h = backend._kernels(shape)
        d_points = cuda.to_device(points)
        centers, radii = cuda.to_device(np.full((1, 3), 1e30)), cuda.to_device(np.zeros(1))
        table = cuda.to_device(np.ones((len(points), 1), dtype=np.int64))
        out, out_direction = cuda.device_array(len(points)), cuda.device_array((0, 3))

        def run():
            backend._launch(namespace["clearance_all"], len(points), d_points, params, centers, radii, table, h,
                            out, out_direction)
            cuda.synchronize()
    else:
        raise ValueError(name)
    run()  # compile, or load
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        run()
        times.append(time.perf_counter() - start)
    return len(points) / float(np.median(times))


def packing_seconds(backend, shape, count, repeats) -> tuple[float, float]:
    """Median seconds of a fast-mode packing of ``count`` spheres, and its fill."""
    nd.pack(shape, min(count, 50), mode="fast", backend=backend)  # compile, or load
    times, fill = [], 0.0
    for _ in range(repeats):
        start = time.perf_counter()
        packing = nd.pack(shape, count, mode="fast", backend=backend)
        times.append(time.perf_counter() - start)
        assert packing.verify().ok
        fill = packing.fill
    return float(np.median(times)), fill


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--backends", nargs="+", default=["numba"])
    parser.add_argument("--points", type=int, default=400_000)
    parser.add_argument("--spheres", type=int, default=2000, help="spheres per packing (default 2000)")
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--shapes", nargs="+", default=["ball", "demo", "deep", "mesh"])
    parser.add_argument("--out")
    args = parser.parse_args(argv)

    catalogue = shapes()
    rows = []
    print(f"{'backend':14s} {'shape':6s} {'tape Md/s':>10s} {'spec. Md/s':>10s} {'ratio':>6s} "
          f"{'tape pack':>9s} {'spec. pack':>10s} {'ratio':>6s}")
    for spec in args.backends:
        name, _, device = spec.partition(":")
        backend = get_backend(name, device=device or None)
        for label in args.shapes:
            rng = np.random.default_rng(1)
            lower, upper = catalogue[label].bounds
            points = np.ascontiguousarray(lower + (upper - lower) * rng.random((args.points, 3)))
            result = {"backend": spec, "shape": label}
            for mode in ("tape", "specialised"):
                os.environ["NDPACK_KERNELS"] = mode
                shape = shapes()[label]  # a fresh object: nothing of the other mode cached on it
                result[f"{mode}_distances_per_s"] = distances_per_second(backend, shape, points, args.repeats)
                result[f"{mode}_pack_s"], result[f"{mode}_fill"] = packing_seconds(
                    backend, shape, args.spheres, max(1, args.repeats // 2))
            os.environ.pop("NDPACK_KERNELS")
            rows.append(result)
            print(f"{spec:14s} {label:6s} {result['tape_distances_per_s'] / 1e6:10.1f} "
                  f"{result['specialised_distances_per_s'] / 1e6:10.1f} "
                  f"{result['tape_distances_per_s'] / result['specialised_distances_per_s']:6.2f} "
                  f"{result['tape_pack_s']:8.2f}s {result['specialised_pack_s']:9.2f}s "
                  f"{result['tape_pack_s'] / result['specialised_pack_s']:6.2f}", flush=True)
            if args.out:  # after each row: a run cut short keeps what it measured
                write_json(Path(args.out), {"machine": machine_info(), "args": vars(args), "rows": rows})
    return 0


if __name__ == "__main__":
    sys.exit(main())
