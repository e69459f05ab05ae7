"""Signed distances of the built-in shapes, written once in the kernel language.

Each function here is plain Python in the subset of :mod:`ndpack.kernels.language`: ``p`` is the
point, ``prm`` the flat parameter array and ``o`` the offset of this shape's parameters in it;
``D`` is the dimension, fixed when the program is printed. The comment above each function gives
its parameter layout; the shape's ``_kernel`` method writes the parameters in that order. The
formulas mirror the NumPy oracles in :mod:`ndpack.shapes`, which are the reference they are
tested against.
"""

# ruff: noqa: F821  (D and point are supplied when a kernel is printed)

import math


# [center (D), radius]
def ball(p, prm, o: int):
    s = 0.0
    for i in range(D):
        t = p[i] - prm[o + i]
        s += t * t
    return math.sqrt(s) - prm[o + D]


# [center (D), half sides (D)]: the exact distance to |x - center| <= half, componentwise.
def box(p, prm, o: int):
    outside = 0.0
    largest = -1.0e300
    for i in range(D):
        q = abs(p[i] - prm[o + i]) - prm[o + D + i]
        if q > 0.0:
            outside += q * q
        largest = max(largest, q)
    return math.sqrt(outside) + min(largest, 0.0)


# [center (D), inner half sides (D), radius]: the inner box dilated by radius.
def rounded_box(p, prm, o: int):
    return box(p, prm, o) - prm[o + 2 * D]


# [unit normal (D), offset]: n . x - offset.
def half_space(p, prm, o: int):
    s = 0.0
    for i in range(D):
        s += p[i] * prm[o + i]
    return s - prm[o + D]


# [unit normal (D), middle, half thickness]: |n . x - middle| - half.
def slab(p, prm, o: int):
    s = 0.0
    for i in range(D):
        s += p[i] * prm[o + i]
    return abs(s - prm[o + D]) - prm[o + D + 1]


# [a (D), b - a (D), unit axis (D), |b - a|^2, radius]: the distance to the segment minus radius.
def capsule(p, prm, o: int):
    length_sq = prm[o + 3 * D]
    t = 0.0
    for i in range(D):
        t += (p[i] - prm[o + i]) * prm[o + D + i]
    if length_sq == 0.0:
        t = 0.0
    else:
        t = t / length_sq
    c = min(max(t, 0.0), 1.0)
    # Beside the segment, remove the component along the axis once more (as the NumPy oracle).
    along = 0.0
    if t > 0.0 and t < 1.0:
        for i in range(D):
            along += (p[i] - prm[o + i] - c * prm[o + D + i]) * prm[o + 2 * D + i]
    s = 0.0
    for i in range(D):
        v = p[i] - prm[o + i] - c * prm[o + D + i]
        v -= along * prm[o + 2 * D + i]
        s += v * v
    return math.sqrt(s) - prm[o + 3 * D + 1]


# [middle (D), unit axis (D), radius, half length]: a (D-1)-ball times an interval.
def cylinder(p, prm, o: int):
    axial = 0.0
    for i in range(D):
        axial += (p[i] - prm[o + i]) * prm[o + D + i]
    # The radial vector, projected once more across the axis (as the NumPy oracle).
    again = 0.0
    for i in range(D):
        again += (p[i] - prm[o + i] - axial * prm[o + D + i]) * prm[o + D + i]
    s = 0.0
    for i in range(D):
        v = p[i] - prm[o + i] - axial * prm[o + D + i]
        v -= again * prm[o + D + i]
        s += v * v
    ra = math.sqrt(s) - prm[o + 2 * D]
    ha = abs(axial) - prm[o + 2 * D + 1]
    outside_r = max(ra, 0.0)
    outside_h = max(ha, 0.0)
    return min(max(ra, ha), 0.0) + math.sqrt(outside_r * outside_r + outside_h * outside_h)


# [m, unit normals (m rows of D), offsets (m)]: max_i (n_i . x - b_i).
def polytope(p, prm, o: int):
    m = int(prm[o])
    largest = -1.0e300
    for k in range(m):
        s = 0.0
        for i in range(D):
            s += p[i] * prm[o + 1 + k * D + i]
        largest = max(largest, s - prm[o + 1 + m * D + k])
    return largest


# [center (D), radii (D), smallest radius]: (|(x - c) / r| - 1) * min(r), a lower bound.
def ellipsoid(p, prm, o: int):
    s = 0.0
    for i in range(D):
        t = (p[i] - prm[o + i]) / prm[o + D + i]
        s += t * t
    return (math.sqrt(s) - 1.0) * prm[o + 2 * D]


# [center (3), major radius, minor radius]: a ring torus around the z axis (D = 3).
def torus(p, prm, o: int):
    x = p[0] - prm[o]
    y = p[1] - prm[o + 1]
    z = p[2] - prm[o + 2]
    radial = math.sqrt(x * x + y * y) - prm[o + 3]
    return math.sqrt(radial * radial + z * z) - prm[o + 4]
