"""The spheres near a box: the sphere index's queries (and the plain one), written once for every compiled backend.

This file is read as text, not imported: :func:`ndpack.kernels.portable.render` prints it for
Numba (the CPU backend and numba-cuda: :mod:`ndpack.backends.numba_common`) and for Warp
(:mod:`ndpack.backends.warp_backend`). The index (see :mod:`ndpack.backends.sphere_index`) is a
hashed grid per octave of radius: level ``l`` has cells of side ``top * 0.5**l`` and holds the
spheres of radius a third to a sixth of that (level 0 also the larger ones), each in the cell of
its centre, in a linked list per hash bucket; ``level_rmax`` is each level's largest radius.

Each backend's own text defines ``INDEX_FACTOR`` (a level's cells are that many times its
largest radius), ``INDEX_SLACK`` (cells a query's window is widened by: 0 in float64; 1 in Warp's
float32, where a window's rounding may miss the cell a sphere was put in, and a bucket's spheres
are then taken without checking their cell: extra spheres in a table are harmless, missing ones
are not) and ``index_bucket(level, cell, mask)``, the hash, whose wrapping integer arithmetic has
no portable form. The argument types are those of :data:`ndpack.kernels.portable.ARGUMENT_TYPES`.
"""

# ruff: noqa: F821  (D, point, INDEX_FACTOR, INDEX_SLACK and index_bucket exist where this text runs)


def point_gap(x: "point", s: "int", centers: "points", radii: "floats"):
    """Gap between sphere ``s`` and the point ``x`` (a box's centre)."""
    length2 = 0.0
    for k in range(D):
        t = x[k] - centers[s, k]
        length2 += t * t
    return math.sqrt(length2) - radii[s]


def box_gap(lo: "point", hi: "point", s: "int", centers: "points", radii: "floats"):
    """Gap between sphere ``s`` and the box ``lo``-``hi`` (negative when they overlap)."""
    outside2 = 0.0
    for k in range(D):
        t = max(lo[k] - centers[s, k], centers[s, k] - hi[k], 0.0)
        outside2 += t * t
    return math.sqrt(outside2) - radii[s]


def box_of(b: "int", lower: "points", upper: "points", lo: "point", hi: "point", middle: "point"):
    """Box ``b``'s corners and centre into ``lo``, ``hi`` and ``middle``, and half its diagonal: a
    query reads them once (from registers on a GPU), not once per cell or sphere."""
    half2 = 0.0
    for k in range(D):
        lo[k] = lower[b, k]
        hi[k] = upper[b, k]
        middle[k] = 0.5 * (lo[k] + hi[k])
        half2 += 0.25 * ((hi[k] - lo[k]) * (hi[k] - lo[k]))
    return math.sqrt(half2)


def near_one(b: "int", lower: "points", upper: "points", reach: "floats", centers: "points", radii: "floats",
             out: "int_table", width: "int"):
    """Spheres whose surface comes within the reach of box ``b``, without the index (every sphere
    looked at): how many, the first ``width`` in ``out``."""
    lo = point()
    hi = point()
    middle = point()
    half = box_of(b, lower, upper, lo, hi, middle)
    bound = reach[b]
    for s in range(radii.shape[0]):  # a tighter reach from the box centre's clearance
        bound = min(bound, point_gap(middle, s, centers, radii) + half)
    found = 0
    for s in range(radii.shape[0]):
        if box_gap(lo, hi, s, centers, radii) <= bound:
            if found < width:
                out[b, found] = s
            found += 1
    return found


def index_level(r: "float", top: "float", levels: "int"):
    """The finest level whose cells are at least ``INDEX_FACTOR`` times ``r``."""
    level = 0
    side = top
    while level < levels - 1 and 0.5 * side >= float(INDEX_FACTOR) * r:
        side = 0.5 * side
        level += 1
    return level


def index_cell_far(lo: "point", hi: "point", middle: "point", cell: "point", origin: "floats", side: "float",
                   bound: "float", half: "float", counting: "int", rmax: "float", margin: "float"):
    """Whether no sphere of radius up to ``rmax`` centred in ``cell`` can answer the query of the box
    ``lo``-``hi`` (centre ``middle``): the cell lies farther than ``bound + rmax`` from the box
    (``counting`` 1, the box's gap), or than ``bound - half + rmax`` from its centre (0, the centre's
    gap), with ``margin`` more for the rounding that put a centre near a face in this cell. The
    window's corners are most of its cells from 4-D up (a ball fills 16% of its cube in 5-D), so
    skipping them before the hash spares most of a query there."""
    reach = (bound + rmax if counting == 1 else bound - half + rmax) + margin
    if reach < 0.0:
        return True
    length2 = 0.0
    for k in range(D):
        start = origin[k] + cell[k] * side
        t = 0.0
        if counting == 1:
            t = max(start - hi[k], lo[k] - (start + side), 0.0)
        else:
            t = max(start - middle[k], middle[k] - (start + side), 0.0)
        length2 += t * t
    return length2 > reach * reach


def index_near(b: "int", lower: "points", upper: "points", bound: "float", counting: "int", centers: "points",
               radii: "floats", origin: "floats", top: "float", heads: "ints", nxt: "ints", level_of: "ints",
               level_head: "ints", level_next: "ints", level_count: "ints", level_rmax: "floats", out: "int_table",
               row: "int", width: "int"):
    """The spheres near box ``b`` (``lower[b]``, ``upper[b]``), found through the index.

    ``counting`` 0: returns ``bound`` tightened by every sphere within it of the box (the upper
    bound of the clearance in the box: a sphere's gap from the box centre plus half a diagonal);
    with ``width`` > 0, ``out[row, 0]`` is the sphere that tightened it most (the first of equals),
    -1 if none did.
    ``counting`` 1: counts the spheres that come within ``bound`` of the box, and writes the
    first ``width`` of them into ``out[row]``. Both visit the cells of each level within ``bound``
    (plus the level's largest radius) of the box, or the level's list where that is shorter;
    ``counting`` 0 with the bound as tightened by the coarser levels. Returns ``(bound, count)``.
    """
    lo = point()
    hi = point()
    middle = point()
    half = box_of(b, lower, upper, lo, hi, middle)
    slack = float(INDEX_SLACK)
    reach = bound
    found = 0
    low = point()
    high = point()
    cell = point()
    mask = heads.shape[0] - 1
    nearest = -1
    side = top
    corrupt = 0
    for level in range(level_head.shape[0]):
        if corrupt == 1:
            break
        if level > 0:
            side = side * 0.5  # a power of two: top * 0.5**level exactly
        if level_count[level] == 0:
            continue
        if counting == 0:  # a sphere tightens the bound only within it: look no farther than that
            reach = bound
        cells = 1.0
        empty = 0
        for k in range(D):
            low[k] = math.floor((lo[k] - reach - level_rmax[level] - origin[k]) / side) - slack
            high[k] = math.floor((hi[k] + reach + level_rmax[level] - origin[k]) / side) + slack
            cells *= high[k] - low[k] + 1.0
            # A bound below minus the level's largest radius (a cell inside a sphere) turns the
            # window inside out: no sphere of the level is that near. Walked, its cell count,
            # negative, sent the odometer over the other axes' ranges (1e9 cells: a hang).
            if high[k] < low[k]:
                empty = 1
        if empty == 1:
            continue
        listed = cells > float(level_count[level])
        # Rounding may have put a centre a millionth of a cell, or a few units in the last place
        # of its coordinates, across a face: a cell is skipped only beyond that much more (and
        # the slack's cells), on every axis (tiny cells far from the origin included).
        extent = 0.0
        for k in range(D):
            extent = max(extent, abs(origin[k]) + max(abs(low[k]), abs(high[k] + 1.0)) * side)
        margin = math.sqrt(float(D)) * ((1e-6 + slack) * side + 1e-15 * extent)
        s = -1
        if listed:
            s = level_head[level]
        else:
            for k in range(D):
                cell[k] = low[k]
            cell[0] = cell[0] - 1.0  # the odometer's first turn lands on the window's first cell
        while True:
            if s < 0:
                if listed:
                    break
                k = 0  # the next cell, like an odometer
                while k < D:
                    cell[k] = cell[k] + 1.0
                    if cell[k] <= high[k]:
                        break
                    cell[k] = low[k]
                    k += 1
                if k == D:
                    break
                if index_cell_far(lo, hi, middle, cell, origin, side, bound, half, counting, level_rmax[level],
                                  margin):
                    continue
                s = heads[index_bucket(level, cell, mask)]
                continue
            if s >= radii.shape[0] or s >= nxt.shape[0] or s >= level_next.shape[0]:
                # Never on a sound index. Guarding the walk also keeps numba-cuda from an illegal
                # address it met without it (docs/benchmarks.md, issue 5's third measurement);
                # NaN tells the host. Not a return here: one inside the loops made Warp's index
                # kernels 3x slower on an H100 (bench/gpu_issue48_step10.sh guard).
                corrupt = 1
                break
            mine = listed
            if not listed and level_of[s] == level:  # skip other cells' spheres in this bucket
                mine = True
                if slack == 0.0:
                    for k in range(D):  # no break: Warp unrolls the loop, and may not assign mine in one it keeps
                        if math.floor((centers[s, k] - origin[k]) / side) != cell[k]:
                            mine = False
            if mine:
                if counting == 0:
                    gap = point_gap(middle, s, centers, radii) + half
                    if gap < bound or (gap == bound and s < nearest):
                        bound = gap
                        nearest = s
                elif box_gap(lo, hi, s, centers, radii) <= bound:
                    if found < width:
                        out[row, found] = s
                    found += 1
            if listed:
                s = level_next[s]
            else:
                s = nxt[s]
    if corrupt == 1:
        return math.nan, found
    if counting == 0 and width > 0:
        out[row, 0] = nearest
    return bound, found
