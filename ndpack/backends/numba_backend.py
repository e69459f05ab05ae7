"""The Numba CPU backend: the reference's loops compiled to machine code, parallel over prototypes.

The kernels of a dimension compile once per machine, for every shape of built-ins (a tape, see
:mod:`ndpack.kernels.tape`), and are loaded from disk afterwards; the per-point
work is shared with the CUDA backend (:mod:`ndpack.backends.numba_kernels`, compiled through
:mod:`ndpack.backends.numba_common`). float64 throughout.
The spheres near a prototype's cell, and the prototypes a round's spheres touch, are found through
a sphere index (:mod:`ndpack.backends.sphere_index`), so neither costs a pass over every sphere.
"""

from __future__ import annotations

import numpy as np

from ..kernels.compiled import compiled_program
from .base import Backend
from .numba_common import FD_STEP, compile_geometry_beside, geometry_kernels, program_kernels
from .prototypes import no_wall
from .sphere_index import SphereIndex

#: Above this many new spheres, :meth:`NumbaBackend.touched` indexes them instead of testing all.
INDEX_NEW_SPHERES = 32


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
        self._indexes = {}  # dim -> SphereIndex of the spheres last asked about
        self._widths = {}  # dim -> near_spheres' first table width (its recent widest rows)

    def _kernels(self, shape):
        """The compiled namespace that runs ``shape``, its numbers and its finite-difference step."""
        flat = compiled_program(shape)
        compile_geometry_beside(shape.dim)
        return program_kernels(flat.program), flat.params, FD_STEP * shape.scale

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
        if not directions:  # converging in no steps measures the clearance: one kernel fewer to compile
            return self.converge(shape, points, points, points, centers, radii, neighbours, np.zeros(0))[1], None
        namespace, params, h = self._kernels(shape)
        out = np.empty(len(points))
        out_direction = np.empty((len(points) if directions else 0, shape.dim))
        self._run(namespace["clearance_all"], _f64(points), params, _f64(centers), _f64(radii),
                  _i64(neighbours), h, out, out_direction)
        return out, out_direction

    def distance(self, shape, points):
        # With no spheres the clearance is minus the distance, exactly: one kernel fewer to compile.
        none = np.zeros((len(points), 0), dtype=np.int64)
        return -self._free_space(shape, points, np.zeros((0, shape.dim)), np.zeros(0), none, directions=False)[0]

    def converge(self, shape, points, cell_lower, cell_upper, centers, radii, neighbours, steps, wall=None,
                 starts=None):
        namespace, params, h = self._kernels(shape)
        out_points = np.empty_like(points)
        out_clearance = np.empty(len(points))
        tries = 0 if starts is None else len(starts)
        starts = _f64(starts) if tries else np.zeros((1, len(points), shape.dim))
        self._run(namespace["converge_all"], _f64(points), starts, tries, _f64(cell_lower), _f64(cell_upper),
                  _f64(no_wall(len(points)) if wall is None else wall), params,
                  _f64(centers), _f64(radii), _i64(neighbours), _f64(steps), h, out_points, out_clearance)
        return out_points, out_clearance

    def tightened_reach(self, box_lower, box_upper, reach, centers, radii):
        return self._bound_walk(box_lower, box_upper, reach, centers, radii)[0]

    def _bound_walk(self, box_lower, box_upper, reach, centers, radii):
        """The sphere index's first walk: the tightened reach (n,), and the index (None with no
        spheres or boxes); it counts, filling nothing."""
        bound = _f64(reach).copy()
        count = len(box_lower)
        if len(centers) == 0 or count == 0:
            return bound, None
        centers, radii = _f64(centers), _f64(radii)
        index = self._index(box_lower.shape[1]).sync(centers, radii)
        self._run(geometry_kernels(box_lower.shape[1])["index_query"], _f64(box_lower), _f64(box_upper), bound, 0,
                  centers, radii, *index, np.empty(count, dtype=np.int64), np.empty((count, 0), dtype=np.int64))
        return bound, index

    def near_spheres(self, box_lower, box_upper, reach, centers, radii, return_bound=False):
        namespace = geometry_kernels(box_lower.shape[1])
        count = len(box_lower)
        bound, index = self._bound_walk(box_lower, box_upper, reach, centers, radii)
        if index is None:
            table = np.zeros((count, 0), dtype=np.int64)
            return (table, bound) if return_bound else table
        centers, radii = _f64(centers), _f64(radii)
        lower, upper = _f64(box_lower), _f64(box_upper)
        counts = np.empty(count, dtype=np.int64)
        query = namespace["index_query"]
        # Count and fill in one walk, in a table as wide as the last calls' widest rows; only the
        # rows that overflow it walk again (a walk per pass is a third of this call's time).
        dim = box_lower.shape[1]
        width = self._widths.get(dim, 8)
        table = np.full((count, width), len(centers), dtype=np.int64)
        self._run(query, lower, upper, bound, 1, centers, radii, *index, counts, table)
        widest = int(counts.max())
        self._widths[dim] = max(widest, width // 2)  # one narrow call does not narrow the next
        if widest > width:
            over = np.flatnonzero(counts > width)
            wide = np.full((len(over), widest), len(centers), dtype=np.int64)
            self._run(query, lower[over], upper[over], bound[over], 1, centers, radii, *index, counts[over], wide)
            table = np.concatenate([table, np.full((count, widest - width), len(centers), dtype=np.int64)], axis=1)
            table[over] = wide
        elif widest < width:
            table = np.ascontiguousarray(table[:, :widest])
        table.sort(axis=1)  # the order of the reference (ascending ids, padding last)
        return (table, bound) if return_bound else table

    def _index(self, dim):
        """The sphere index of this backend's current packing (one per dimension)."""
        if dim not in self._indexes:
            self._indexes[dim] = SphereIndex(geometry_kernels(dim)["index_insert_range"])
        return self._indexes[dim]

    def touched(self, points, clearance, new_centers, new_radii):
        namespace = geometry_kernels(points.shape[1])
        points, clearance = _f64(points), _f64(clearance)
        if len(new_radii) <= INDEX_NEW_SPHERES:
            out = np.empty(len(points), dtype=np.int64)
            self._run(namespace["touched_all"], points, clearance, _f64(new_centers), _f64(new_radii), out)
            return out
        # Many new spheres (a large batch): index them, so each prototype looks only nearby.
        new_centers, new_radii = _f64(new_centers), _f64(new_radii)
        index = SphereIndex(namespace["index_insert_range"]).sync(new_centers, new_radii)
        bound = clearance.copy()
        nearest = np.empty((len(points), 1), dtype=np.int64)
        self._run(namespace["index_query"], points, points, bound, 0, new_centers, new_radii, *index,
                  np.empty(0, dtype=np.int64), nearest)
        return nearest[:, 0]


def warm_geometry(dim: int) -> None:
    """Compile (or load) the shape-free kernels of ``dim`` by running them on a few spheres, with
    the argument types a packing passes: what :func:`compile_geometry_beside`'s process runs."""
    rng = np.random.default_rng(0)
    backend = NumbaBackend()
    centers, radii = rng.random((40, dim)), np.full(40, 0.01)
    points = rng.random((8, dim))
    backend.near_spheres(points, points + 0.1, np.ones(8), centers, radii, return_bound=True)
    backend.touched(points, np.full(8, 0.1), centers[:2], radii[:2])
    backend.touched(points, np.full(8, 0.1), centers, radii)


def _f64(array):
    return np.ascontiguousarray(array, dtype=np.float64)


def _i64(array):
    return np.ascontiguousarray(array, dtype=np.int64)
