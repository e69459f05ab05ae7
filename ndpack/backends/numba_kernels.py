"""Per-point work of the Numba backends, shared by the CPU (prange) and CUDA (one thread each).

This file is read as text, not imported: :func:`ndpack.kernels.compile.numba_namespace` runs it
in the namespace of a compiled program, where ``sd(p, prm)`` is the signed distance of the shape
whose numbers are ``prm``, ``D`` the dimension, and ``point()`` a local array of length ``D``.
Every function mirrors a step of :class:`ndpack.backends.numpy_backend.NumpyBackend`, the
reference it is tested against.

Array arguments: ``points``, ``lower``, ``upper``, ``centers`` (n, D) float64; ``radii``,
``steps``, ``prm`` 1-D float64; ``nbr`` (n, k) int64 neighbour table padded with ``len(radii)``;
``h`` the finite-difference step (a fraction of the shape's size: an argument, so that a shape of
another size runs the same compiled code).
"""

# ruff: noqa: F821  (D, sd, sd_feature, sd_at, sd_slope and point exist where this text runs)


def nearest_obstacle(x, prm, centers, radii, nbr, row, floor, hint):
    """Clearance of ``x``, its nearest sphere (-1 when the shape's boundary is nearest), a lower
    bound of the boundary's distance (exact where it was evaluated, -inf where nothing is known),
    and the boundary's nearest feature there (``sd_feature``; -1 where not evaluated or where the
    shape has none, -2 where only known farther than the nearest sphere).

    ``floor`` is a lower bound of the boundary's distance at ``x`` (from the cell's wall, see
    :func:`wall_floor`): a sphere nearer than that is nearest without evaluating the shape, which
    spares the (mesh) distance deep inside. Where it is evaluated, the search for the nearest
    feature starts from ``hint`` (a feature found nearby, or -1) and looks no farther than the
    nearest sphere. The result is the same as evaluating it in full.
    The row ``nbr[row]`` may list the spheres in any order: ties resolve by sphere id.
    """
    gap_min = math.inf
    nearest = -1
    count = radii.shape[0]
    for j in range(nbr.shape[1]):
        s = nbr[row, j]
        if s >= count:  # the padding, which always follows a row's spheres
            break
        length2 = 0.0
        for k in range(D):
            t = x[k] - centers[s, k]
            length2 += t * t
        gap = math.sqrt(length2) - radii[s]
        # Equal gaps: the lower sphere id wins, whatever the table's order (as the
        # reference's argmin over ascending ids).
        if gap < gap_min or (gap == gap_min and nearest > s):
            gap_min = gap
            nearest = s
    if nearest >= 0 and gap_min < floor:
        return gap_min, nearest, -math.inf, -1.0
    feature = sd_feature(x, prm, hint, gap_min)
    if feature == -2.0:  # no boundary as near as the sphere: the sphere wins
        return gap_min, nearest, gap_min, feature
    boundary = -sd_at(x, prm, feature)
    if gap_min < boundary:  # the boundary wins over an equal sphere
        return gap_min, nearest, boundary, feature
    return boundary, -1, boundary, feature


def wall_floor(x, lower, upper, wall, cell):
    """Lower bound of the boundary's distance at ``x``: the cell centre's distance ``wall[cell]``
    (slack already taken off) less the way from the centre, as the distance is 1-Lipschitz."""
    length2 = 0.0
    for k in range(D):
        t = x[k] - 0.5 * (lower[cell, k] + upper[cell, k])
        length2 += t * t
    return wall[cell] - math.sqrt(length2)


def free_space(x, g, prm, centers, radii, nbr, row, floor, hint, h, direction):
    """Clearance of ``x``, a lower bound of the boundary's distance and the boundary's nearest
    feature (see :func:`nearest_obstacle`, which ``floor`` and ``hint`` are for); in ``g``, where
    ``direction`` is true, the direction away from the nearest obstacle.

    Away from the shape's boundary it is ``-grad sd``: closed-form from the nearest feature where
    the shape has one (meshes, outlines), else by central differences of step ``h`` (the
    reference uses the analytic gradient); away from a sphere, the unit vector from its centre.
    """
    clearance, nearest, boundary, feature = nearest_obstacle(x, prm, centers, radii, nbr, row, floor, hint)
    if not direction:  # a clearance alone: no distance evaluated beyond x's own
        return clearance, boundary, feature
    if nearest < 0 and feature >= 0.0:
        for k in range(D):
            g[k] = -sd_slope(x, prm, feature, -boundary, k)
    elif nearest < 0:
        # (down - up) / 2h per axis, with one call of sd in the loop: the compilers inline it
        # once, not twice (the shape's whole interpreter: half the code to compile).
        for m in range(2 * D):
            k = m // 2
            xk = x[k]
            x[k] = xk + h if m % 2 == 0 else xk - h
            value = sd(x, prm)
            x[k] = xk
            if m % 2 == 0:
                g[k] = -value
            else:
                g[k] = (g[k] + value) / (2.0 * h)
    else:
        length2 = 0.0
        for k in range(D):
            g[k] = x[k] - centers[nearest, k]
            length2 += g[k] * g[k]
        length = math.sqrt(length2)
        for k in range(D):
            if length > 0.0:
                g[k] = g[k] / length
            else:  # exactly at a centre: any way out will do, take axis 0 as the reference does
                g[k] = 1.0 if k == 0 else 0.0
    return clearance, boundary, feature


def clearance_one(i, points, prm, centers, radii, nbr, h, out, out_direction):
    """Clearance of point ``i`` into ``out``; its direction into ``out_direction`` if that has rows."""
    x = point()
    g = point()
    for k in range(D):
        x[k] = points[i, k]
    out[i] = free_space(x, g, prm, centers, radii, nbr, i, -math.inf, -1.0, h, out_direction.shape[0] > i)[0]
    if out_direction.shape[0] > i:
        for k in range(D):
            out_direction[i, k] = g[k]


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


def converge_from(x, g, best, cell, row, lower, upper, wall, prm, centers, radii, nbr, steps, h):
    """``p <- p + eps |c| g`` from ``x``, clipped to cell ``cell``, with neighbour row ``row``.

    Leaves the best point seen in ``best`` (as the reference does) and returns its clearance;
    ``x`` and ``g`` are scratch. The boundary's distance last bounded from below, at ``anchor``,
    bounds it nearby (1-Lipschitz) better than the cell's wall: steps are small, so most
    evaluations deep in the packing are spared. The last nearest feature found is the next
    search's hint.
    """
    anchor = point()
    anchored = -math.inf
    hint = -1.0
    for k in range(D):
        best[k] = x[k]
        anchor[k] = x[k]
    best_clearance = -math.inf
    count = steps.shape[0]
    for t in range(count + 1):
        length2 = 0.0
        for k in range(D):
            length2 += (x[k] - anchor[k]) ** 2
        floor = max(wall_floor(x, lower, upper, wall, cell), anchored - math.sqrt(length2) - 1e-3 * h)
        c, boundary, feature = free_space(x, g, prm, centers, radii, nbr, row, floor, hint, h, t < count)
        if feature >= 0.0:
            hint = feature
        if boundary > -math.inf:
            anchored = boundary
            for k in range(D):
                anchor[k] = x[k]
        if c > best_clearance:
            best_clearance = c
            for k in range(D):
                best[k] = x[k]
        if t < count:
            step = steps[t] * abs(c)
            for k in range(D):
                x[k] = min(max(x[k] + step * g[k], lower[cell, k]), upper[cell, k])
    return best_clearance


def restart_mix(h):
    """MurmurHash3's finaliser of a 32-bit word held in a uint64 (ndpack.backends.restarts)."""
    h = h ^ (h >> np.uint64(16))
    h = (h * np.uint64(0x85EBCA6B)) & np.uint64(0xFFFFFFFF)
    h = h ^ (h >> np.uint64(13))
    h = (h * np.uint64(0xC2B2AE35)) & np.uint64(0xFFFFFFFF)
    return h ^ (h >> np.uint64(16))


def restart_key(stream, i):
    """Prototype ``i``'s hash in a restart's ``stream`` (a uint64)."""
    word = np.uint64(i) & np.uint64(0xFFFFFFFF)
    return restart_mix((stream + word * np.uint64(0x9E3779B9)) & np.uint64(0xFFFFFFFF))


def restart_unit(key, counter):
    """Number ``counter`` (from 0) in [0, 1) of a prototype with hash ``key``."""
    word = restart_mix((key + np.uint64(counter + 1) * np.uint64(0x9E3779B9)) & np.uint64(0xFFFFFFFF))
    return float(word) * 2.3283064365386963e-10  # 2**-32: exact in float64


def move_one(b, lane, ids, first, first_rows, tries, stream, points, clearance, polished, lower, upper, wall, prm,
             centers, radii, nbr, steps, h, polish, polish_steps, polish_low, polish_from):
    """Move prototype ``ids[b]`` in place: from the best of its point, ``first[b]`` (clipped to
    its cell, where ``b < first_rows``) and ``tries`` random points of its cell drawn from
    ``stream``, converge; keep the result (``polish`` 0), or keep it only if better and mark it
    polished (1). Then, where it was not a polish and the clearance reaches ``polish_low``,
    polish it with ``polish_steps``: converge again from the result, keep it only if better,
    mark it polished; rows from ``polish_from`` on are only polished (the host store's
    ``move(..., ahead=PolishAhead(...))``). Lane 0 writes: the lanes of a cooperative launch
    (ndpack.backends.numba_cuda_lanes) all compute the same move.

    The move and the polish are two passes of one loop, so that the compilers inline the
    converge (the move kernel's bulk) once: with three call sites numba-cuda's move kernel itself
    was 14,180 of its 39,677 PTX lines."""
    i = ids[b]
    x = point()
    g = point()
    best = point()
    for k in range(D):
        x[k] = points[i, k]
    moving = b < polish_from
    lead = 1 if b < first_rows else 0
    if moving and lead + tries > 0:
        top = nearest_obstacle(x, prm, centers, radii, nbr, b, wall_floor(x, lower, upper, wall, i), -1.0)[0]
        key = restart_key(stream, i)
        for r in range(lead + tries):
            for k in range(D):
                if r < lead:
                    g[k] = min(max(first[b, k], lower[i, k]), upper[i, k])
                else:
                    g[k] = lower[i, k] + (upper[i, k] - lower[i, k]) * restart_unit(key, (r - lead) * D + k)
            # A start whose nearest sphere is nearer than the best so far cannot beat it: the best
            # clearance floors the boundary's bound, so such a start walks no tree (its clearance,
            # then the sphere's gap, above the true one, is only compared with top).
            c = nearest_obstacle(g, prm, centers, radii, nbr, b, max(wall_floor(g, lower, upper, wall, i), top),
                                 -1.0)[0]
            if c > top:
                top = c
                for k in range(D):
                    x[k] = g[k]
    for phase in range(0 if moving else 1, 2):  # 0: the move, 1: the polish
        c = converge_from(x, g, best, i, b, lower, upper, wall, prm, centers, radii, nbr,
                          steps if phase == 0 else polish_steps, h)
        if lane == 0:
            if (phase == 0 and polish == 0) or c > clearance[i]:
                clearance[i] = c
                for k in range(D):
                    points[i, k] = best[k]
            polished[i] = polish if phase == 0 else 1
        if phase == 0 and (polish != 0 or c < polish_low):
            break
        for k in range(D):
            x[k] = best[k]


def near_one(b, lower, upper, reach, centers, radii, out, width):
    """Spheres whose surface comes within the reach of box ``b``: how many, the first ``width`` in ``out``."""
    half2 = 0.0
    for k in range(D):
        half2 += 0.25 * (upper[b, k] - lower[b, k]) ** 2
    half = math.sqrt(half2)
    bound = reach[b]
    for s in range(radii.shape[0]):  # a tighter reach from the box centre's clearance
        bound = min(bound, centre_gap(b, s, lower, upper, centers, radii) + half)
    found = 0
    for s in range(radii.shape[0]):
        if box_gap(b, s, lower, upper, centers, radii) <= bound:
            if found < width:
                out[b, found] = s
            found += 1
    return found


def touched_one(i, points, clearance, centers, radii, out):
    out[i] = touches(i, points, clearance, centers, radii)


def touches(i, points, clearance, centers, radii):
    """The sphere nearest to prototype ``i`` (smallest gap, the first of equals) if its clearance
    ball meets it, else -1."""
    nearest = -1
    gap_min = clearance[i]
    for s in range(radii.shape[0]):
        length2 = 0.0
        for k in range(D):
            t = points[i, k] - centers[s, k]
            length2 += t * t
        gap = math.sqrt(length2) - radii[s]
        if gap < gap_min:
            gap_min = gap
            nearest = s
    return nearest


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

