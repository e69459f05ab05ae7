"""Arithmetic whose bits do not depend on the machine, for the numbers that steer a packing.

NumPy picks its transcendental functions (``power``, ``exp``, ``log``, ...) by the CPU at run time:
on an AVX-512 machine ``np.power`` of a float64 array takes a vectorised routine whose last bit
differs now and then from the AVX2 or SSE one (measured: 3 of the 50 steps of the cooling
schedule). The C library's ``pow`` and ``exp`` may differ between versions too. A step size that
differs in its last bit moves a prototype elsewhere after a few hundred rounds, and the same seed
gave other spheres on another machine (issue 45).

The few such numbers a run computes (the cooling schedules, the grid's cell side) are computed
here with Python's :mod:`decimal`, which works in integers and gives the same digits everywhere,
then rounded once to float64. They are a few hundred numbers a run, and the schedules are kept
once computed (about 14 ms each in Decimal, a GPU packing's hundredth). Every
other operation the drivers use is one IEEE 754 rounds exactly (+, -, *, /, sqrt, comparisons),
or is summed in a fixed order (see ``docs/reliability.md``).
"""

from __future__ import annotations

import functools
from decimal import Decimal, localcontext

#: Digits carried: far more than float64's 17, so that the one rounding to float64 decides.
_DIGITS = 40


def power(base: float, exponent: float) -> float:
    """``base ** exponent`` for ``base >= 0``, the same float64 on every machine."""
    if base < 0:
        raise ValueError(f"power() takes a base >= 0, not {base}")
    with localcontext() as context:
        context.prec = _DIGITS
        return float(Decimal(float(base)) ** Decimal(float(exponent)))


def root(value: float, degree: int) -> float:
    """The ``degree``-th root of ``value >= 0``, the same float64 on every machine."""
    if value < 0 or degree < 1:
        raise ValueError(f"root() takes a value >= 0 and a degree >= 1, not {value} and {degree}")
    with localcontext() as context:
        context.prec = _DIGITS
        return float(Decimal(float(value)) ** (Decimal(1) / Decimal(int(degree))))


def geometric_schedule(count: int, start: float, end: float, power_of_time: float) -> tuple[float, ...]:
    """``start * (end / start) ** ((t / (count - 1)) ** power_of_time)`` for ``t = 0 .. count - 1``,
    each the same float64 on every machine (``count >= 2``, ``start, end > 0``)."""
    return _geometric_schedule(int(count), float(start), float(end), float(power_of_time))


@functools.lru_cache(maxsize=64)
def _geometric_schedule(count: int, start: float, end: float, power_of_time: float) -> tuple[float, ...]:
    with localcontext() as context:
        context.prec = _DIGITS
        first, ratio = Decimal(start), Decimal(end) / Decimal(start)
        shape, last = Decimal(power_of_time), Decimal(count - 1)
        return tuple(float(first * ratio ** ((Decimal(t) / last) ** shape)) for t in range(count))
