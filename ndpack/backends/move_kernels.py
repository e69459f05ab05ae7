"""The move: a prototype's converge and its restarts, written once for every compiled backend.

This file is read as text, not imported: :func:`ndpack.kernels.portable.render` prints it for
Numba (the CPU backend and numba-cuda: :mod:`ndpack.backends.numba_common`) and for Warp
(:mod:`ndpack.backends.warp_backend`), in the namespace of a compiled program, where ``sd(p, prm)``
is the signed distance of the shape whose numbers are ``prm`` (and ``sd_feature``, ``sd_at`` and
``sd_slope`` its nearest feature's queries), ``D`` the dimension and ``point()`` a local point.
Every function mirrors a step of :class:`ndpack.backends.numpy_backend.NumpyBackend`, the
reference it is tested against.

Arguments (the types of :data:`ndpack.kernels.portable.ARGUMENT_TYPES`): ``points``, ``lower``,
``upper``, ``centers`` (n, D) floats; ``radii``, ``steps``, ``prm`` 1-D floats; ``nbr`` (n, k) int
neighbour table padded with ``len(radii)``; ``h`` the finite-difference step (a fraction of the
shape's size: an argument, so that a shape of another size runs the same compiled code). A point
given to a function that writes it (``g``, ``best``) comes back written, in Numba and in Warp alike
(see :mod:`ndpack.kernels.portable`).
"""

# ruff: noqa: F821  (D, sd, sd_feature, sd_at, sd_slope, point and u64 exist where this text runs)


def nearest_obstacle(x: "point", prm: "floats", centers: "points", radii: "floats", nbr: "int_table", row: "int",
                     floor: "float", hint: "float"):
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


def wall_floor(x: "point", lower: "points", upper: "points", wall: "floats", cell: "int"):
    """Lower bound of the boundary's distance at ``x``: the cell centre's distance ``wall[cell]``
    (slack already taken off) less the way from the centre, as the distance is 1-Lipschitz."""
    length2 = 0.0
    for k in range(D):
        t = x[k] - 0.5 * (lower[cell, k] + upper[cell, k])
        length2 += t * t
    return wall[cell] - math.sqrt(length2)


def free_space(x: "point", g: "point", prm: "floats", centers: "points", radii: "floats", nbr: "int_table", row: "int",
               floor: "float", hint: "float", h: "float", direction: "bool"):
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


def clearance_one(i: "int", points: "points", prm: "floats", centers: "points", radii: "floats", nbr: "int_table",
                  h: "float", out: "floats", out_direction: "points"):
    """Clearance of point ``i`` into ``out``; its direction into ``out_direction`` if that has rows."""
    x = point()
    g = point()
    for k in range(D):
        x[k] = points[i, k]
    c, boundary, feature = free_space(x, g, prm, centers, radii, nbr, i, -math.inf, -1.0, h, out_direction.shape[0] > i)
    out[i] = c
    if out_direction.shape[0] > i:
        for k in range(D):
            out_direction[i, k] = g[k]


def converge_from(x: "point", g: "point", best: "point", cell: "int", row: "int", lower: "points", upper: "points",
                  wall: "floats", prm: "floats", centers: "points", radii: "floats", nbr: "int_table", steps: "floats",
                  h: "float"):
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
            d = x[k] - anchor[k]
            length2 += d * d
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


def restart_mix(h: "u64"):
    """MurmurHash3's finaliser of a 32-bit word held in a uint64 (ndpack.backends.restarts)."""
    h = h ^ (h >> u64(16))
    h = (h * u64(0x85EBCA6B)) & u64(0xFFFFFFFF)
    h = h ^ (h >> u64(13))
    h = (h * u64(0xC2B2AE35)) & u64(0xFFFFFFFF)
    return h ^ (h >> u64(16))


def restart_key(stream: "u64", i: "int"):
    """Prototype ``i``'s hash in a restart's ``stream`` (a uint64)."""
    word = u64(i) & u64(0xFFFFFFFF)
    return restart_mix((stream + word * u64(0x9E3779B9)) & u64(0xFFFFFFFF))


def restart_unit(key: "u64", counter: "int"):
    """Number ``counter`` (from 0) in [0, 1) of a prototype with hash ``key``."""
    word = restart_mix((key + u64(counter + 1) * u64(0x9E3779B9)) & u64(0xFFFFFFFF))
    return float(word) * 2.3283064365386963e-10  # 2**-32: exact in float64


def move_one(b: "int", lane: "int", ids: "ints", first: "points", first_rows: "int", tries: "int", stream: "u64",
             points: "points", clearance: "floats", polished: "ints", lower: "points", upper: "points", wall: "floats",
             prm: "floats", centers: "points", radii: "floats", nbr: "int_table", steps: "floats", h: "float",
             polish: "int", polish_steps: "floats", polish_low: "float", polish_from: "int"):
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
        top, nearest, bound, feature = nearest_obstacle(x, prm, centers, radii, nbr, b,
                                                        wall_floor(x, lower, upper, wall, i), -1.0)
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
            c, nearest, bound, feature = nearest_obstacle(g, prm, centers, radii, nbr, b,
                                                          max(wall_floor(g, lower, upper, wall, i), top), -1.0)
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


def touches(i: "int", points: "points", clearance: "floats", centers: "points", radii: "floats"):
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
