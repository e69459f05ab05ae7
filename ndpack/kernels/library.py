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
