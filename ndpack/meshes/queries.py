"""Mesh queries on the CPU: the kernel-language functions compiled by Numba, run by threads over points.

What the mesh oracle's NumPy-facing methods (and so the numpy backend) call. The traversal is the
one the compiled backends run (:mod:`ndpack.meshes.kernels`); this module only loops over points.
"""

from __future__ import annotations

import functools

import numpy as np

from ..kernels.compile import PARALLEL_FROM, numba_namespace
from ..kernels.program import Program
from ..parallel import run_in_slices
from . import kernels

_LOOPS = '''
def signed_all(first, last, points, prm, out):
    for i in range(first, last):
        out[i] = surface_distance(points[i], prm, 0)


def closest_all(first, last, points, prm, limit, signed, out_distance, out_closest, out_triangle):
    scale = prm[2]
    for i in range(first, last):
        q = np.empty(3)
        for j in range(3):
            q[j] = (points[i, j] - prm[3 + j]) / scale
        k = int(nearest_element(q, prm, 0, (limit / scale) ** 2))
        out_triangle[i] = k
        if k < 0:
            out_distance[i] = limit
            continue
        t = int(prm[8]) + 30 * k
        unsigned = np.sqrt(triangle_query(q, prm, t, 0)) * scale
        for j in range(3):
            out_closest[i, j] = triangle_query(q, prm, t, 2 + j) * scale + prm[3 + j]
        inside = False
        if signed and prm[1] == 0.0:
            inside = triangle_query(q, prm, t, 1) < 0.0
        elif signed:
            inside = mesh_winding_number(q, prm, 0) > 0.5
        out_distance[i] = -unsigned if inside else unsigned


def winding_all(first, last, points, prm, out):
    scale = prm[2]
    for i in range(first, last):
        q = np.empty(3)
        for j in range(3):
            q[j] = (points[i, j] - prm[3 + j]) / scale
        out[i] = mesh_winding_number(q, prm, 0)
'''


@functools.cache
def _namespace():
    """The compiled loops, each over a slice of the points and releasing the GIL, so that threads
    run them (:func:`ndpack.parallel.run_in_slices`; compiled once, then loaded from disk)."""
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


def winding_number(block: np.ndarray, points: np.ndarray) -> np.ndarray:
    """(n,) generalised winding numbers of ``points`` (n, 3): 1 inside a closed outward mesh, 0 outside."""
    out = np.empty(len(points))
    _run("winding_all", points, block, out)
    return out
