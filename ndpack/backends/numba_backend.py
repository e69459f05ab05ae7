"""The Numba CPU backend: the reference's loops compiled to machine code, parallel over prototypes.

Each shape compiles once per structure and dimension (see :mod:`ndpack.kernels`); the per-point
work is shared with the CUDA backend (:mod:`ndpack.backends.numba_kernels`). float64 throughout.
The spheres near a prototype's cell, and the prototypes a round's spheres touch, are found through
a sphere index (:mod:`ndpack.backends.sphere_index`), so neither costs a pass over every sphere.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .base import Backend, compiled_program, no_wall

#: The per-point functions, as text (see numba_kernels.py).
KERNELS = Path(__file__).with_name("numba_kernels.py").read_text()

#: Entry points: a parallel loop over prototypes (or boxes) calling the per-point functions.
ENTRIES = '''
def clearance_all(points, prm, centers, radii, nbr, out, out_direction):
    for i in prange(points.shape[0]):
        clearance_one(i, points, prm, centers, radii, nbr, out, out_direction)


def distance_all(points, prm, out):
    for i in prange(points.shape[0]):
        out[i] = sd(points[i], prm)


def converge_all(points, starts, tries, lower, upper, wall, prm, centers, radii, nbr, steps, out_points,
                 out_clearance):
    for i in prange(points.shape[0]):
        converge_one(i, points, starts, tries, lower, upper, wall, prm, centers, radii, nbr, steps, out_points,
                     out_clearance)


def touched_all(points, clearance, centers, radii, out):
    for i in prange(points.shape[0]):
        touched_one(i, points, clearance, centers, radii, out)


def index_insert_range(start, stop, centers, radii, origin, top, heads, nxt, level_of, level_head, level_next,
                       level_count, level_rmax):
    for s in range(start, stop):
        index_insert(s, centers, radii, origin, top, heads, nxt, level_of, level_head, level_next, level_count,
                     level_rmax)


def index_bound(lower, upper, reach, centers, radii, origin, top, heads, nxt, level_of, level_head, level_next,
                level_count, level_rmax, out):
    for b in prange(lower.shape[0]):
        out[b] = index_near(b, lower, upper, reach[b], 0, centers, radii, origin, top, heads, nxt, level_of,
                            level_head, level_next, level_count, level_rmax, heads.reshape(1, -1), 0, 0)[0]


def index_fill(lower, upper, bound, centers, radii, origin, top, heads, nxt, level_of, level_head, level_next,
               level_count, level_rmax, counts, out):
    for b in prange(lower.shape[0]):
        counts[b] = index_near(b, lower, upper, bound[b], 1, centers, radii, origin, top, heads, nxt, level_of,
                               level_head, level_next, level_count, level_rmax, out, b, out.shape[1])[1]
'''

#: Central-difference step, as a fraction of the shape's scale: float64 rounding in the
#: difference is about 1e-16 / 1e-6 of the gradient, truncation about 1e-12 for unit curvature.
FD_STEP = 1e-6
#: Above this many new spheres, :meth:`NumbaBackend.touched` indexes them instead of testing all.
INDEX_NEW_SPHERES = 32
ENTRY_NAMES = ("distance_all", "clearance_all", "converge_all", "touched_all", "index_bound", "index_fill")


def _jit(namespace, names):
    import numba

    for name in names:
        parallel = name in ENTRY_NAMES
        namespace[name] = numba.njit(parallel=parallel, cache=True)(namespace[name])


class NumbaBackend(Backend):
    """Numba on the CPU, float64, parallel over prototypes with ``prange``.

    Parameters
    ----------
    threads : int, optional
        Numba threads to use; default all (``NUMBA_NUM_THREADS``).
    """

    name = "numba"

    def __init__(self, threads: int | None = None):
        import numba

        self.numba = numba
        self.threads = threads
        self._namespaces = {}  # id(program) -> (program, namespace)
        self._indexes = {}  # dim -> SphereIndex of the spheres last asked about

    def _kernels(self, shape):
        from ..kernels.compile import numba_namespace

        program, params = compiled_program(shape)
        if id(program) in self._namespaces:
            return self._namespaces[id(program)][1], params
        namespace = numba_namespace(program, "cpu", KERNELS + ENTRIES, {"H": FD_STEP * shape.scale}, _jit)
        self._namespaces[id(program)] = (program, namespace)
        return namespace, params

    def _run(self, function, *args):
        if self.threads is None:
            return function(*args)
        previous = self.numba.get_num_threads()
        self.numba.set_num_threads(self.threads)
        try:
            return function(*args)
        finally:
            self.numba.set_num_threads(previous)

    def _free_space(self, shape, points, centers, radii, neighbours, directions):
        namespace, params = self._kernels(shape)
        out = np.empty(len(points))
        out_direction = np.empty((len(points) if directions else 0, shape.dim))
        self._run(namespace["clearance_all"], _f64(points), params, _f64(centers), _f64(radii),
                  _i64(neighbours), out, out_direction)
        return out, out_direction

    def distance(self, shape, points):
        namespace, params = self._kernels(shape)
        out = np.empty(len(points))
        self._run(namespace["distance_all"], _f64(points), params, out)
        return out

    def converge(self, shape, points, cell_lower, cell_upper, centers, radii, neighbours, steps, wall=None,
                 starts=None):
        namespace, params = self._kernels(shape)
        out_points = np.empty_like(points)
        out_clearance = np.empty(len(points))
        tries = 0 if starts is None else len(starts)
        starts = _f64(starts) if tries else np.zeros((1, len(points), shape.dim))
        self._run(namespace["converge_all"], _f64(points), starts, tries, _f64(cell_lower), _f64(cell_upper),
                  _f64(no_wall(len(points)) if wall is None else wall), params,
                  _f64(centers), _f64(radii), _i64(neighbours), _f64(steps), out_points, out_clearance)
        return out_points, out_clearance

    def near_spheres(self, box_lower, box_upper, reach, centers, radii, return_bound=False):
        namespace = geometry_kernels(box_lower.shape[1])
        count = len(box_lower)
        if len(centers) == 0 or count == 0:
            table = np.zeros((count, 0), dtype=np.int64)
            return (table, _f64(reach).copy()) if return_bound else table
        centers, radii = _f64(centers), _f64(radii)
        index = self._index(box_lower.shape[1]).sync(centers, radii)
        lower, upper = _f64(box_lower), _f64(box_upper)
        bound = np.empty(count)
        self._run(namespace["index_bound"], lower, upper, _f64(reach), centers, radii, *index, bound)
        counts = np.empty(count, dtype=np.int64)
        self._run(namespace["index_fill"], lower, upper, bound, centers, radii, *index, counts,
                  np.empty((count, 0), dtype=np.int64))
        table = np.full((count, int(counts.max())), len(centers), dtype=np.int64)
        self._run(namespace["index_fill"], lower, upper, bound, centers, radii, *index, counts, table)
        table.sort(axis=1)  # the order of the reference (ascending ids, padding last)
        return (table, bound) if return_bound else table

    def _index(self, dim):
        """The sphere index of this backend's current packing (one per dimension)."""
        from .sphere_index import SphereIndex

        if dim not in self._indexes:
            self._indexes[dim] = SphereIndex(geometry_kernels(dim)["index_insert_range"])
        return self._indexes[dim]

    def touched(self, points, clearance, new_centers, new_radii):
        namespace = geometry_kernels(points.shape[1])
        points, clearance = _f64(points), _f64(clearance)
        if len(new_radii) <= INDEX_NEW_SPHERES:
            out = np.empty(len(points), dtype=np.bool_)
            self._run(namespace["touched_all"], points, clearance, _f64(new_centers), _f64(new_radii), out)
            return out
        # Many new spheres (a large batch): index them, so each prototype looks only nearby.
        from .sphere_index import SphereIndex

        new_centers, new_radii = _f64(new_centers), _f64(new_radii)
        index = SphereIndex(namespace["index_insert_range"]).sync(new_centers, new_radii)
        bound = np.empty(len(points))
        self._run(namespace["index_bound"], points, points, clearance, new_centers, new_radii, *index, bound)
        return bound < clearance


_geometry_kernels = {}


def geometry_kernels(dim):
    """The shape-free kernels (near_spheres, touched) for dimension ``dim``."""
    if dim in _geometry_kernels:
        return _geometry_kernels[dim]
    from ..kernels.compile import numba_namespace
    from ..kernels.program import shape_free

    _geometry_kernels[dim] = numba_namespace(shape_free(dim), "cpu", KERNELS + ENTRIES, {"H": 1.0}, _jit)
    return _geometry_kernels[dim]


def _f64(array):
    return np.ascontiguousarray(array, dtype=np.float64)


def _i64(array):
    return np.ascontiguousarray(array, dtype=np.int64)
