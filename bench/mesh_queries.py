"""Signed-distance queries per second on a triangle mesh: every ndpack backend beside Warp's
``wp.Mesh``, fcpw and libigl, in one run.

Each engine answers the same points (uniform in the mesh's box enlarged by 5%, so about a third
inside): the signed distance by its exact sign method for closed meshes (pseudo-normals, or
fcpw's inside test). Repeats go round-robin over the engines, so a noisy neighbour slows them all
alike; the table gives medians. Errors are against ndpack's float64 CPU answer, itself tested
against libigl in ``tests/shapes/test_mesh.py``.

    python bench/mesh_queries.py                               # armadillo, then subdivided once
    python bench/mesh_queries.py --points 50000 --repeats 3 --out bench/results/x.json
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

import numpy as np

import ndpack as nd
from _common import machine_info, write_json

HERE = Path(__file__).resolve().parent
DEFAULT_MESH = HERE.parent.parent / "shared" / "data" / "meshes" / "armadillo.obj"


# ---------------------------------------------------------------------- engines
def ndpack_engines(mesh, points):
    """Each ndpack backend that works here, as (name, device, build seconds, query function)."""
    engines = [("ndpack numba-cpu (oracle)", "cpu", 0.0, lambda: mesh.distance(points))]
    from ndpack import backends

    for name, options in (("numba", {}), ("warp", {"precision": "float32"}), ("warp", {"precision": "float64"}),
                          ("numba-cuda", {})):
        try:
            backend = backends.get_backend(name, **options)
        except nd.BackendError:
            continue
        device = getattr(backend, "device", "cpu")
        device = f"cuda:{device}" if name == "numba-cuda" else device
        started = time.perf_counter()
        backend.distance(mesh, points[:64])  # compiles and uploads the mesh
        label = f"ndpack {name}" + (f" {options['precision']}" if options else "")
        engines.append((label, str(device), time.perf_counter() - started,
                        lambda backend=backend: backend.distance(mesh, points)))
    return engines


def warp_mesh_engines(mesh, points):
    """``wp.Mesh`` with pseudo-normal sign (float32), on Warp's CUDA device if there is one."""
    try:
        import warp as wp
    except ImportError:
        return []
    wp.config.quiet = True
    wp.init()
    device = "cuda:0" if wp.is_cuda_available() else "cpu"

    @wp.kernel
    def signed(mesh_id: wp.uint64, queries: wp.array(dtype=wp.vec3), out: wp.array(dtype=float)):
        i = wp.tid()
        p = queries[i]
        hit = wp.mesh_query_point_sign_normal(mesh_id, p, 1.0e6)
        if hit.result:
            out[i] = hit.sign * wp.length(p - wp.mesh_eval_position(mesh_id, hit.face, hit.u, hit.v))

    started = time.perf_counter()
    surface = wp.Mesh(points=wp.array(mesh.vertices.astype(np.float32), dtype=wp.vec3, device=device),
                      indices=wp.array(mesh.faces.astype(np.int32).ravel(), dtype=wp.int32, device=device))
    build = time.perf_counter() - started

    def run():
        queries = wp.array(points.astype(np.float32), dtype=wp.vec3, device=device)
        out = wp.zeros(len(points), dtype=float, device=device)
        wp.launch(signed, dim=len(points), inputs=[surface.id, queries, out], device=device)
        return out.numpy().astype(np.float64)

    run.keep = surface  # the mesh must outlive its id
    return [("warp wp.Mesh float32", device, build, run)]


def fcpw_engines(mesh, points):
    try:
        import fcpw
    except ImportError:
        return []
    started = time.perf_counter()
    scene = fcpw.scene_3D()
    scene.set_object_count(1)
    scene.set_object_vertices(np.asfortranarray(mesh.vertices, np.float32), 0)
    scene.set_object_triangles(np.asfortranarray(mesh.faces, np.int32), 0)
    scene.build(fcpw.aggregate_type.bvh_surface_area, False, False, False)
    build = time.perf_counter() - started
    queries = np.asfortranarray(points, np.float32)
    as_list = fcpw.float_3D_list(list(queries))

    def run():
        hits = fcpw.interaction_3D_list()
        scene.find_closest_points(queries, np.full(len(points), np.inf, np.float32), hits, False)
        inside = fcpw.uint32_list()
        scene.contains(as_list, inside)  # fcpw's array form of contains returns zeros in 1.2.0
        distance = np.fromiter((hit.d for hit in hits), np.float64, len(points))
        return np.where(np.array(inside) == 1, -distance, distance)

    return [("fcpw (closest + contains) float32", "cpu", build, run)]


def libigl_engines(mesh, points):
    try:
        import igl
    except ImportError:
        return []
    vertices, faces = mesh.vertices, mesh.faces
    started = time.perf_counter()
    tree = igl.AABB()
    tree.init(vertices, faces)
    build = time.perf_counter() - started

    def unsigned():
        return np.sqrt(tree.squared_distance(vertices, faces, points)[0])

    def signed():
        kind = igl.SignedDistanceType.SIGNED_DISTANCE_TYPE_PSEUDONORMAL
        return igl.signed_distance(points, vertices, faces, kind)[0]

    return [("libigl AABB unsigned", "cpu", build, unsigned),
            ("libigl signed_distance pseudonormal", "cpu", 0.0, signed)]


# ---------------------------------------------------------------------- run
def measure(mesh, count, repeats, seed=0):
    lower, upper = mesh.bounds
    centre, half = (lower + upper) / 2, (upper - lower) / 2 * 1.05
    points = centre + np.random.default_rng(seed).uniform(-1, 1, (count, 3)) * half
    reference = mesh.distance(points)
    engines = ndpack_engines(mesh, points) + warp_mesh_engines(mesh, points) + fcpw_engines(mesh, points)
    engines += libigl_engines(mesh, points)
    errors, times = {}, {name: [] for name, *_ in engines}
    for name, _, _, run in engines:  # warm-up (compiles), and the accuracy check
        got = run()
        unsigned = "unsigned" in name
        errors[name] = float(np.abs((np.abs(reference) if unsigned else reference) - got).max())
    for _ in range(repeats):
        for name, _, _, run in engines:
            started = time.perf_counter()
            run()
            times[name].append(time.perf_counter() - started)
    rows = []
    for name, device, build, _ in engines:
        median = float(np.median(times[name]))
        rows.append({"engine": name, "device": device, "build_s": round(build, 4), "median_s": median,
                     "queries_per_s": count / median, "max_error": errors[name],
                     "max_error_relative": errors[name] / float(np.ptp(mesh.vertices, axis=0).max())})
    return rows


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--mesh", default=str(DEFAULT_MESH))
    parser.add_argument("--points", type=int, default=200_000)
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--no-subdivided", action="store_true", help="skip the once-subdivided mesh")
    parser.add_argument("--out", default=str(HERE / "results" / "mesh_queries.json"))
    args = parser.parse_args()

    import numba
    import trimesh

    # Numba compiles the mesh queries once a process: timed apart, on a small box.
    started = time.perf_counter()
    nd.TriangleMesh.from_trimesh(trimesh.creation.box()).distance(np.zeros((1, 3)))
    compile_s = time.perf_counter() - started
    source = trimesh.load(args.mesh, force="mesh")
    variants = [("armadillo", source)]
    if not args.no_subdivided:
        variants.append(("armadillo subdivided", source.subdivide()))
    results = {"machine": machine_info(), "numba_threads": numba.get_num_threads(),
               "igl_threads": os.environ.get("IGL_NUM_THREADS", "all cores"), "points": args.points,
               "repeats": args.repeats, "first_mesh_compile_s": compile_s, "meshes": []}
    print(f"first mesh in the process (Numba compiles the queries): {compile_s:.1f} s")
    for label, surface in variants:
        started = time.perf_counter()
        mesh = nd.TriangleMesh.from_trimesh(surface)
        build = time.perf_counter() - started
        rows = measure(mesh, args.points, args.repeats)
        results["meshes"].append({"mesh": label, "triangles": mesh.n_triangles, "ndpack_build_s": build,
                                  "sign_method": mesh.sign_method, "rows": rows})
        print(f"\n{label}: {mesh.n_triangles:,} triangles, ndpack build {build:.2f} s (sign: {mesh.sign_method})")
        print("| engine | device | build s | queries/s | max error / size |\n|---|---|---|---|---|")
        for row in rows:
            print(f"| {row['engine']} | {row['device']} | {row['build_s']:.3f} | {row['queries_per_s']:,.0f} | "
                  f"{row['max_error_relative']:.1e} |")
    write_json(Path(args.out), results)
    print(f"\nwrote {args.out}")


if __name__ == "__main__":
    main()
