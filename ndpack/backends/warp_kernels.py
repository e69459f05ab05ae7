"""Warp kernels of the Warp backend, written in Warp's Python dialect.

This file is read as text, not imported: :func:`ndpack.kernels.compile.warp_module` appends it
to a shape's generated module, which defines ``F`` (the float type), ``D``, ``VecD`` (a point)
and ``sd(p, prm)``. Every kernel mirrors a step of the NumPy reference
(:class:`ndpack.backends.numpy_backend.NumpyBackend`) and of the Numba per-point functions.
"""

# ruff: noqa: F821  (F, D, VecD, sd and wp exist where this text runs)


@wp.func
def free_space(x: VecD, prm: wp.array(dtype=F), centers: wp.array(dtype=VecD), radii: wp.array(dtype=F),
               nbr: wp.array2d(dtype=wp.int32), row: int, h: F):
    """Clearance of ``x`` and the direction away from its nearest obstacle (``-grad sd`` by
    central differences of step ``h``, or away from the nearest sphere's centre)."""
    clearance = -sd(x, prm)
    nearest = int(-1)
    count = radii.shape[0]
    for j in range(nbr.shape[1]):
        s = nbr[row, j]
        if s < count:
            gap = wp.length(x - centers[s]) - radii[s]
            if gap < clearance:
                clearance = gap
                nearest = s
    g = VecD()
    if nearest < 0:
        for k in range(D):
            q = x
            q[k] = x[k] + h
            up = sd(q, prm)
            q[k] = x[k] - h
            down = sd(q, prm)
            g[k] = (down - up) / (F(2.0) * h)
    else:
        away = x - centers[nearest]
        length = wp.length(away)
        if length > F(0.0):
            g = away / length
        else:
            g[0] = F(1.0)
    return clearance, g


@wp.kernel
def clearance_all(points: wp.array(dtype=VecD), prm: wp.array(dtype=F), centers: wp.array(dtype=VecD),
                  radii: wp.array(dtype=F), nbr: wp.array2d(dtype=wp.int32), h: F, out: wp.array(dtype=F),
                  out_direction: wp.array(dtype=VecD)):
    i = wp.tid()
    c, g = free_space(points[i], prm, centers, radii, nbr, i, h)
    out[i] = c
    if out_direction.shape[0] > i:
        out_direction[i] = g


@wp.kernel
def converge_all(points: wp.array(dtype=VecD), lower: wp.array(dtype=VecD), upper: wp.array(dtype=VecD),
                 prm: wp.array(dtype=F), centers: wp.array(dtype=VecD), radii: wp.array(dtype=F),
                 nbr: wp.array2d(dtype=wp.int32), steps: wp.array(dtype=F), h: F,
                 out_points: wp.array(dtype=VecD), out_clearance: wp.array(dtype=F)):
    i = wp.tid()
    x = points[i]
    best = x
    best_clearance = F(-1.0e30)
    count = steps.shape[0]
    for t in range(count + 1):
        c, g = free_space(x, prm, centers, radii, nbr, i, h)
        if c > best_clearance:
            best_clearance = c
            best = x
        if t < count:
            x = x + (steps[t] * wp.abs(c)) * g
            for k in range(D):
                x[k] = wp.min(wp.max(x[k], lower[i][k]), upper[i][k])
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


@wp.kernel
def touched_all(points: wp.array(dtype=VecD), clearance: wp.array(dtype=F), centers: wp.array(dtype=VecD),
                radii: wp.array(dtype=F), out: wp.array(dtype=wp.int32)):
    i = wp.tid()
    hit = int(0)
    for s in range(radii.shape[0]):
        if wp.length(points[i] - centers[s]) - radii[s] < clearance[i]:
            hit = 1
    out[i] = hit
