"""Random restarts drawn from a counter-based hash: the same points on every backend, made where
the prototypes live.

A restart tries a prototype's cell at a few random points and starts from the best of them (and
its current point). The points come from a hash of (run, restart, prototype id, try, axis), not
from a generator's stream: a GPU draws them inside its move kernel, with nothing uploaded, and the
host draws the same numbers for the same prototype, so that every backend still makes the same
packing from the same seed. The hash is MurmurHash3's 32-bit finaliser. The kernels hold its
32-bit words in 64-bit integers and mask every product, so that none overflows (NumPy scalars
warn on overflow, and the CUDA simulator runs the kernels on NumPy scalars); the host hashes
uint32 arrays, whose products wrap to the same bits. ``move_kernels.py`` implements the same
functions (``restart_key``, ``restart_unit``) once for every compiled backend, tested equal to these.

A *stream* (one 32-bit number) names one restart of many prototypes: :func:`stream` of the run's
key and a serial number the driver counts up.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

MASK = 0xFFFFFFFF
#: MurmurHash3's finaliser constants, and the golden ratio's 32 bits (spreads counters apart).
MIX1, MIX2, GOLDEN = 0x85EBCA6B, 0xC2B2AE35, 0x9E3779B9
#: A hash (32 bits) as a number in [0, 1): exact in float64.
UNIT = 2.0**-32


def _mix(h):
    """MurmurHash3's finaliser of a 32-bit word ``h`` (a Python int)."""
    h = h ^ (h >> 16)
    h = (h * MIX1) & MASK
    h = h ^ (h >> 13)
    h = (h * MIX2) & MASK
    return h ^ (h >> 16)


def run_key(rng: np.random.Generator) -> int:
    """A run's 32-bit key, drawn once from the run's seeded generator."""
    return int(rng.integers(0, MASK + 1))


def stream(key: int, serial: int) -> int:
    """The 32-bit stream of restart number ``serial`` of the run with ``key``."""
    return _mix(_mix(serial & MASK) ^ (key & MASK))


def _mix_in_place(h: np.ndarray) -> np.ndarray:
    """:func:`_mix` of a uint32 array, in place: uint32 products wrap modulo 2**32 as the masks
    do, without a copy per step (six times as fast as uint64 with masks)."""
    h ^= h >> np.uint32(16)
    h *= np.uint32(MIX1)
    h ^= h >> np.uint32(13)
    h *= np.uint32(MIX2)
    h ^= h >> np.uint32(16)
    return h


def units(stream_: int, ids: np.ndarray, tries: int, dim: int) -> np.ndarray:
    """Numbers in [0, 1): (tries, k, dim) float64, for prototypes ``ids`` (k,) int.

    Entry ``[t, b, k]`` is ``restart_unit(restart_key(stream, ids[b]), t * dim + k)`` of the kernels.
    """
    ids = np.asarray(ids).astype(np.uint32)  # modulo 2**32, as the kernels' mask
    key = _mix_in_place(np.uint32(stream_) + ids * np.uint32(GOLDEN))  # (k,)
    counters = np.arange(1, tries * dim + 1, dtype=np.uint32).reshape(tries, 1, dim) * np.uint32(GOLDEN)
    return _mix_in_place(key[None, :, None] + counters) * UNIT


@dataclass(frozen=True)
class Restarts:
    """How a move restarts its prototypes: from the best of their current point, a first point
    (for the first ``len(first)`` of them) and ``tries`` random points of their cells from
    ``stream``.

    Attributes
    ----------
    stream : int
        The 32-bit stream (:func:`stream`).
    tries : int
        Random points per prototype.
    first : (j, d) float64 or None
        A point tried first by each of the move's first ``j`` prototypes, clipped to its cell.
    """

    stream: int
    tries: int
    first: np.ndarray | None = None

    def part(self, rows: slice) -> "Restarts":
        """The restarts of the prototypes at positions ``rows`` (a slice from 0 on) of the move's ids."""
        first = None if self.first is None else self.first[rows]
        return Restarts(self.stream, self.tries, first if first is not None and len(first) else None)

    def points(self, ids: np.ndarray, lower: np.ndarray, upper: np.ndarray, current: np.ndarray) -> np.ndarray | None:
        """The starts of prototypes ``ids`` (k,) in cells ``lower``, ``upper`` (k, d) now at
        ``current`` (k, d): (t, k, d) float64, the first points (clipped; the current point for
        prototypes beyond them, which changes nothing) then the random points; None when there
        are none."""
        parts = []
        if self.first is not None:
            lead = current.copy()
            lead[: len(self.first)] = self.first
            parts.append(np.clip(lead, lower, upper)[None])
        if self.tries:
            parts.append(lower + (upper - lower) * units(self.stream, ids, self.tries, lower.shape[1]))
        return np.concatenate(parts) if parts else None
