"""Per-point work of the Numba backends, shared by the CPU (prange) and CUDA (one thread each).

This file is read as text, not imported: :func:`ndpack.kernels.compile.numba_namespace` runs it
in the namespace of a shape's compiled program, where ``sd(p, prm)`` is the shape's signed
distance, ``D`` the dimension, ``H`` the finite-difference step, and ``point()`` a local array of
length ``D``. Every function mirrors a step of :class:`ndpack.backends.numpy_backend.NumpyBackend`,
the reference it is tested against.

Array arguments: ``points``, ``lower``, ``upper``, ``centers`` (n, D) float64; ``radii``,
``steps``, ``prm`` 1-D float64; ``nbr`` (n, k) int64 neighbour table padded with ``len(radii)``.
"""

# ruff: noqa: F821  (D, H, sd and point exist where this text runs)


def nearest_obstacle(x, prm, centers, radii, nbr, row):
    """Clearance of ``x`` and its nearest sphere (-1 when the shape's boundary is nearest).

    The row ``nbr[row]`` may list the spheres in any order: ties resolve by sphere id.
    """
    clearance = -sd(x, prm)
    nearest = -1
    count = radii.shape[0]
    for j in range(nbr.shape[1]):
        s = nbr[row, j]
        if s < count:
            length2 = 0.0
            for k in range(D):
                t = x[k] - centers[s, k]
                length2 += t * t
            gap = math.sqrt(length2) - radii[s]
            # Equal gaps: the lower sphere id wins, whatever the table's order (as the
            # reference's argmin over ascending ids); the boundary wins over an equal sphere.
            if gap < clearance or (gap == clearance and nearest > s):
                clearance = gap
                nearest = s
    return clearance, nearest


def free_space(x, g, prm, centers, radii, nbr, row):
    """Clearance of ``x`` and, in ``g``, the direction away from its nearest obstacle.

    Away from the shape's boundary it is ``-grad sd`` by central differences of step ``H``
    (the reference uses the analytic gradient); away from a sphere, the unit vector from its centre.
    """
    clearance, nearest = nearest_obstacle(x, prm, centers, radii, nbr, row)
    if nearest < 0:
        for k in range(D):
            xk = x[k]
            x[k] = xk + H
            up = sd(x, prm)
            x[k] = xk - H
            down = sd(x, prm)
            x[k] = xk
            g[k] = (down - up) / (2.0 * H)
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
    return clearance


def clearance_one(i, points, prm, centers, radii, nbr, out, out_direction):
    """Clearance of point ``i`` into ``out``; its direction into ``out_direction`` if that has rows."""
    x = point()
    g = point()
    for k in range(D):
        x[k] = points[i, k]
    out[i] = free_space(x, g, prm, centers, radii, nbr, i)
    if out_direction.shape[0] > i:
        for k in range(D):
            out_direction[i, k] = g[k]


def converge_one(i, points, lower, upper, prm, centers, radii, nbr, steps, out_points, out_clearance):
    """Converge point ``i`` in its cell (row ``i`` of every table) into the outputs."""
    x = point()
    g = point()
    best = point()
    for k in range(D):
        x[k] = points[i, k]
    out_clearance[i] = converge_from(x, g, best, i, i, lower, upper, prm, centers, radii, nbr, steps)
    for k in range(D):
        out_points[i, k] = best[k]


def converge_from(x, g, best, cell, row, lower, upper, prm, centers, radii, nbr, steps):
    """``p <- p + eps |c| g`` from ``x``, clipped to cell ``cell``, with neighbour row ``row``.

    Leaves the best point seen in ``best`` (as the reference does) and returns its clearance;
    ``x`` and ``g`` are scratch.
    """
    for k in range(D):
        best[k] = x[k]
    best_clearance = -math.inf
    count = steps.shape[0]
    for t in range(count + 1):
        c = free_space(x, g, prm, centers, radii, nbr, row)
        if c > best_clearance:
            best_clearance = c
            for k in range(D):
                best[k] = x[k]
        if t < count:
            step = steps[t] * abs(c)
            for k in range(D):
                x[k] = min(max(x[k] + step * g[k], lower[cell, k]), upper[cell, k])
    return best_clearance


def move_one(b, ids, starts, tries, points, clearance, polished, lower, upper, prm, centers, radii, nbr,
             steps, polish):
    """Move prototype ``ids[b]`` in place: from the best of its point and ``starts[:tries, b]``,
    converge; keep the result (``polish`` 0), or keep it only if better and mark it polished (1)."""
    i = ids[b]
    x = point()
    g = point()
    best = point()
    for k in range(D):
        x[k] = points[i, k]
    if tries > 0:
        top = nearest_obstacle(x, prm, centers, radii, nbr, b)[0]
        for t in range(tries):
            for k in range(D):
                g[k] = starts[t, b, k]
            c = nearest_obstacle(g, prm, centers, radii, nbr, b)[0]
            if c > top:
                top = c
                for k in range(D):
                    x[k] = g[k]
    c = converge_from(x, g, best, i, b, lower, upper, prm, centers, radii, nbr, steps)
    if polish == 0 or c > clearance[i]:
        clearance[i] = c
        for k in range(D):
            points[i, k] = best[k]
    polished[i] = polish


def near_one(b, lower, upper, reach, centers, radii, out, width):
    """Spheres whose surface comes within the reach of box ``b``: how many, the first ``width`` in ``out``."""
    half2 = 0.0
    for k in range(D):
        half2 += 0.25 * (upper[b, k] - lower[b, k]) ** 2
    half = math.sqrt(half2)
    bound = reach[b]
    for s in range(radii.shape[0]):  # a tighter reach from the box centre's clearance
        length2 = 0.0
        for k in range(D):
            t = 0.5 * (lower[b, k] + upper[b, k]) - centers[s, k]
            length2 += t * t
        bound = min(bound, math.sqrt(length2) - radii[s] + half)
    found = 0
    for s in range(radii.shape[0]):
        outside2 = 0.0
        for k in range(D):
            t = max(lower[b, k] - centers[s, k], centers[s, k] - upper[b, k], 0.0)
            outside2 += t * t
        if math.sqrt(outside2) - radii[s] <= bound:
            if found < width:
                out[b, found] = s
            found += 1
    return found


def touched_one(i, points, clearance, centers, radii, out):
    out[i] = touches(i, points, clearance, centers, radii)


def touches(i, points, clearance, centers, radii):
    """Whether prototype ``i``'s clearance ball meets one of the spheres."""
    for s in range(radii.shape[0]):
        length2 = 0.0
        for k in range(D):
            t = points[i, k] - centers[s, k]
            length2 += t * t
        if math.sqrt(length2) - radii[s] < clearance[i]:
            return True
    return False
