"""The empty set and all of space: what a CSG tree may hold where a part has no points.

A difference that removes everything, an intersection of parts that do not meet, or an empty
manifold3d solid is a valid empty set, and a tree that holds one is still a shape: ``a - empty``
is ``a``, ``a | empty`` is ``a``, ``a & empty`` is empty. The operators (``|``, ``&``, ``-``,
``~`` and the transforms, see :class:`ndpack.oracle.Oracle`) apply these rules as a tree is
built, and so do the node classes (``Union(a, empty)`` is ``a``, see
:class:`ndpack.shapes.csg._Node`), so an :class:`Empty` or :class:`Everything` is only ever a
whole shape, never a node's part, and no kernel evaluates one. Only an empty *whole* shape is
an error, raised where it is packed (:func:`ndpack.oracle.check_packable`) with the reason it
is empty.
"""

from __future__ import annotations

import numpy as np

from ..errors import ShapeError
from ..oracle import Oracle, parts


class _Special(Oracle):
    """A point set that no node of a tree holds as a part (see the module)."""

    exact_inside = exact_outside = True
    convex = True

    def __init__(self, dim: int, reason: str):
        self.dim, self.reason = int(dim), reason

    def _kernel(self, program):
        raise ShapeError(f"{self!r} reached a kernel: {self.reason}; build trees with |, & and -, "
                         "which leave it out")

    _tape = _kernel

    def _gradient(self, points):
        return np.zeros_like(points)

    # Moved, turned, scaled or grown, nothing stays nothing and all of space stays all of space.
    def translate(self, offset):
        return self

    def rotate(self, matrix, center=None):
        return self

    def scale_by(self, factor, center=None):
        return self

    def offset(self, amount):
        return self


class Empty(_Special):
    """No point at all: its distance is +inf everywhere.

    Parameters
    ----------
    dim : int
    reason : str
        Why it is empty, in words (for the error raised where it is packed).
    """

    is_empty_set = True

    def __init__(self, dim: int, reason: str = "the shape is empty"):
        super().__init__(dim, reason)
        self._bounds = np.stack([np.full(self.dim, np.inf), np.full(self.dim, -np.inf)])

    def __repr__(self):
        return f"Empty(dim={self.dim})"

    def _distance(self, points):
        return np.full(len(points), np.inf)

    def _exact_volume(self):
        return 0.0

    # Combined with nothing, the other part (or nothing).
    def union(self, *others):
        others = _dimension(self, others)
        return others[0].union(*others[1:]) if others else self

    def intersection(self, *others):
        _dimension(self, others)
        return self

    def difference(self, *others):
        _dimension(self, others)
        return self

    def complement(self):
        return Everything(self.dim, f"the complement of an empty set ({self.reason})")

    def shell(self, thickness):
        return self

    def smooth_union(self, other, blend):
        return _dimension(self, (other,))[0]


class Everything(_Special):
    """All of space: its distance is -inf everywhere (the complement of an :class:`Empty`)."""

    def __init__(self, dim: int, reason: str = "all of space"):
        super().__init__(dim, reason)
        self._bounds = np.stack([np.full(self.dim, -np.inf), np.full(self.dim, np.inf)])

    def __repr__(self):
        return f"Everything(dim={self.dim})"

    def _distance(self, points):
        return np.full(len(points), -np.inf)

    def union(self, *others):
        _dimension(self, others)
        return self

    def intersection(self, *others):
        others = _dimension(self, others)
        return others[0].intersection(*others[1:]) if others else self

    def difference(self, *others):
        others = _dimension(self, others)
        return others[0].union(*others[1:]).complement() if others else self

    def complement(self):
        return Empty(self.dim, "the complement of all of space")

    def shell(self, thickness):
        return Empty(self.dim, "the shell of all of space (it has no boundary)")

    def smooth_union(self, other, blend):
        _dimension(self, (other,))
        return self


def is_special(shape) -> bool:
    """Whether ``shape`` is an :class:`Empty` or an :class:`Everything`."""
    return isinstance(shape, _Special)


def _dimension(shape, others):
    """The others as shapes (other libraries' converted), checked to share ``shape``'s dimension."""
    return parts(shape, others)[1:]

