"""The Numba CPU backend: the reference's loops compiled to machine code, parallel over prototypes.

The kernels of a dimension compile once per machine, for every shape of built-ins (a tape, see
:mod:`ndpack.kernels.tape`), and are loaded from disk afterwards; the per-point
work is shared with the CUDA backend (:mod:`ndpack.backends.numba_kernels`, compiled through
:mod:`ndpack.backends.numba_common`). float64 throughout.
The spheres near a prototype's cell, and the prototypes a round's spheres touch, are found through
a sphere index (:mod:`ndpack.backends.sphere_index`), so neither costs a pass over every sphere.
"""

from __future__ import annotations

import math
import os
import time

import numpy as np

from ..kernels.compiled import compiled_program
from .base import Backend
from .numba_common import FD_STEP, compile_geometry_beside, geometry_kernels, program_kernels
from .prototypes import no_wall
from .sphere_index import SphereIndex

#: Above this many new spheres, :meth:`NumbaBackend.touched` indexes them instead of testing all.
INDEX_NEW_SPHERES = 32

#: A launch goes to all of Numba's threads only where the time they would spare it (its estimated
#: time on one thread, less its share of it) is at least ``GAIN`` times what waking them and
#: waiting for the last of them costs now (``overhead``, measured: see ``NumbaBackend._probe``);
#: a smaller one runs on one thread, in the calling thread. That cost is microseconds on a quiet
#: machine, where nearly every launch goes to the threads, and milliseconds on a busy one, where
#: a thread the scheduler has put off holds up the whole launch.
GAIN = 1.0
#: ... and never below this many seconds of work.
PARALLEL_MIN = 1e-5
#: The overhead is measured again at most this often (seconds), a parallel launch of a few
#: empty items, and the median of the last ``PROBES`` is taken.
PROBE_EVERY, PROBES = 1.0, 3

#: A fixed threshold instead (seconds of work on one thread), for benchmarks: ``NDPACK_PARALLEL_FROM``;
#: 0 runs every launch on all threads, as before issue 47. None: measured, as above.
PARALLEL_FROM = float(os.environ["NDPACK_PARALLEL_FROM"]) if os.environ.get("NDPACK_PARALLEL_FROM") else None

#: Seconds per unit of work of each entry (the units: see the callers of
#: :meth:`NumbaBackend._run`), a first guess that each backend refines from its launches on one thread.
RATES = {"converge_all": 2e-8, "clearance_all": 2e-8, "touched_all": 2e-9, "index_query": 1e-6}

#: A shape's distance, in units of a sphere's (what a converge step costs beyond the neighbours').
SHAPE_UNITS = 8

#: Only launches at least this long teach (shorter: the call's own cost rules).
LEARN_FROM = 5e-5

#: Every launch as ``(entry, items, units, on one thread, seconds, estimated seconds on one
#: thread)``, where a list (benchmarks set it).
trace = None


class NumbaBackend(Backend):
    """Numba on the CPU, float64, parallel over prototypes with ``prange``.

    Each launch goes to Numba's threads only where they would spare it more than waking them
    costs, which the backend measures about once a second: microseconds on a quiet machine,
    where nearly every launch goes to them, and milliseconds on a machine shared with other
    busy processes (the last of the threads waits for the scheduler), where only launches of
    tens of milliseconds' work do and the rest run on one thread, in the calling thread. So the
    default threads are never much slower than one, quiet or busy (bench/threads.py), and a
    shared machine needs no setting; ``NUMBA_NUM_THREADS=1`` (or ``threads=1``) also gives up
    the large launches that still pay there.

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
        self._rates = {}  # id(entry) -> seconds per unit of work, as its launches on one thread took
        self._overheads = []  # the last probes' seconds (see _probe)
        self._probed = -math.inf  # perf_counter time of the last probe
        self._overhead_now = 0.0  # their median

    def _kernels(self, shape):
        """The compiled namespace that runs ``shape``, its numbers and its finite-difference step."""
        flat = compiled_program(shape)
        compile_geometry_beside(shape.dim)
        return program_kernels(flat.program), flat.params, FD_STEP * shape.scale

    def _run(self, namespace, name, units, *args):
        """Launch entry ``name`` of ``namespace`` on ``args`` and return what it returns.

        ``units`` is the launch's work (the callers say in what; :data:`RATES` prices it, and
        learns from launches on one thread). Where the threads would spare it less than
        :data:`GAIN` times their overhead (see :data:`GAIN`), or one thread is all there is, it
        runs on one thread: Numba's OpenMP and TBB layers then run the loop in this thread,
        without waking the pool (the workqueue layer hands it to one of its threads). Else on
        all of them. The same compiled loop runs either way: the same bits.

        On 2 cores shared with other busy processes, a converge launch of 1.8 ms on one thread
        took 6 ms on two (the second waited for the scheduler; the probe measured 10 ms), and the
        4-D faithful packing of 1,000 spheres, seven thousand launches, took 36 s against 6 s now
        (7 s on one thread); on 2 quiet cores the same launch took 1.9 ms on two threads against
        3.8 ms, beside a 3 us probe (bench/threads.py; bench/results/threads_*.json).
        """
        function = namespace[name]
        threads = self.numba.get_num_threads() if self.threads is None else self.threads
        key = id(function)
        rate = self._rates.get(key, RATES[name])
        alone_time = units * rate
        if threads <= 1:
            alone = True
        elif PARALLEL_FROM is not None:
            alone = alone_time < PARALLEL_FROM
        else:
            alone = alone_time < PARALLEL_MIN or (
                alone_time * (1.0 - 1.0 / threads) < GAIN * self._overhead(args[0].shape[1], threads))
        started = time.perf_counter()
        result = self._launch(function, 1 if alone else self.threads, args)
        elapsed = time.perf_counter() - started
        if alone and elapsed >= LEARN_FROM and units > 0:
            # A fifth of the way towards the launch's own rate (in ratio, at most a factor 2
            # each way): about the median of its launches, which the scheduler rarely holds back.
            self._rates[key] = rate * min(max(elapsed / alone_time, 0.5), 2.0) ** 0.2
        if trace is not None:
            trace.append((name, len(args[0]), units, alone, elapsed, alone_time))
        return result

    def _overhead(self, dim, threads):
        """What a launch on all threads costs beyond its work now (seconds): the median of the
        last probes, probing again where the last is older than :data:`PROBE_EVERY`."""
        now = time.perf_counter()
        if now - self._probed >= PROBE_EVERY:
            if not self._overheads:
                self._probe(dim, threads)  # the first loads the kernel: not a measurement
            self._overheads = [*self._overheads[1 - PROBES:], self._probe(dim, threads)]
            self._overhead_now = sorted(self._overheads)[(len(self._overheads) - 1) // 2]  # the median
            self._probed = time.perf_counter()
        return self._overhead_now

    def _probe(self, dim, threads):
        """Seconds of one parallel launch of an item per thread and no work: waking the threads
        and waiting for the last of them (the geometry kernels' ``touched_all`` over no spheres)."""
        points = np.zeros((threads, dim))
        entry = geometry_kernels(dim)["touched_all"]
        arguments = (points, np.zeros(threads), np.zeros((0, dim)), np.zeros(0), np.empty(threads, dtype=np.int64))
        started = time.perf_counter()
        self._launch(entry, self.threads, arguments)
        return time.perf_counter() - started

    def _launch(self, function, threads, args):
        """``function(*args)`` on ``threads`` Numba threads (None: as many as Numba has)."""
        if threads is None:
            return function(*args)
        previous = self.numba.get_num_threads()
        if previous == threads:
            return function(*args)
        self.numba.set_num_threads(threads)
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
        neighbours = _i64(neighbours)
        self._run(namespace, "clearance_all", len(points) * (neighbours.shape[1] + SHAPE_UNITS), _f64(points), params,
                  _f64(centers), _f64(radii), neighbours, h, out, out_direction)
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
        neighbours = _i64(neighbours)
        units = len(points) * (len(steps) + 1 + tries) * (neighbours.shape[1] + SHAPE_UNITS)
        self._run(namespace, "converge_all", units, _f64(points), starts, tries, _f64(cell_lower),
                  _f64(cell_upper), _f64(no_wall(len(points)) if wall is None else wall), params,
                  _f64(centers), _f64(radii), neighbours, _f64(steps), h, out_points, out_clearance)
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
        self._run(geometry_kernels(box_lower.shape[1]), "index_query", count, _f64(box_lower), _f64(box_upper),
                  bound, 0, centers, radii, *index, np.empty(count, dtype=np.int64),
                  np.empty((count, 0), dtype=np.int64))
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
        # Count and fill in one walk, in a table as wide as the last calls' widest rows; only the
        # rows that overflow it walk again (a walk per pass is a third of this call's time).
        dim = box_lower.shape[1]
        width = self._widths.get(dim, 8)
        table = np.empty((count, width), dtype=np.int64)  # padded by the kernel
        self._run(namespace, "index_query", count, lower, upper, bound, 1, centers, radii, *index, counts, table)
        widest = int(counts.max())
        self._widths[dim] = max(widest, width // 2)  # one narrow call does not narrow the next
        if widest > width:
            over = np.flatnonzero(counts > width)
            wide = np.empty((len(over), widest), dtype=np.int64)
            self._run(namespace, "index_query", len(over), lower[over], upper[over], bound[over], 1, centers, radii,
                      *index, counts[over], wide)
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
            self._run(namespace, "touched_all", len(points) * (len(new_radii) + 1), points, clearance,
                      _f64(new_centers), _f64(new_radii), out)
            return out
        # Many new spheres (a large batch): index them, so each prototype looks only nearby.
        new_centers, new_radii = _f64(new_centers), _f64(new_radii)
        index = SphereIndex(namespace["index_insert_range"]).sync(new_centers, new_radii)
        bound = clearance.copy()
        nearest = np.empty((len(points), 1), dtype=np.int64)
        self._run(namespace, "index_query", len(points), points, points, bound, 0, new_centers, new_radii, *index,
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
