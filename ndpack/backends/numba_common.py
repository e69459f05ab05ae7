"""What the Numba backends share: the per-point kernels' text, the CPU entry points and their
compiled namespaces, among them the shape-free geometry kernels (the sphere index's).

:mod:`ndpack.backends.numba_backend` runs them on the CPU; :mod:`ndpack.backends.sphere_index`
inserts spheres with them for every backend's device index, and the CUDA backend prints the same
per-point functions (:data:`KERNELS`) as device code. Nothing here imports Numba until a kernel is
compiled.
"""

from __future__ import annotations

from pathlib import Path

from .. import compile_ahead as ahead
from ..kernels.compile import numba_namespace
from ..kernels.portable import render
from ..kernels.tape import interpreter
from .kernel_texts import INDEX, MOVE, portable_text


#: The per-point functions, as text: Numba's own (numba_kernels.py), then the move and the sphere index's
#: queries, written once for every compiled backend (move_kernels.py, index_kernels.py).
KERNELS = (Path(__file__).with_name("numba_kernels.py").read_text() + "\n\n"
           + render(portable_text(MOVE, INDEX), "numba"))


#: Entry points: a parallel loop over prototypes (or boxes) calling the per-point functions.
ENTRIES = '''
def clearance_all(points, prm, centers, radii, nbr, h, out, out_direction):
    for i in prange(points.shape[0]):
        clearance_one(i, points, prm, centers, radii, nbr, h, out, out_direction)


def converge_all(points, starts, tries, lower, upper, wall, prm, centers, radii, nbr, steps, h, out_points,
                 out_clearance):
    for i in prange(points.shape[0]):
        converge_one(i, 0, points, starts, tries, lower, upper, wall, prm, centers, radii, nbr, steps, h, out_points,
                     out_clearance)


def touched_all(points, clearance, centers, radii, out):
    for i in prange(points.shape[0]):
        touched_one(i, points, clearance, centers, radii, out)


def index_insert_range(start, stop, centers, radii, origin, top, heads, nxt, level_of, level_head, level_next,
                       level_count, level_rmax):
    for s in range(start, stop):
        index_insert(s, centers, radii, origin, top, heads, nxt, level_of, level_head, level_next, level_count,
                     level_rmax)


def index_query(lower, upper, bound, counting, centers, radii, origin, top, heads, nxt, level_of, level_head,
                level_next, level_count, level_rmax, counts, out):
    for b in prange(lower.shape[0]):
        # counting 0: tighten bound[b] (and put the sphere that did in out[b, 0], if out has a
        # column); 1: count the spheres within it, the first of them in out[b] (one kernel for
        # all: each parallel entry costs seconds to compile on first use).
        if counting == 0:
            bound[b] = index_near(b, lower, upper, bound[b], 0, centers, radii, origin, top, heads, nxt, level_of,
                                  level_head, level_next, level_count, level_rmax, out, b, out.shape[1])[0]
        else:
            counts[b] = index_near(b, lower, upper, bound[b], 1, centers, radii, origin, top, heads, nxt, level_of,
                                   level_head, level_next, level_count, level_rmax, out, b, out.shape[1])[1]
            for j in range(counts[b], out.shape[1]):  # the padding, here where the row is warm
                out[b, j] = radii.shape[0]
'''

#: Central-difference step, as a fraction of the shape's scale: float64 rounding in the
#: difference is about 1e-16 / 1e-6 of the gradient, truncation about 1e-12 for unit curvature.
FD_STEP = 1e-6
ENTRY_NAMES = ("clearance_all", "converge_all", "touched_all", "index_query")


def _jit(namespace, names):
    import numba

    for name in names:
        parallel = name in ENTRY_NAMES
        namespace[name] = numba.njit(parallel=parallel, cache=True)(namespace[name])


_namespaces = {}  # id(program) -> (program, namespace)


def program_kernels(program):
    """The backend's kernels compiled with ``program`` (cached: in this process, and on disk by
    Numba)."""
    if id(program) not in _namespaces:
        _namespaces[id(program)] = (program, numba_namespace(program, "cpu", KERNELS + ENTRIES, _jit))
    return _namespaces[id(program)][1]


def geometry_kernels(dim, wait: bool = True):
    """The shape-free kernels (near_spheres, touched) for dimension ``dim``: those of the tape
    interpreter's namespace, which the shapes of built-ins share. Where a helper process is
    compiling them (:func:`compile_geometry_beside`), waits for it first (unless not ``wait``)."""
    if wait:
        ahead.wait(_geometry_job(dim))
    return program_kernels(interpreter(dim))


#: The shape-free entry points every packing calls.
GEOMETRY_ENTRIES = ("index_query", "touched_all", "index_insert_range")
_asked: set[int] = set()  # the dimensions compile_geometry_beside has looked at


def _geometry_job(dim: int) -> str:
    return f"numba: the shape-free kernels of {int(dim)}-D"


def compile_geometry_beside(dim: int) -> None:
    """Where this machine has not compiled the shape-free kernels of ``dim`` yet, compile them in
    a helper process while this one compiles the shape's (:mod:`ndpack.compile_ahead`), where two
    helpers could start (3 cores and up). Numba's disk cache hands the result over. On 2 cores it
    once paid (a first ``ndpack pack`` 17 s -> 12 s, issue 6), but no longer: the two processes
    compile many of the same functions, and the demo's first ``ndpack pack`` took 22.5 s and
    23.3 s with the helper against 20.7 s and 20.7 s without, the armadillo's first packing 32.5 s
    against 31.3 s (issue 48, twelfth step)."""
    if dim in _asked:
        return
    _asked.add(dim)
    namespace = geometry_kernels(dim, wait=False)
    if not all(ahead.on_disk(namespace[name]) for name in GEOMETRY_ENTRIES):
        ahead.start([(_geometry_job(dim), 1.0, "ndpack.backends.numba_backend:warm_geometry", [int(dim)])], least=2)
