"""The Numba backends' own functions: the CPU's converge and what the printed kernels need of Numba.

This file is read as text, not imported: :func:`ndpack.kernels.compile.numba_namespace` runs it
in the namespace of a compiled program, where ``sd(p, prm)`` is the signed distance of the shape
whose numbers are ``prm``, ``D`` the dimension, and ``point()`` a local array of length ``D``, with
the functions written once for every compiled backend (:mod:`ndpack.backends.move_kernels`,
:mod:`ndpack.backends.index_kernels`), printed in Numba's dialect (:data:`ndpack.backends.numba_common.KERNELS`).
Array arguments as there.
"""

# ruff: noqa: F821  (D, sd, sd_feature, sd_at, sd_slope and point exist where this text runs)


def converge_one(i, lane, points, starts, tries, lower, upper, wall, prm, centers, radii, nbr, steps, h, out_points,
                 out_clearance):
    """Converge point ``i`` in its cell (row ``i`` of every table), from the best of it and
    ``starts[:tries, i]``, into the outputs. Lane 0 writes: the lanes of a cooperative launch
    (ndpack.backends.numba_cuda_lanes) all compute the same point."""
    x = point()
    g = point()
    best = point()
    for k in range(D):
        x[k] = points[i, k]
    best_start(x, g, starts, tries, i, i, lower, upper, wall, prm, centers, radii, nbr)
    c = converge_from(x, g, best, i, i, lower, upper, wall, prm, centers, radii, nbr, steps, h)
    if lane == 0:
        out_clearance[i] = c
        for k in range(D):
            out_points[i, k] = best[k]


def best_start(x, g, starts, tries, cell, row, lower, upper, wall, prm, centers, radii, nbr):
    """Replace ``x`` by the first of ``starts[:tries, row]`` with a larger clearance, if any
    (``g`` is scratch): the reference's best of a prototype's point and its restarts."""
    if tries > 0:
        top = nearest_obstacle(x, prm, centers, radii, nbr, row, wall_floor(x, lower, upper, wall, cell), -1.0)[0]
        for t in range(tries):
            for k in range(D):
                g[k] = starts[t, row, k]
            c = nearest_obstacle(g, prm, centers, radii, nbr, row, max(wall_floor(g, lower, upper, wall, cell), top),
                                 -1.0)[0]  # the best so far floors the bound, as in move_one
            if c > top:
                top = c
                for k in range(D):
                    x[k] = g[k]


def touched_one(i, points, clearance, centers, radii, out):
    out[i] = touches(i, points, clearance, centers, radii)


# ---------------------------------------------------------------------------- the sphere index
# A hashed grid per octave of radius (see ndpack.backends.sphere_index). Level ``l`` has cells of
# side ``top * 0.5**l`` and holds the spheres of radius a third to a sixth of that (level 0 also the
# larger ones), each in the cell of its centre, in a linked list per hash bucket; ``level_rmax``
# is each level's largest radius.

#: A level holds the spheres of radius a third to a sixth of its cells' side. Measured on the
#: queries of 3-D to 5-D packings (60,000-95,000 spheres; bench/index_speed.py --queries, with
#: this edited): 3 was as fast as 4 in 3-D and 1.2-1.9x faster in 4-D and 5-D, where a cell of
#: side 4r has room for about 200 spheres of radius r/2 (its volume over theirs); 2, 2.5, 3.5 and 8
#: were slower.
INDEX_FACTOR = 3.0
#: Cells a query's window is widened by (see ndpack.backends.index_kernels): none in float64.
INDEX_SLACK = 0.0


def index_bucket(level, cell, mask):
    """Hash bucket of grid cell ``cell`` (whole numbers as floats) of ``level``."""
    key = level + 1
    for k in range(D):
        key = key * 1000003 + int(cell[k])  # int64 wraps, which is fine for a hash
    key = key ^ (key >> 29)
    return key & mask


def index_insert(s, centers, radii, origin, top, heads, nxt, level_of, level_head, level_next, level_count,
                 level_rmax):
    """Put sphere ``s`` in its level's grid and in its level's list (serial: not thread-safe)."""
    levels = level_head.shape[0]
    level = index_level(radii[s], top, levels)
    side = top * 0.5 ** level
    cell = point()
    for k in range(D):
        cell[k] = math.floor((centers[s, k] - origin[k]) / side)
    bucket = index_bucket(level, cell, heads.shape[0] - 1)
    nxt[s] = heads[bucket]
    heads[bucket] = s
    level_of[s] = level
    level_next[s] = level_head[level]
    level_head[level] = s
    level_count[level] += 1
    level_rmax[level] = max(level_rmax[level], radii[s])

