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


# The sphere index's queries (box_gap, index_near, ...) and the prototype store's kernels are written
# once for every compiled backend (ndpack.backends.index_kernels, ndpack.backends.store_kernels) and
# printed after this text; what they need of Warp's own follows.

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
