"""The GPU backends' kernels, written once for both: the prototype store's, and the array operations'.

This file is read as text, not imported: :func:`ndpack.kernels.portable.render` prints it for
numba-cuda (:mod:`ndpack.backends.numba_cuda_backend`) and for Warp
(:mod:`ndpack.backends.warp_backend`), whose modules define ``D``, ``sd(p, prm)`` and the
kernels' other names. The kernels work on the device-resident prototypes by id
(:class:`ndpack.backends.prototypes.DevicePrototypes` launches them) and compact their answers
with an atomic counter. Those over every prototype take the store's ``count`` first: its arrays
may hold more rows (room to grow), and a launch reads only the first ``count``. Every kernel
mirrors a step of the host store (:class:`ndpack.backends.prototypes.HostPrototypes`).

The argument annotations are the portable types of :data:`ndpack.kernels.portable.ARGUMENT_TYPES`
(``points`` (n, D) floats, ``ints`` 1-D ints, ...); a function that calls ``thread()`` is a
kernel, one thread per item, the others device functions.
"""

# ruff: noqa: F821  (D, sd, point, thread, the atomics and the functions of move_kernels.py and
# index_kernels.py exist where this text runs)


def clearance_all(points: "points", prm: "floats", centers: "points", radii: "floats", nbr: "int_table", h: "float",
                  out: "floats", out_direction: "points"):
    """Clearance of every point into ``out``; its direction into ``out_direction`` if that has rows."""
    i = thread()
    if i < points.shape[0]:
        clearance_one(i, points, prm, centers, radii, nbr, h, out, out_direction)


def touched_all(points: "points", clearance: "floats", centers: "points", radii: "floats", out: "ints"):
    """Per point, the sphere nearest to it if its clearance ball meets it, else -1 (``touches``)."""
    i = thread()
    if i < points.shape[0]:
        out[i] = touches(i, points, clearance, centers, radii)


def near_all(lower: "points", upper: "points", reach: "floats", centers: "points", radii: "floats", counts: "ints",
             out: "int_table"):
    """How many spheres come within reach of box ``b`` (``near_one``, every sphere looked at); the first
    ``out.shape[1]`` of them in ``out``. The host counts with a one-column scratch table, then fills one
    that fits."""
    b = thread()
    if b < lower.shape[0]:
        counts[b] = near_one(b, lower, upper, reach, centers, radii, out, out.shape[1])


def append(i: "int", points: "points", clearance: "floats", polished: "ints", counter: "ints", out_ids: "ints",
           out_values: "floats", out_points: "points", out_flags: "ints"):
    """Append prototype ``i`` to the answer buffers; returns its slot."""
    slot = atomic_add(counter, 0, 1)
    out_ids[slot] = i
    out_values[slot] = clearance[i]
    for k in range(D):
        out_points[slot, k] = points[i, k]
    out_flags[slot] = polished[i]
    return slot


def max_all(count: "int", clearance: "floats", below: "float", out: "floats"):
    """``out[0]``: the largest clearance below ``below`` (at least ``out[0]`` as filled)."""
    i = thread()
    if i < count:
        c = clearance[i]
        if c < below and c > out[0]:  # the read spares most atomics on one address
            atomic_max(out, 0, c)


# A fast round's window with its late finds (DevicePrototypes.window with ``late``), in one query:
# max_all gives the largest clearance (``window[0]``), window_count how many lie within the window
# below it, window_below the largest clearance below that window (``window[1]``) where the late
# finds' rule may take it, and select_window the window below the frontier that the rule gives.
def late_taken(window: "floats", late: "ints", floor: "float", few: "int"):
    """Whether the late finds' rule takes the frontier below the largest clearance's window."""
    return window[0] > 0.0 and window[0] >= floor and late[0] < few


def window_count(count: "int", clearance: "floats", window: "floats", relative: "float", low: "float", few: "int",
                 late: "ints"):
    """``late[0]``: how many clearances lie within ``relative`` below ``window[0]`` (and at least
    ``low``), counted up to ``few`` at least (past it the count only has to stay there)."""
    i = thread()
    if i < count:
        top = window[0]
        if top > 0.0 and clearance[i] >= max(low, top * (1.0 - relative)) and late[0] < few:
            atomic_add(late, 0, 1)


def window_below(count: "int", clearance: "floats", window: "floats", relative: "float", late: "ints",
                 floor: "float", few: "int"):
    """``window[1]``: the largest clearance below the window of ``window[0]``, where the late finds'
    rule applies (else it stays as filled)."""
    i = thread()
    if i < count and late_taken(window, late, floor, few):
        c = clearance[i]
        if c < window[0] * (1.0 - relative) and c > window[1]:  # the read spares most atomics
            atomic_max(window, 1, c)


def select_window(count: "int", clearance: "floats", polished: "ints", points: "points", low: "float",
                  window: "floats", relative: "float", late: "ints", floor: "float", few: "int", counter: "ints",
                  out_ids: "ints", out_values: "floats", out_points: "points", out_flags: "ints"):
    """Append the prototypes within ``relative`` below the frontier (and at least ``low``): the
    largest clearance ``window[0]``, or ``window[1]`` where the late finds' rule takes it and it
    is positive; none where the largest is not positive."""
    i = thread()
    if i < count:
        frontier = window[0]
        if late_taken(window, late, floor, few) and window[1] > 0.0:
            frontier = window[1]
        if frontier > 0.0 and clearance[i] >= max(low, frontier * (1.0 - relative)):
            append(i, points, clearance, polished, counter, out_ids, out_values, out_points, out_flags)


def select_all(count: "int", clearance: "floats", polished: "ints", points: "points", low: "float", high: "float",
               unpolished: "int", top: "floats", relative: "float", counter: "ints", out_ids: "ints",
               out_values: "floats", out_points: "points", out_flags: "ints"):
    """Append the prototypes with ``low <= clearance <= high`` (unpolished ones only, if asked);
    with ``relative >= 0``, ``low`` rises to ``(1 - relative) * top[0]`` where that is positive."""
    i = thread()
    if i < count:
        c = clearance[i]
        lo = low
        if relative >= 0.0 and top[0] > 0.0:
            lo = max(lo, top[0] * (1.0 - relative))
        if c >= lo and c <= high and (unpolished == 0 or polished[i] == 0):
            append(i, points, clearance, polished, counter, out_ids, out_values, out_points, out_flags)


def gather_ids(ids: "ints", points: "points", clearance: "floats", polished: "ints", out_points: "points",
               out_clearance: "floats", out_flags: "ints"):
    """The points, clearances and polish flags of prototypes ``ids``, as a selection appends them."""
    b = thread()
    if b < ids.shape[0]:
        i = ids[b]
        for k in range(D):
            out_points[b, k] = points[i, k]
        out_clearance[b] = clearance[i]
        out_flags[b] = polished[i]


def set_floats(ids: "ints", values: "floats", out: "floats"):
    """``out[ids] = values``."""
    b = thread()
    if b < ids.shape[0]:
        out[ids[b]] = values[b]


def lower_floats(ids: "ints", values: "floats", out: "floats"):
    """``out[ids] = min(out[ids], values)``."""
    b = thread()
    if b < ids.shape[0]:
        out[ids[b]] = min(out[ids[b]], values[b])


def near_finish(found: "ints", sphere_count: "int", width: "ints", out: "int_table"):
    """Pad row ``b`` of a neighbour table and widen ``width``. Rows stay in the order the atomics
    gave: the nearest sphere is found alike in any order (see nearest_obstacle)."""
    b = thread()
    if b < found.shape[0]:
        for j in range(min(found[b], out.shape[1]), out.shape[1]):
            out[b, j] = sphere_count
        atomic_max(width, 0, found[b])


def split_mark(count: "int", lower: "points", upper: "points", reach: "floats", points: "points",
               clearance: "floats", bound: "floats", low: "float", longest: "float", counter: "ints", out_ids: "ints",
               out_values: "floats", out_points: "points", out_flags: "ints"):
    """Append the cells that may split, with their tightened bounds (the host store's
    ``split_candidates``); every cell looked at keeps its tighter bound."""
    i = thread()
    if i < count:
        side = upper[i, 0] - lower[i, 0]
        for k in range(1, D):
            side = max(side, upper[i, k] - lower[i, k])
        if side > longest and bound[i] >= low:
            c = clearance[i]
            far2 = 0.0
            for k in range(D):
                far = max(points[i, k] - lower[i, k], upper[i, k] - points[i, k])
                far2 += far * far
            b = reach[i]
            if c > -math.inf:  # converged: the attained clearance bounds the cell too
                b = min(b, c + math.sqrt(far2))
            bound[i] = min(bound[i], b)
            if b >= low:
                slot = atomic_add(counter, 0, 1)
                out_ids[slot] = i
                out_values[slot] = b


def split_cut(ids: "ints", lower: "points", upper: "points", reach: "floats", points: "points",
              clearance: "floats", polished: "ints", first_new: "int"):
    """Cut cell ``ids[b]`` in two across its longest side (the first of equals); the half without
    its prototype becomes row ``first_new + b``, with a new prototype at its centre and its
    parent's reach, which :func:`cell_distances` tightens (the host store's ``split_cells``)."""
    b = thread()
    if b < ids.shape[0]:
        i = ids[b]
        j = first_new + b
        axis = 0
        side = upper[i, 0] - lower[i, 0]
        for k in range(1, D):
            if upper[i, k] - lower[i, k] > side:
                axis = k
                side = upper[i, k] - lower[i, k]
        middle = 0.5 * (lower[i, axis] + upper[i, axis])
        low_half = points[i, axis] < middle
        for k in range(D):
            lower[j, k] = lower[i, k]
            upper[j, k] = upper[i, k]
        if low_half:
            upper[i, axis] = middle
            lower[j, axis] = middle
        else:
            lower[i, axis] = middle
            upper[j, axis] = middle
        reach[j] = reach[i]
        for k in range(D):
            points[j, k] = 0.5 * (lower[j, k] + upper[j, k])
        clearance[j] = -math.inf
        polished[j] = 0


def cell_distances(ids: "ints", count: "int", first_new: "int", lower: "points", upper: "points", reach: "floats",
                   wall: "floats", bound: "floats", prm: "floats", wall_slack: "float"):
    """Bound the cells cut by :func:`split_cut` by their centres' signed distances (the host's
    ``cell_bounds``): row ``ids[t]`` for ``t < count``, row ``first_new + t - count`` after; its
    reach (never above what it was), wall and split bound. A thread a half: the two halves'
    distances, each a walk of the mesh's trees, are not one chain."""
    t = thread()
    if t < 2 * count:
        row = first_new + t - count
        if t < count:
            row = ids[t]
        centre = point()
        half2 = 0.0
        for k in range(D):
            centre[k] = 0.5 * (lower[row, k] + upper[row, k])
            side = upper[row, k] - lower[row, k]
            half2 += side * side
        distance = sd(centre, prm)
        reach[row] = min(reach[row], -distance + 0.5 * math.sqrt(half2))
        wall[row] = -distance - wall_slack
        bound[row] = reach[row]


def touched_index_select(count: "int", points: "points", clearance: "floats", polished: "ints", centers: "points",
                         radii: "floats", origin: "floats", top: "float", heads: "ints", nxt: "ints",
                         level_of: "ints", level_head: "ints", level_next: "ints", level_count: "ints",
                         level_rmax: "floats", nearest: "int_table", counter: "ints", out_ids: "ints",
                         out_values: "floats", out_points: "points", out_flags: "ints"):
    """Append the prototypes whose clearance ball meets a new sphere (indexed in the arguments),
    with the nearest new sphere in the flags' place (``nearest`` (n, 1) is its scratch): the
    index of the new spheres tightens the bound of a touched prototype below its clearance."""
    i = thread()
    if i < count:
        c = clearance[i]
        if c > -math.inf:
            tight, found = index_near(i, points, points, c, 0, centers, radii, origin, top, heads, nxt, level_of,
                                      level_head, level_next, level_count, level_rmax, nearest, i, 1)
            if tight < c:
                slot = append(i, points, clearance, polished, counter, out_ids, out_values, out_points, out_flags)
                out_flags[slot] = nearest[i, 0]


# ---------------------------------------------------------------------------- the sphere index
# Built on the device (index_clear, index_insert_range) and queried there (index_near, of
# ndpack.backends.index_kernels).
def index_clear(heads: "ints", level_head: "ints", level_count: "ints", level_rmax: "floats"):
    """An empty sphere index: every bucket and level list empty (on ``max(buckets, levels)`` threads)."""
    i = thread()
    if i < heads.shape[0]:
        heads[i] = -1
    if i < level_head.shape[0]:
        level_head[i] = -1
        level_count[i] = 0
        level_rmax[i] = 0.0


def index_insert_range(start: "int", centers: "points", radii: "floats", origin: "floats", top: "float",
                       heads: "ints", nxt: "ints", level_of: "ints", level_head: "ints", level_next: "ints",
                       level_count: "ints", level_rmax: "floats"):
    """Put sphere ``start + thread`` in its level's grid and list. The lists' order follows the
    atomics, which no query depends on: a query's answers are sets, and its nearest sphere is the
    lowest id among equals (index_near)."""
    s = start + thread()
    if s < radii.shape[0]:
        level = index_level(radii[s], top, level_head.shape[0])
        side = top
        for _ in range(level):
            side = side * 0.5  # a power of two: top * 0.5**level exactly
        cell = point()
        for k in range(D):
            cell[k] = math.floor((centers[s, k] - origin[k]) / side)
        nxt[s] = atomic_exch(heads, index_bucket(level, cell, heads.shape[0] - 1), s)
        level_of[s] = level
        level_next[s] = atomic_exch(level_head, level, s)
        atomic_add(level_count, level, 1)
        atomic_max(level_rmax, level, radii[s])


def index_bound_ids(ids: "ints", lower: "points", upper: "points", reach: "floats", centers: "points",
                    radii: "floats", origin: "floats", top: "float", heads: "ints", nxt: "ints", level_of: "ints",
                    level_head: "ints", level_next: "ints", level_count: "ints", level_rmax: "floats",
                    scratch: "int_table", bound: "floats", spread: "int"):
    """``bound[b]``: the reference's upper bound of the clearance in the cell of ``ids[b]``, on
    thread ``b * spread`` (as ``move_ids``)."""
    t = thread()
    b = t // spread
    if t % spread == 0 and b < ids.shape[0]:
        i = ids[b]
        tight, found = index_near(i, lower, upper, reach[i], 0, centers, radii, origin, top, heads, nxt, level_of,
                                  level_head, level_next, level_count, level_rmax, scratch, 0, 0)
        bound[b] = tight


def index_fill_ids(ids: "ints", lower: "points", upper: "points", bound: "floats", centers: "points",
                   radii: "floats", origin: "floats", top: "float", heads: "ints", nxt: "ints", level_of: "ints",
                   level_head: "ints", level_next: "ints", level_count: "ints", level_rmax: "floats",
                   found: "ints", out: "int_table", spread: "int"):
    """Row ``b``: the spheres that come within ``bound[b]`` of the cell of ``ids[b]``; ``found[b]``
    their count; on thread ``b * spread`` (as ``move_ids``)."""
    t = thread()
    b = t // spread
    if t % spread == 0 and b < ids.shape[0]:
        tight, count = index_near(ids[b], lower, upper, bound[b], 1, centers, radii, origin, top, heads, nxt,
                                  level_of, level_head, level_next, level_count, level_rmax, out, b, out.shape[1])
        found[b] = count
