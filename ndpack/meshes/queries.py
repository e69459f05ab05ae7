"""Mesh queries on the CPU: the kernel-language functions compiled by Numba, run by threads over points.

What the mesh oracle's NumPy-facing methods (and so the numpy backend) call. The traversal is the
one the compiled backends run (:mod:`ndpack.meshes.kernels`); this module only loops over points.
"""

from __future__ import annotations

import functools

import numpy as np

from .. import compile_ahead as ahead
from ..kernels.compile import PARALLEL_FROM, announce, numba_namespace
from ..kernels.program import Program
from ..parallel import run_in_slices
from . import kernels

_LOOPS = '''
def signed_all(first, last, points, prm, out):
    for i in range(first, last):
        out[i] = surface_distance(points[i], prm, 0)


def nearest_signed(q, prm, limit, signed, near):
    # The nearest triangle to q (in the block's frame) within limit: its distance (signed by the
    # block's own sign method, where signed) and its id in leaf order, its nearest point written to
    # near (3,); (limit, -1) where none is within limit.
    scale = prm[2]
    k = int(nearest_element(q, prm, 0, (limit / scale) ** 2))
    if k < 0:
        return limit, k
    t = int(prm[8]) + 30 * k
    unsigned = np.sqrt(triangle_query(q, prm, t, 0)) * scale
    for j in range(3):
        near[j] = triangle_query(q, prm, t, 2 + j) * scale + prm[3 + j]
    inside = False
    if signed and prm[1] == 0.0:
        inside = triangle_query(q, prm, t, 1) < 0.0
    elif signed:
        inside = mesh_winding_number(q, prm, 0) > 0.5
    return (-unsigned if inside else unsigned), k


def closest_all(first, last, points, prm, limit, signed, out_distance, out_closest, out_triangle):
    scale = prm[2]
    q = np.empty(3)
    near = np.empty(3)
    for i in range(first, last):
        for j in range(3):
            q[j] = (points[i, j] - prm[3 + j]) / scale
        out_distance[i], out_triangle[i] = nearest_signed(q, prm, limit, signed, near)
        if out_triangle[i] >= 0:
            for j in range(3):
                out_closest[i, j] = near[j]


def step_in_all(first, last, points, lower, upper, prm, steps, margin, on_surface, vertices, faces, order,
                out_points, out_depth):
    # The loop of Oracle._step_inside, point by point, with closest_all's signed distance and the
    # mesh's _distance_and_gradient: the same operations in the same order, so the same numbers.
    scale = prm[2]
    p = np.empty(3)
    q = np.empty(3)
    g = np.empty(3)
    near = np.empty(3)
    e1 = np.empty(3)
    e2 = np.empty(3)
    for i in range(first, last):
        for j in range(3):
            p[j] = points[i, j]
        for _ in range(steps):
            for j in range(3):
                q[j] = (p[j] - prm[3 + j]) / scale
            distance, k = nearest_signed(q, prm, 1e30, True, near)  # closest()'s limit
            if k < 0:  # no triangle: no nearest point (unit_rows: the first axis)
                g[0], g[1], g[2] = 1.0, 0.0, 0.0
            else:
                if distance < 0.0:
                    break
                length = abs(distance)
                if length <= on_surface:  # no direction: the nearest triangle's normal
                    face = order[k]
                    a, b, c = faces[face, 0], faces[face, 1], faces[face, 2]
                    for j in range(3):
                        e1[j] = vertices[b, j] - vertices[a, j]
                        e2[j] = vertices[c, j] - vertices[a, j]
                    g[0] = e1[1] * e2[2] - e1[2] * e2[1]
                    g[1] = e1[2] * e2[0] - e1[0] * e2[2]
                    g[2] = e1[0] * e2[1] - e1[1] * e2[0]
                else:
                    sign = 1.0 if distance > 0.0 else 0.0
                    for j in range(3):
                        g[j] = sign * (p[j] - near[j]) / length
                norm = np.sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2])
                if norm > 0.0:
                    for j in range(3):
                        g[j] = g[j] / norm
                else:
                    g[0], g[1], g[2] = 1.0, 0.0, 0.0
            step = 1.5 * (distance + margin)
            for j in range(3):
                p[j] = min(max(p[j] - step * g[j], lower[i, j]), upper[i, j])
        for j in range(3):
            out_points[i, j] = p[j]
        out_depth[i] = -surface_distance(p, prm, 0)


def winding_all(first, last, points, prm, out):
    scale = prm[2]
    for i in range(first, last):
        q = np.empty(3)
        for j in range(3):
            q[j] = (points[i, j] - prm[3 + j]) / scale
        out[i] = mesh_winding_number(q, prm, 0)
'''


#: The loops' argument types as :func:`_run` passes them (Numba's words): what the compile helpers
#: compile them for (:func:`compile_ahead`).
SIGNATURES = {
    "signed_all": "(int64, int64, float64[:, ::1], float64[::1], float64[::1])",
    "winding_all": "(int64, int64, float64[:, ::1], float64[::1], float64[::1])",
    "closest_all": "(int64, int64, float64[:, ::1], float64[::1], float64, boolean, float64[::1], float64[:, ::1], "
                   "int64[::1])",
    "step_in_all": "(int64, int64, float64[:, ::1], float64[:, ::1], float64[:, ::1], float64[::1], int64, float64, "
                   "float64, float64[:, ::1], int64[:, ::1], int64[::1], float64[:, ::1], float64[::1])",
}
#: Their first compiles on 2 cores, in seconds (helpers share them by it).
WEIGHTS = {"signed_all": 3.0, "winding_all": 2.0, "closest_all": 3.0, "step_in_all": 3.5}


def compile_ahead() -> None:
    """Where Numba's disk cache lacks them, start helper processes compiling a mesh's kernels side
    by side (:mod:`ndpack.compile_ahead`): its tree's build, its winding data and these loops, which
    loading a mesh compiles one after the other (from 2 helpers up: one would compile them in turn)."""
    from . import bvh, layout

    jobs = []
    namespace = _dispatchers()
    for name, signature in SIGNATURES.items():
        if not ahead.on_disk(namespace[name]):
            jobs.append((_job(name), WEIGHTS[name], "ndpack.compile_ahead:compile_signature",
                         [__name__, "_dispatchers", name, signature]))
    for module, getter, function, signature, weight in (
            (bvh, "_compiled", bvh._build, bvh.SIGNATURE, 1.5),
            (layout, "_compiled_winding_data", layout._winding_data, layout.WINDING_SIGNATURE, 1.0)):
        jobs += ahead.job_unless_on_disk(function, module.AHEAD_JOB, weight, "ndpack.compile_ahead:compile_signature",
                                         [module.__name__, getter, None, signature])
    if ahead.start(jobs, least=2):
        # Its typical time: loading the armadillo on a fresh H100's host took 7.0-7.5 s with helpers, 2-3 s of
        # it reading the file (bench/results/fresh_machine_h100_issue48_step12_turn*_now.json).
        announce("numba", "a mesh's tree, winding data and queries, by helper processes", typical=5)


def _job(name: str) -> str:
    return f"numba: the mesh query {name}"


def _namespace():
    """The compiled loops, each over a slice of the points and releasing the GIL, so that threads
    run them (:func:`ndpack.parallel.run_in_slices`; compiled once, then loaded from disk, where
    compile helpers may have put them)."""
    for name in SIGNATURES:
        ahead.wait(_job(name))
    return _dispatchers()


@functools.cache
def _dispatchers():
    """The loops as Numba's dispatchers: nothing compiles until one is called."""
    import numba

    program = Program(3, "mesh queries")
    kernels.add_queries(program)
    for function in (kernels.nearest_element, kernels.triangle_query, kernels.mesh_winding_number):
        program.use(function)

    def jit(namespace, names):
        for name in names:
            namespace[name] = numba.njit(nogil=True, cache=True)(namespace[name])

    return numba_namespace(program, "cpu", _LOOPS, jit)


#: A mesh query costs microseconds a point, so threads pay from fewer points than the general
#: kernels' :data:`~ndpack.kernels.compile.PARALLEL_FROM`.
PARALLEL_FROM_MESH = min(PARALLEL_FROM, 1_000)


def _run(name: str, points: np.ndarray, *args):
    run_in_slices(_namespace()[name], len(points), np.ascontiguousarray(points, dtype=np.float64), *args,
                  serial_below=PARALLEL_FROM_MESH)


def signed_distance(block: np.ndarray, points: np.ndarray) -> np.ndarray:
    """(n,) signed distances of ``points`` (n, 3) to the mesh packed in ``block`` (its own offsets)."""
    out = np.empty(len(points))
    _run("signed_all", points, block, out)
    return out


def closest(block: np.ndarray, points: np.ndarray, limit: float = np.inf, signed: bool = False):
    """Nearest surface points of ``points`` (n, 3) within ``limit``.

    Returns
    -------
    distance : (n,) float64
        Unsigned, or signed by the block's own sign method (``signed=True``); ``limit`` where no
        triangle is within ``limit``.
    closest : (n, 3) float64
        Nearest points (NaN where none is within ``limit``).
    triangle : (n,) int64
        The nearest triangle in leaf order, or -1.
    """
    n = len(points)
    distance, closest_points = np.empty(n), np.full((n, 3), np.nan)
    triangle = np.empty(n, dtype=np.int64)
    limit = min(float(limit), 1e30)
    _run("closest_all", points, block, limit, signed, distance, closest_points, triangle)
    return distance, closest_points, triangle


#: A step in costs up to its ``steps`` queries a point, so threads should pay from fewer points than
#: one query's :data:`PARALLEL_FROM_MESH` (a choice, not tuned: the set-up's 1,208 points use them).
PARALLEL_FROM_STEP_IN = 64


def step_in(block: np.ndarray, points: np.ndarray, lower: np.ndarray, upper: np.ndarray, steps: int, margin: float,
            on_surface: float, vertices: np.ndarray, faces: np.ndarray, order: np.ndarray):
    """:meth:`ndpack.Oracle._step_inside` of the mesh packed in ``block``, point by point on threads.

    Parameters
    ----------
    points, lower, upper : (k, 3) float64
        The points and the boxes they stay in.
    steps : int and margin : float
        As ``_step_inside`` takes them.
    on_surface : float
        A distance up to which a point is on the surface, where the nearest triangle's normal
        (of ``vertices`` (v, 3) float64, ``faces`` (f, 3) int64 in the block's ``order`` (f,) int64)
        is the direction.

    Returns
    -------
    points : (k, 3) float64 and depth : (k,) float64
    """
    k = len(points)
    out_points, out_depth = np.empty((k, 3)), np.empty(k)
    run_in_slices(_namespace()["step_in_all"], k, np.ascontiguousarray(points, dtype=np.float64),
                  np.ascontiguousarray(lower, dtype=np.float64), np.ascontiguousarray(upper, dtype=np.float64), block,
                  int(steps), float(margin), float(on_surface), vertices, faces, order, out_points, out_depth,
                  serial_below=PARALLEL_FROM_STEP_IN)
    return out_points, out_depth


def winding_number(block: np.ndarray, points: np.ndarray) -> np.ndarray:
    """(n,) generalised winding numbers of ``points`` (n, 3): 1 inside a closed outward mesh, 0 outside."""
    out = np.empty(len(points))
    _run("winding_all", points, block, out)
    return out
