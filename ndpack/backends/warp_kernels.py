"""Warp kernels of the Warp backend, written in Warp's Python dialect.

This file is read as text, not imported: :func:`ndpack.kernels.compile.warp_module` appends it
to a shape's generated module, which defines ``F`` (the float type), ``D``, ``VecD`` (a point)
and ``sd(p, prm)``. Every kernel mirrors a step of the NumPy reference
(:class:`ndpack.backends.numpy_backend.NumpyBackend`) and of the Numba per-point functions.
"""

# ruff: noqa: F821  (F, D, VecD, sd, sd_feature, sd_at, sd_slope and wp exist where this text runs)

# The kernels over every prototype take the store's ``count`` first: its arrays may hold more rows
# (room to grow), and a launch of ``count`` threads reads only the first ``count``.


@wp.func
def nearest_obstacle(x: VecD, prm: wp.array(dtype=F), centers: wp.array(dtype=VecD), radii: wp.array(dtype=F),
                     nbr: wp.array2d(dtype=wp.int32), row: int, floor: F, hint: F):
    """Clearance of ``x``, its nearest sphere (-1 when the shape's boundary is nearest), a lower
    bound of the boundary's distance (exact where evaluated, -1e30 where nothing is known), and
    the boundary's nearest feature (-1 where not evaluated or where the shape has none, -2 where
    only known farther than the nearest sphere).

    A sphere nearer than ``floor``, a lower bound of the boundary's distance, is nearest without
    evaluating the shape; the search for the nearest feature starts from ``hint`` and looks no
    farther than the nearest sphere (see the Numba kernels). Ties resolve by sphere id, whatever
    the row's order.
    """
    gap_min = F(1.0e30)
    nearest = int(-1)
    count = radii.shape[0]
    for j in range(nbr.shape[1]):
        s = nbr[row, j]
        if s >= count:  # the padding, which always follows a row's spheres
            break
        gap = wp.length(x - centers[s]) - radii[s]
        if gap < gap_min or (gap == gap_min and nearest > s):
            gap_min = gap
            nearest = s
    if nearest >= 0 and gap_min < floor:
        return gap_min, nearest, F(-1.0e30), F(-1.0)
    feature = sd_feature(x, prm, hint, gap_min)
    if feature == F(-2.0):  # no boundary as near as the sphere: the sphere wins
        return gap_min, nearest, gap_min, feature
    boundary = -sd_at(x, prm, feature)
    if gap_min < boundary:  # the boundary wins over an equal sphere
        return gap_min, nearest, boundary, feature
    return boundary, int(-1), boundary, feature


@wp.func
def wall_floor(x: VecD, lower: VecD, upper: VecD, wall: F):
    """Lower bound of the boundary's distance at ``x``: the cell centre's, less the way from it."""
    return wall - wp.length(x - F(0.5) * (lower + upper))


@wp.func
def free_space(x: VecD, prm: wp.array(dtype=F), centers: wp.array(dtype=VecD), radii: wp.array(dtype=F),
               nbr: wp.array2d(dtype=wp.int32), row: int, h: F, floor: F, hint: F):
    """Clearance of ``x``, the direction away from its nearest obstacle (``-grad sd``,
    closed-form from the nearest feature where the shape has one, else by central differences of
    step ``h``; or away from the nearest sphere's centre), and ``nearest_obstacle``'s bound of
    the boundary's distance and feature."""
    clearance, nearest, bound, feature = nearest_obstacle(x, prm, centers, radii, nbr, row, floor, hint)
    g = VecD()
    if nearest < 0 and feature >= F(0.0):
        for k in range(D):
            g[k] = -sd_slope(x, prm, feature, -clearance, k)
    elif nearest < 0:
        # (down - up) / 2h per axis, with one call of sd in the loop: the compiler inlines the
        # shape's whole interpreter once, not twice.
        for m in range(2 * D):
            k = m // 2
            q = x
            if m % 2 == 0:
                q[k] = x[k] + h
            else:
                q[k] = x[k] - h
            value = sd(q, prm)
            if m % 2 == 0:
                g[k] = -value
            else:
                g[k] = (g[k] + value) / (F(2.0) * h)
    else:
        away = x - centers[nearest]
        length = wp.length(away)
        if length > F(0.0):
            g = away / length
        else:
            g[0] = F(1.0)
    return clearance, g, bound, feature


@wp.kernel
def distance_all(points: wp.array(dtype=VecD), prm: wp.array(dtype=F), out: wp.array(dtype=F)):
    i = wp.tid()
    out[i] = sd(points[i], prm)


@wp.kernel
def clearance_all(points: wp.array(dtype=VecD), prm: wp.array(dtype=F), centers: wp.array(dtype=VecD),
                  radii: wp.array(dtype=F), nbr: wp.array2d(dtype=wp.int32), h: F, out: wp.array(dtype=F),
                  out_direction: wp.array(dtype=VecD)):
    i = wp.tid()
    c, g, bound, feature = free_space(points[i], prm, centers, radii, nbr, i, h, F(-1.0e30), F(-1.0))
    out[i] = c
    if out_direction.shape[0] > i:
        out_direction[i] = g


@wp.func
def converge_from(x: VecD, lower: VecD, upper: VecD, wall: F, prm: wp.array(dtype=F), centers: wp.array(dtype=VecD),
                  radii: wp.array(dtype=F), nbr: wp.array2d(dtype=wp.int32), row: int, steps: wp.array(dtype=F),
                  h: F):
    """``p <- p + eps |c| g`` from ``x``, clipped to the cell; the best point seen and its clearance.
    The last lower bound of the boundary's distance, at ``anchor``, spares evaluations nearby,
    and the last nearest feature is the next search's hint (see the Numba kernels)."""
    best = x
    best_clearance = F(-1.0e30)
    anchor = x
    anchored = F(-1.0e30)
    hint = F(-1.0)
    count = steps.shape[0]
    for t in range(count + 1):
        floor = wp.max(wall_floor(x, lower, upper, wall), anchored - wp.length(x - anchor) - F(1.0e-3) * h)
        c, g, bound, feature = free_space(x, prm, centers, radii, nbr, row, h, floor, hint)
        if feature >= F(0.0):
            hint = feature
        if bound > F(-1.0e30):
            anchored = bound
            anchor = x
        if c > best_clearance:
            best_clearance = c
            best = x
        if t < count:
            x = x + (steps[t] * wp.abs(c)) * g
            for k in range(D):
                x[k] = wp.min(wp.max(x[k], lower[k]), upper[k])
    return best, best_clearance


@wp.kernel
def converge_all(points: wp.array(dtype=VecD), lower: wp.array(dtype=VecD), upper: wp.array(dtype=VecD),
                 wall: wp.array(dtype=F), prm: wp.array(dtype=F), centers: wp.array(dtype=VecD),
                 radii: wp.array(dtype=F),
                 nbr: wp.array2d(dtype=wp.int32), steps: wp.array(dtype=F), h: F,
                 out_points: wp.array(dtype=VecD), out_clearance: wp.array(dtype=F)):
    i = wp.tid()
    best, best_clearance = converge_from(points[i], lower[i], upper[i], wall[i], prm, centers, radii, nbr, i, steps, h)
    out_points[i] = best
    out_clearance[i] = best_clearance


@wp.func
def near_bound(b: int, lower: wp.array(dtype=VecD), upper: wp.array(dtype=VecD), reach: wp.array(dtype=F),
               centers: wp.array(dtype=VecD), radii: wp.array(dtype=F)):
    """Upper bound of the clearance of any point of box ``b`` (the reference's tighter reach)."""
    middle = F(0.5) * (lower[b] + upper[b])
    half = F(0.5) * wp.length(upper[b] - lower[b])
    bound = reach[b]
    for s in range(radii.shape[0]):
        bound = wp.min(bound, wp.length(middle - centers[s]) - radii[s] + half)
    return bound


@wp.func
def box_gap(b: int, s: int, lower: wp.array(dtype=VecD), upper: wp.array(dtype=VecD),
            centers: wp.array(dtype=VecD), radii: wp.array(dtype=F)):
    outside = VecD()
    for k in range(D):
        outside[k] = wp.max(wp.max(lower[b][k] - centers[s][k], centers[s][k] - upper[b][k]), F(0.0))
    return wp.length(outside) - radii[s]


@wp.kernel
def near_all(lower: wp.array(dtype=VecD), upper: wp.array(dtype=VecD), reach: wp.array(dtype=F),
             centers: wp.array(dtype=VecD), radii: wp.array(dtype=F), counts: wp.array(dtype=wp.int32),
             out: wp.array2d(dtype=wp.int32)):
    """How many spheres come within reach of box ``b``; the first ``out.shape[1]`` of them in ``out``."""
    b = wp.tid()
    bound = near_bound(b, lower, upper, reach, centers, radii)
    found = int(0)
    for s in range(radii.shape[0]):
        if box_gap(b, s, lower, upper, centers, radii) <= bound:
            if found < out.shape[1]:
                out[b, found] = s
            found += 1
    counts[b] = found


@wp.func
def touches(i: int, points: wp.array(dtype=VecD), clearance: wp.array(dtype=F), centers: wp.array(dtype=VecD),
            radii: wp.array(dtype=F)):
    """The sphere nearest to prototype ``i`` (smallest gap, the first of equals) if its clearance
    ball meets it, else -1."""
    nearest = int(-1)
    gap_min = clearance[i]
    for s in range(radii.shape[0]):
        gap = wp.length(points[i] - centers[s]) - radii[s]
        if gap < gap_min:
            gap_min = gap
            nearest = s
    return nearest


@wp.kernel
def touched_all(points: wp.array(dtype=VecD), clearance: wp.array(dtype=F), centers: wp.array(dtype=VecD),
                radii: wp.array(dtype=F), out: wp.array(dtype=wp.int32)):
    i = wp.tid()
    out[i] = touches(i, points, clearance, centers, radii)


# The prototype store's kernels (see ndpack.backends.prototypes.DevicePrototypes): they work on
# the device-resident prototypes by id, and compact their answers with an atomic counter.


@wp.func
def append(i: int, points: wp.array(dtype=VecD), clearance: wp.array(dtype=F), polished: wp.array(dtype=wp.int32),
           counter: wp.array(dtype=wp.int32), out_ids: wp.array(dtype=wp.int32), out_values: wp.array(dtype=F),
           out_points: wp.array(dtype=VecD), out_flags: wp.array(dtype=wp.int32)):
    """Append prototype ``i`` to the answer buffers."""
    slot = wp.atomic_add(counter, 0, 1)
    out_ids[slot] = i
    out_values[slot] = clearance[i]
    out_points[slot] = points[i]
    out_flags[slot] = polished[i]
    return slot


@wp.kernel
def max_all(count: int, clearance: wp.array(dtype=F), below: F, out: wp.array(dtype=F)):
    c = clearance[wp.tid()]
    if c < below and c > out[0]:  # the read spares most atomics on one address
        wp.atomic_max(out, 0, c)


# A fast round's window with its late finds (DevicePrototypes.window with ``late``), in one query:
# max_all gives the largest clearance (``window[0]``), window_count how many lie within the window
# below it, window_below the largest clearance below that window (``window[1]``) where the late
# finds' rule may take it, and select_window the window below the frontier that the rule gives.
@wp.func
def window_edge(top: F, relative: F):
    return top * (F(1.0) - relative)


@wp.func
def late_taken(window: wp.array(dtype=F), late: wp.array(dtype=wp.int32), floor: F, few: int):
    """Whether the late finds' rule takes the frontier below the largest clearance's window."""
    return window[0] > F(0.0) and window[0] >= floor and late[0] < few


@wp.kernel
def window_count(count: int, clearance: wp.array(dtype=F), window: wp.array(dtype=F), relative: F, low: F, few: int,
                 late: wp.array(dtype=wp.int32)):
    """``late[0]``: how many clearances lie within ``relative`` below ``window[0]`` (and at least
    ``low``), counted up to ``few`` at least (past it the count only has to stay there)."""
    c = clearance[wp.tid()]
    top = window[0]
    if top > F(0.0) and c >= wp.max(low, window_edge(top, relative)) and late[0] < few:
        wp.atomic_add(late, 0, 1)


@wp.kernel
def window_below(count: int, clearance: wp.array(dtype=F), window: wp.array(dtype=F), relative: F,
                 late: wp.array(dtype=wp.int32), floor: F, few: int):
    """``window[1]``: the largest clearance below the window of ``window[0]``, where the late finds'
    rule applies (else it stays as filled)."""
    if late_taken(window, late, floor, few):
        c = clearance[wp.tid()]
        if c < window_edge(window[0], relative) and c > window[1]:  # the read spares most atomics
            wp.atomic_max(window, 1, c)


@wp.kernel
def select_window(count: int, clearance: wp.array(dtype=F), polished: wp.array(dtype=wp.int32),
                  points: wp.array(dtype=VecD), low: F, window: wp.array(dtype=F), relative: F,
                  late: wp.array(dtype=wp.int32), floor: F, few: int,
                  counter: wp.array(dtype=wp.int32), out_ids: wp.array(dtype=wp.int32),
                  out_values: wp.array(dtype=F), out_points: wp.array(dtype=VecD),
                  out_flags: wp.array(dtype=wp.int32)):
    """Append the prototypes within ``relative`` below the frontier (and at least ``low``): the
    largest clearance ``window[0]``, or ``window[1]`` where the late finds' rule takes it and it
    is positive; none where the largest is not positive."""
    frontier = window[0]
    if late_taken(window, late, floor, few) and window[1] > F(0.0):
        frontier = window[1]
    if frontier > F(0.0):
        i = wp.tid()
        c = clearance[i]
        if c >= wp.max(low, window_edge(frontier, relative)):
            append(i, points, clearance, polished, counter, out_ids, out_values, out_points, out_flags)


@wp.kernel
def select_all(count: int, clearance: wp.array(dtype=F), polished: wp.array(dtype=wp.int32),
               points: wp.array(dtype=VecD),
               low: F, high: F, unpolished: int, top: wp.array(dtype=F), relative: F,
               counter: wp.array(dtype=wp.int32), out_ids: wp.array(dtype=wp.int32), out_values: wp.array(dtype=F),
               out_points: wp.array(dtype=VecD), out_flags: wp.array(dtype=wp.int32)):
    """Append the prototypes with ``low <= clearance <= high`` (unpolished ones only, if asked);
    with ``relative >= 0``, ``low`` rises to ``(1 - relative) * top[0]`` where that is positive."""
    i = wp.tid()
    c = clearance[i]
    lo = low
    if relative >= F(0.0) and top[0] > F(0.0):
        lo = wp.max(lo, top[0] * (F(1.0) - relative))
    if c >= lo and c <= high:
        if unpolished == 0 or polished[i] == 0:
            append(i, points, clearance, polished, counter, out_ids, out_values, out_points, out_flags)


@wp.kernel
def gather_ids(ids: wp.array(dtype=wp.int32), points: wp.array(dtype=VecD), clearance: wp.array(dtype=F),
               polished: wp.array(dtype=wp.int32), out_points: wp.array(dtype=VecD), out_clearance: wp.array(dtype=F),
               out_flags: wp.array(dtype=wp.int32)):
    """The points, clearances and polish flags of prototypes ``ids``, as a selection appends them."""
    b = wp.tid()
    out_points[b] = points[ids[b]]
    out_clearance[b] = clearance[ids[b]]
    out_flags[b] = polished[ids[b]]


# ---------------------------------------------------------------------------- the sphere index
# The index of ndpack.backends.sphere_index (a hashed grid per octave of radius, each bucket a
# linked list), built on the device (index_clear, index_insert_range) and queried there
# (index_near); both follow the Numba kernels of the same names.

#: In float32 a query's cell ranges may round to a neighbouring cell of the one a sphere was put
#: in, so they are widened by this many cells and a bucket's spheres are taken without checking
#: their cell (extra spheres in a table are harmless, missing ones are not).
INDEX_SLACK = wp.constant(0.0 if F is wp.float64 else 1.0)
INDEX_ROOT_D = wp.constant(float(D) ** 0.5)  # a margin on every axis, as one distance
#: The Numba kernels' INDEX_FACTOR: a level holds spheres of a third to a sixth of its cells' side.
INDEX_FACTOR = wp.constant(3.0)


@wp.func
def index_level(r: F, top: F, levels: int):
    """The finest level whose cells are at least ``INDEX_FACTOR`` times ``r``."""
    level = int(0)
    side = top
    while level < levels - 1 and F(0.5) * side >= F(INDEX_FACTOR) * r:
        side = F(0.5) * side
        level += 1
    return level


@wp.func
def index_bucket(level: int, cell: VecD, mask: int):
    """Hash bucket of grid ``cell`` of ``level``: the Numba kernels' hash, in unsigned arithmetic
    (the same bits as their wrapping int64 one wherever the mask reaches)."""
    key = wp.uint64(level + 1)
    for k in range(D):
        key = key * wp.uint64(1000003) + wp.uint64(wp.int64(cell[k]))
    key = key ^ (key >> wp.uint64(29))
    return int(key & wp.uint64(mask))


@wp.func
def index_cell_far(lo: VecD, hi: VecD, middle: VecD, cell: VecD, origin: wp.array(dtype=F), side: F, bound: F,
                   half: F, counting: int, rmax: F, margin: F):
    """Whether no sphere of radius up to ``rmax`` centred in ``cell`` can answer the query of the
    box ``lo``-``hi``: the Numba kernels' test."""
    reach = bound + rmax + margin
    if counting == 0:
        reach = bound - half + rmax + margin
    if reach < F(0.0):
        return True
    length2 = F(0.0)
    for k in range(D):
        start = origin[k] + cell[k] * side
        t = F(0.0)
        if counting == 1:
            t = wp.max(wp.max(start - hi[k], lo[k] - (start + side)), F(0.0))
        else:
            t = wp.max(wp.max(start - middle[k], middle[k] - (start + side)), F(0.0))
        length2 = length2 + t * t
    return length2 > reach * reach


@wp.func
def index_near(lo: VecD, hi: VecD, bound: F, counting: int, centers: wp.array(dtype=VecD),
               radii: wp.array(dtype=F), origin: wp.array(dtype=F), top: F, heads: wp.array(dtype=wp.int32),
               nxt: wp.array(dtype=wp.int32), level_of: wp.array(dtype=wp.int32),
               level_head: wp.array(dtype=wp.int32), level_next: wp.array(dtype=wp.int32),
               level_count: wp.array(dtype=wp.int32), level_rmax: wp.array(dtype=F),
               out: wp.array2d(dtype=wp.int32), row: int):
    """The spheres near the box ``lo``-``hi``: ``counting`` 0 tightens ``bound`` (a sphere's gap
    from the box centre plus half a diagonal) and, where ``row >= 0``, puts the sphere that
    tightened it most (the first of equals; -1 if none) in ``out[row, 0]``; 1 counts those
    within ``bound`` of the box and writes the first ones into ``out[row]``. Returns ``(bound,
    count)``."""
    middle = F(0.5) * (lo + hi)
    half = F(0.5) * wp.length(hi - lo)
    slack = F(INDEX_SLACK)
    reach = bound
    found = int(0)
    low = VecD()
    high = VecD()
    cell = VecD()
    mask = heads.shape[0] - 1
    nearest = int(-1)
    side = top
    for level in range(level_head.shape[0]):
        if level > 0:
            side = side * F(0.5)
        if level_count[level] == 0:
            continue
        if counting == 0:  # a sphere tightens the bound only within it: look no farther than that
            reach = bound
        cells = F(1.0)
        empty = int(0)
        for k in range(D):
            low[k] = wp.floor((lo[k] - reach - level_rmax[level] - origin[k]) / side) - slack
            high[k] = wp.floor((hi[k] + reach + level_rmax[level] - origin[k]) / side) + slack
            cells = cells * (high[k] - low[k] + F(1.0))
            if high[k] < low[k]:  # a window inside out (a cell inside a sphere): see numba_kernels
                empty = 1
        if empty == 1:
            continue
        listed = cells > F(level_count[level])
        # The Numba kernels' margin for rounding across a face, with INDEX_SLACK cells more.
        extent = F(0.0)
        for k in range(D):
            extent = wp.max(extent, wp.abs(origin[k]) + wp.max(wp.abs(low[k]), wp.abs(high[k] + F(1.0))) * side)
        margin = F(INDEX_ROOT_D) * ((F(1e-6) + slack) * side + F(1e-15) * extent)
        s = int(-1)
        if listed:
            s = level_head[level]
        else:
            cell = low
            cell[0] = cell[0] - F(1.0)  # the odometer's first turn lands on the window's first cell
        while True:
            if s < 0:
                if listed:
                    break
                k = int(0)  # the next cell, like an odometer
                while k < D:
                    cell[k] = cell[k] + F(1.0)
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
            mine = listed
            if not listed and level_of[s] == level:  # skip other cells' spheres in this bucket
                mine = True
                if slack == F(0.0):
                    for k in range(D):
                        if wp.floor((centers[s][k] - origin[k]) / side) != cell[k]:
                            mine = False
            if mine:
                if counting == 0:
                    gap = wp.length(middle - centers[s]) - radii[s] + half
                    if gap < bound or (gap == bound and s < nearest):
                        bound = gap
                        nearest = s
                else:
                    outside = VecD()
                    for k in range(D):
                        outside[k] = wp.max(wp.max(lo[k] - centers[s][k], centers[s][k] - hi[k]), F(0.0))
                    if wp.length(outside) - radii[s] <= bound:
                        if found < out.shape[1]:
                            out[row, found] = s
                        found += 1
            if listed:
                s = level_next[s]
            else:
                s = nxt[s]
    if counting == 0 and row >= 0:
        out[row, 0] = nearest
    return bound, found


@wp.kernel
def index_clear(heads: wp.array(dtype=wp.int32), level_head: wp.array(dtype=wp.int32),
                level_count: wp.array(dtype=wp.int32), level_rmax: wp.array(dtype=F)):
    """An empty index: every bucket and level list empty (on ``max(buckets, levels)`` threads)."""
    i = wp.tid()
    if i < heads.shape[0]:
        heads[i] = -1
    if i < level_head.shape[0]:
        level_head[i] = -1
        level_count[i] = 0
        level_rmax[i] = F(0.0)


@wp.kernel
def index_insert_range(start: int, centers: wp.array(dtype=VecD), radii: wp.array(dtype=F),
                       origin: wp.array(dtype=F), top: F, heads: wp.array(dtype=wp.int32),
                       nxt: wp.array(dtype=wp.int32), level_of: wp.array(dtype=wp.int32),
                       level_head: wp.array(dtype=wp.int32), level_next: wp.array(dtype=wp.int32),
                       level_count: wp.array(dtype=wp.int32), level_rmax: wp.array(dtype=F)):
    """Put sphere ``start + tid`` in its level's grid and list. The lists' order follows the
    atomics, which no query depends on: a query's answers are sets, and its nearest sphere is
    the lowest id among equals (index_near)."""
    s = start + wp.tid()
    level = index_level(radii[s], top, level_head.shape[0])
    side = top
    for _ in range(level):
        side = side * F(0.5)
    cell = VecD()
    for k in range(D):
        cell[k] = wp.floor((centers[s][k] - origin[k]) / side)
    nxt[s] = wp.atomic_exch(heads, index_bucket(level, cell, heads.shape[0] - 1), s)
    level_of[s] = level
    level_next[s] = wp.atomic_exch(level_head, level, s)
    wp.atomic_add(level_count, level, 1)
    wp.atomic_max(level_rmax, level, radii[s])


@wp.kernel
def index_bound_ids(ids: wp.array(dtype=wp.int32), lower: wp.array(dtype=VecD), upper: wp.array(dtype=VecD),
                    reach: wp.array(dtype=F), centers: wp.array(dtype=VecD), radii: wp.array(dtype=F),
                    origin: wp.array(dtype=F), top: F, heads: wp.array(dtype=wp.int32), nxt: wp.array(dtype=wp.int32),
                    level_of: wp.array(dtype=wp.int32), level_head: wp.array(dtype=wp.int32),
                    level_next: wp.array(dtype=wp.int32), level_count: wp.array(dtype=wp.int32),
                    level_rmax: wp.array(dtype=F), scratch: wp.array2d(dtype=wp.int32), bound: wp.array(dtype=F),
                    spread: int):
    """``bound[b]``: the reference's upper bound of the clearance in the cell of ``ids[b]``, on
    thread ``b * spread`` (as ``move_ids``)."""
    t = wp.tid()
    if t % spread != 0:
        return
    b = t // spread
    i = ids[b]
    c, n = index_near(lower[i], upper[i], reach[i], 0, centers, radii, origin, top, heads, nxt, level_of, level_head,
                      level_next, level_count, level_rmax, scratch, -1)
    bound[b] = c


@wp.kernel
def index_fill_ids(ids: wp.array(dtype=wp.int32), lower: wp.array(dtype=VecD), upper: wp.array(dtype=VecD),
                   bound: wp.array(dtype=F), centers: wp.array(dtype=VecD), radii: wp.array(dtype=F),
                   origin: wp.array(dtype=F), top: F, heads: wp.array(dtype=wp.int32), nxt: wp.array(dtype=wp.int32),
                   level_of: wp.array(dtype=wp.int32), level_head: wp.array(dtype=wp.int32),
                   level_next: wp.array(dtype=wp.int32), level_count: wp.array(dtype=wp.int32),
                   level_rmax: wp.array(dtype=F), found: wp.array(dtype=wp.int32), out: wp.array2d(dtype=wp.int32),
                   spread: int):
    """Row ``b``: the spheres that come within ``bound[b]`` of the cell of ``ids[b]``; ``found[b]`` their
    count; on thread ``b * spread`` (as ``move_ids``)."""
    t = wp.tid()
    if t % spread != 0:
        return
    b = t // spread
    i = ids[b]
    c, n = index_near(lower[i], upper[i], bound[b], 1, centers, radii, origin, top, heads, nxt, level_of, level_head,
                      level_next, level_count, level_rmax, out, b)
    found[b] = n


@wp.kernel
def touched_index_select(count: int, points: wp.array(dtype=VecD), clearance: wp.array(dtype=F),
                         polished: wp.array(dtype=wp.int32), centers: wp.array(dtype=VecD), radii: wp.array(dtype=F),
                         origin: wp.array(dtype=F), top: F, heads: wp.array(dtype=wp.int32),
                         nxt: wp.array(dtype=wp.int32), level_of: wp.array(dtype=wp.int32),
                         level_head: wp.array(dtype=wp.int32), level_next: wp.array(dtype=wp.int32),
                         level_count: wp.array(dtype=wp.int32), level_rmax: wp.array(dtype=F),
                         nearest: wp.array2d(dtype=wp.int32), counter: wp.array(dtype=wp.int32),
                         out_ids: wp.array(dtype=wp.int32), out_values: wp.array(dtype=F),
                         out_points: wp.array(dtype=VecD), out_flags: wp.array(dtype=wp.int32)):
    """Append the prototypes whose clearance ball meets a new sphere (indexed in the arguments),
    with the nearest new sphere in the flags' place (``nearest`` (n, 1) is its scratch)."""
    i = wp.tid()
    c = clearance[i]
    if c > F(-1.0e30):
        tight, n = index_near(points[i], points[i], c, 0, centers, radii, origin, top, heads, nxt, level_of,
                              level_head, level_next, level_count, level_rmax, nearest, i)
        if tight < c:
            slot = append(i, points, clearance, polished, counter, out_ids, out_values, out_points, out_flags)
            out_flags[slot] = nearest[i, 0]


@wp.kernel
def near_finish(found: wp.array(dtype=wp.int32), sphere_count: int, width: wp.array(dtype=wp.int32),
                out: wp.array2d(dtype=wp.int32)):
    """Pad row ``b`` and widen ``width``. Rows stay in the order the atomics gave: the nearest
    sphere is found alike in any order (see nearest_obstacle)."""
    b = wp.tid()
    for j in range(wp.min(found[b], out.shape[1]), out.shape[1]):
        out[b, j] = sphere_count
    wp.atomic_max(width, 0, found[b])


@wp.kernel
def set_floats(ids: wp.array(dtype=wp.int32), values: wp.array(dtype=F), out: wp.array(dtype=F)):
    b = wp.tid()
    out[ids[b]] = values[b]


@wp.kernel
def lower_floats(ids: wp.array(dtype=wp.int32), values: wp.array(dtype=F), out: wp.array(dtype=F)):
    b = wp.tid()
    out[ids[b]] = wp.min(out[ids[b]], values[b])


@wp.kernel
def split_mark(count: int, lower: wp.array(dtype=VecD), upper: wp.array(dtype=VecD), reach: wp.array(dtype=F),
               points: wp.array(dtype=VecD), clearance: wp.array(dtype=F), bound: wp.array(dtype=F), low: F,
               longest: F, counter: wp.array(dtype=wp.int32), out_ids: wp.array(dtype=wp.int32),
               out_values: wp.array(dtype=F),
               out_points: wp.array(dtype=VecD), out_flags: wp.array(dtype=wp.int32)):
    """Append the cells that may split, with their tightened bounds (the host store's
    ``split_candidates``); every cell looked at keeps its tighter bound."""
    i = wp.tid()
    lo = lower[i]
    hi = upper[i]
    side = hi[0] - lo[0]
    for k in range(1, D):
        side = wp.max(side, hi[k] - lo[k])
    if side > longest and bound[i] >= low:
        c = clearance[i]
        p = points[i]
        farthest = VecD()
        for k in range(D):
            farthest[k] = wp.max(p[k] - lo[k], hi[k] - p[k])
        b = reach[i]
        if c > -F(wp.inf):  # converged: the attained clearance bounds the cell too
            b = wp.min(b, c + wp.length(farthest))
        bound[i] = wp.min(bound[i], b)
        if b >= low:
            slot = wp.atomic_add(counter, 0, 1)
            out_ids[slot] = i
            out_values[slot] = b


@wp.kernel
def split_cut(ids: wp.array(dtype=wp.int32), lower: wp.array(dtype=VecD), upper: wp.array(dtype=VecD),
              reach: wp.array(dtype=F), points: wp.array(dtype=VecD), clearance: wp.array(dtype=F),
              polished: wp.array(dtype=wp.int32), first_new: int):
    """Cut cell ``ids[b]`` in two across its longest side (the first of equals); the half without
    its prototype becomes row ``first_new + b``, with a new prototype at its centre and its
    parent's reach, which :func:`cell_distances` tightens (the host store's ``split_cells``)."""
    b = wp.tid()
    i = ids[b]
    j = first_new + b
    lo = lower[i]
    hi = upper[i]
    axis = int(0)
    side = hi[0] - lo[0]
    for k in range(1, D):
        if hi[k] - lo[k] > side:
            axis = k
            side = hi[k] - lo[k]
    middle = F(0.5) * (lo[axis] + hi[axis])
    kept_lo = lo
    kept_hi = hi
    other_lo = lo
    other_hi = hi
    if points[i][axis] < middle:
        kept_hi[axis] = middle
        other_lo[axis] = middle
    else:
        kept_lo[axis] = middle
        other_hi[axis] = middle
    lower[i] = kept_lo
    upper[i] = kept_hi
    lower[j] = other_lo
    upper[j] = other_hi
    reach[j] = reach[i]
    points[j] = F(0.5) * (other_lo + other_hi)
    clearance[j] = -F(wp.inf)
    polished[j] = 0


@wp.kernel
def cell_distances(ids: wp.array(dtype=wp.int32), count: int, first_new: int, lower: wp.array(dtype=VecD),
                   upper: wp.array(dtype=VecD), reach: wp.array(dtype=F), wall: wp.array(dtype=F),
                   bound: wp.array(dtype=F), prm: wp.array(dtype=F), wall_slack: F):
    """Bound the cells cut by :func:`split_cut` by their centres' signed distances (the host's
    ``cell_bounds``): row ``ids[t]`` for ``t < count``, row ``first_new + t - count`` after; its
    reach (never above what it was), wall and split bound. A thread a half: the two halves'
    distances, each a walk of the mesh's trees, are not one chain."""
    t = wp.tid()
    row = first_new + t - count
    if t < count:
        row = ids[t]
    lo = lower[row]
    hi = upper[row]
    distance = sd(F(0.5) * (lo + hi), prm)
    bounded = wp.min(reach[row], -distance + F(0.5) * wp.length(hi - lo))
    reach[row] = bounded
    wall[row] = -distance - wall_slack
    bound[row] = bounded


@wp.func
def restart_mix(h: wp.uint64):
    """MurmurHash3's finaliser of a 32-bit word held in 64 bits (ndpack.backends.restarts)."""
    h = h ^ (h >> wp.uint64(16))
    h = (h * wp.uint64(0x85EBCA6B)) & wp.uint64(0xFFFFFFFF)
    h = h ^ (h >> wp.uint64(13))
    h = (h * wp.uint64(0xC2B2AE35)) & wp.uint64(0xFFFFFFFF)
    return h ^ (h >> wp.uint64(16))


@wp.func
def restart_key(stream: wp.uint64, i: int):
    """Prototype ``i``'s hash in a restart's ``stream``."""
    word = wp.uint64(i) & wp.uint64(0xFFFFFFFF)
    return restart_mix((stream + word * wp.uint64(0x9E3779B9)) & wp.uint64(0xFFFFFFFF))


@wp.func
def restart_point(key: wp.uint64, t: int, lower: VecD, upper: VecD):
    """Random point ``t`` of a prototype's cell ``lower``-``upper`` from its hash ``key``."""
    y = VecD()
    for k in range(D):
        counter = wp.uint64(t * D + k + 1)
        word = restart_mix((key + counter * wp.uint64(0x9E3779B9)) & wp.uint64(0xFFFFFFFF))
        unit = F(wp.float64(word) * wp.float64(2.3283064365386963e-10))  # 2**-32: exact in float64
        y[k] = lower[k] + (upper[k] - lower[k]) * unit
    return y


@wp.func
def move_one(b: int, lane: int, ids: wp.array(dtype=wp.int32), first: wp.array(dtype=VecD), first_rows: int,
             tries: int, stream: wp.uint64, points: wp.array(dtype=VecD), clearance: wp.array(dtype=F),
             polished: wp.array(dtype=wp.int32), lower: wp.array(dtype=VecD), upper: wp.array(dtype=VecD),
             wall: wp.array(dtype=F), prm: wp.array(dtype=F), centers: wp.array(dtype=VecD),
             radii: wp.array(dtype=F), nbr: wp.array2d(dtype=wp.int32), steps: wp.array(dtype=F), h: F, polish: int,
             polish_steps: wp.array(dtype=F), polish_low: F, polish_from: int):
    """Move prototype ``ids[b]`` in place: from the best of its point, ``first[b]`` (clipped to its
    cell, where ``b < first_rows``) and ``tries`` random points of its cell drawn from ``stream``,
    converge; keep the result (``polish`` 0), or keep it only if better and mark it polished (1).
    Then, where it was not a polish and the clearance reaches ``polish_low``, polish it with
    ``polish_steps``: converge again from the result, keep it only if better, mark it polished;
    rows from ``polish_from`` on are only polished (the host store's
    ``move(..., ahead=PolishAhead(...))``). Lane 0 writes: the lanes of a cooperative launch
    (ndpack.backends.warp_lanes) all compute the same move. The move and the polish are two passes
    of one loop, so that the converge is compiled once (as numba's move_one)."""
    i = ids[b]
    x = points[i]
    moving = b < polish_from
    lead = int(0)
    if b < first_rows:
        lead = 1
    if moving and lead + tries > 0:
        top, nearest, bound, feature = nearest_obstacle(x, prm, centers, radii, nbr, b,
                                                        wall_floor(x, lower[i], upper[i], wall[i]), F(-1.0))
        key = restart_key(stream, i)
        for r in range(lead + tries):
            y = VecD()
            if r < lead:
                y = first[b]
                for k in range(D):
                    y[k] = wp.min(wp.max(y[k], lower[i][k]), upper[i][k])
            else:
                y = restart_point(key, r - lead, lower[i], upper[i])
            # A start whose nearest sphere is nearer than the best so far cannot beat it: the best
            # clearance floors the boundary's bound, so such a start walks no tree (its clearance,
            # then the sphere's gap, above the true one, is only compared with top).
            c, s, bound, f = nearest_obstacle(y, prm, centers, radii, nbr, b,
                                              wp.max(wall_floor(y, lower[i], upper[i], wall[i]), top), F(-1.0))
            if c > top:
                top = c
                x = y
    phase = int(1)  # 0: the move, 1: the polish
    if moving:
        phase = 0
    while phase < 2:
        best, best_clearance = converge_from(x, lower[i], upper[i], wall[i], prm, centers, radii, nbr, b,
                                             wp.where(phase == 0, steps, polish_steps), h)
        if lane == 0:
            if (phase == 0 and polish == 0) or best_clearance > clearance[i]:
                points[i] = best
                clearance[i] = best_clearance
            if phase == 0:
                polished[i] = polish
            else:
                polished[i] = 1
        if phase == 0 and (polish != 0 or best_clearance < polish_low):
            phase = 2
        else:
            phase = phase + 1
        x = best


@wp.kernel
def move_ids(ids: wp.array(dtype=wp.int32), first: wp.array(dtype=VecD), first_rows: int, tries: int,
             stream: wp.uint64, points: wp.array(dtype=VecD), clearance: wp.array(dtype=F),
             polished: wp.array(dtype=wp.int32), lower: wp.array(dtype=VecD), upper: wp.array(dtype=VecD),
             wall: wp.array(dtype=F), prm: wp.array(dtype=F), centers: wp.array(dtype=VecD),
             radii: wp.array(dtype=F), nbr: wp.array2d(dtype=wp.int32), steps: wp.array(dtype=F), h: F, polish: int,
             spread: int, polish_steps: wp.array(dtype=F), polish_low: F, polish_from: int):
    """:func:`move_one` of prototype ``ids[b]`` by thread ``b * spread``; the ``spread - 1`` threads
    after it idle (see :func:`ndpack.backends.prototypes.lane_spread`)."""
    t = wp.tid()
    if t % spread != 0:
        return
    move_one(t // spread, 0, ids, first, first_rows, tries, stream, points, clearance, polished, lower, upper, wall,
             prm, centers, radii, nbr, steps, h, polish, polish_steps, polish_low, polish_from)
