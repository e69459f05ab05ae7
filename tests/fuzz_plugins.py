"""User plug-ins for fuzzing: exact distances written as a user would, in the kernel language
(:class:`ndpack.ScalarFunction`, every backend) and in NumPy (:class:`ndpack.Function`, the NumPy
backend; :mod:`fuzz_shapes` writes those as lambdas in the tree's text).

Each is the exact signed distance of a ball or a box; the fuzzing reference of the same numbers is
:func:`fuzz_reference.ball` or :func:`fuzz_reference.box`, which shares no code with these.
``D`` is the dimension (the kernel language's name for it).
"""

import math


def ball(p, params):
    """A ball: ``params`` are its centre (D numbers), then its radius."""
    s = 0.0
    for i in range(D):  # noqa: F821  (D is the dimension)
        s += (p[i] - params[i]) * (p[i] - params[i])
    return math.sqrt(s) - params[D]  # noqa: F821


def box(p, params):
    """An axis-aligned box: ``params`` are its lower corner, then its upper corner (D each)."""
    outside = 0.0
    inside = -1.0e300
    for i in range(D):  # noqa: F821
        gap = max(params[i] - p[i], p[i] - params[D + i])  # noqa: F821
        inside = max(inside, gap)
        if gap > 0.0:
            outside += gap * gap
    if outside > 0.0:
        return math.sqrt(outside)
    return inside
