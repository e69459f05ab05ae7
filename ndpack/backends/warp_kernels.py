"""Warp's own kernels: what the kernels written once for every compiled backend need of Warp.

This file is read as text, not imported: :func:`ndpack.kernels.compile.warp_module` appends it
to a shape's generated module, which defines ``F`` (the float type), ``D``, ``VecD`` (a point)
and ``sd(p, prm)``, and the printed kernels follow it: the move
(:mod:`ndpack.backends.move_kernels`), the sphere index's queries
(:mod:`ndpack.backends.index_kernels`) and the prototype store's kernels
(:mod:`ndpack.backends.store_kernels`). What is here is Warp's launch shapes and hash.
"""

# ruff: noqa: F821  (F, D, VecD, sd, move_one and wp exist where this text runs)


@wp.kernel
def distance_all(points: wp.array(dtype=VecD), prm: wp.array(dtype=F), out: wp.array(dtype=F)):
    i = wp.tid()
    out[i] = sd(points[i], prm)


#: In float32 a query's cell ranges may round to a neighbouring cell of the one a sphere was put
#: in, so they are widened by this many cells (see ndpack.backends.index_kernels).
INDEX_SLACK = wp.constant(0.0 if F is wp.float64 else 1.0)
#: The Numba kernels' INDEX_FACTOR: a level holds spheres of a third to a sixth of its cells' side.
INDEX_FACTOR = wp.constant(3.0)


@wp.func
def index_bucket(level: int, cell: VecD, mask: int):
    """Hash bucket of grid ``cell`` of ``level``: the Numba kernels' hash, in unsigned arithmetic
    (the same bits as their wrapping int64 one wherever the mask reaches)."""
    key = wp.uint64(level + 1)
    for k in range(D):
        key = key * wp.uint64(1000003) + wp.uint64(wp.int64(cell[k]))
    key = key ^ (key >> wp.uint64(29))
    return int(key & wp.uint64(mask))


@wp.kernel
def move_ids(ids: wp.array(dtype=wp.int32), first: wp.array(dtype=VecD), first_rows: int, tries: int,
             stream: wp.uint64, points: wp.array(dtype=VecD), clearance: wp.array(dtype=F),
             polished: wp.array(dtype=wp.int32), lower: wp.array(dtype=VecD), upper: wp.array(dtype=VecD),
             wall: wp.array(dtype=F), prm: wp.array(dtype=F), centers: wp.array(dtype=VecD),
             radii: wp.array(dtype=F), nbr: wp.array2d(dtype=wp.int32), steps: wp.array(dtype=F), h: F, polish: int,
             spread: int, polish_steps: wp.array(dtype=F), polish_low: F, polish_from: int):
    """``move_one`` of prototype ``ids[b]`` by thread ``b * spread``; the ``spread - 1`` threads after it
    idle (see :func:`ndpack.backends.prototypes.lane_spread`). It also runs the backend's converge (no
    restarts, no polish). The cooperative launch is another module's (ndpack.backends.warp_lanes)."""
    t = wp.tid()
    if t % spread != 0:
        return
    move_one(t // spread, 0, ids, first, first_rows, tries, stream, points, clearance, polished, lower, upper, wall,
             prm, centers, radii, nbr, steps, h, polish, polish_steps, polish_low, polish_from)
