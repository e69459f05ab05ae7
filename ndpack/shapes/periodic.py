"""A periodic domain: a shape whose bounding box wraps around along some axes."""

from __future__ import annotations

import numpy as np

from ..errors import ShapeError
from ..oracle import Oracle
from ..geometry.period import Period
from .csg import _Transformed
from .primitives import Box


class Periodic(_Transformed):
    """``shape`` with some axes of its bounding box periodic: a sphere that crosses a periodic
    face comes back in at the opposite one (``nd.Periodic(nd.Box(...))`` is the plain periodic
    box of N-D packing experiments and bulk granular samples).

    Along a periodic axis the shape is its cross-section through the middle of its bounds,
    extended (the distance is the shape's at the point moved to that middle): a box, or a
    cylinder along that axis, is unchanged but for the faces that wrap, which are no walls.
    Packing such a shape keeps every sphere clear of every image of every other
    (:mod:`ndpack.geometry.period`), and no sphere wider than half the shortest period (it would meet its
    own image). The packing records the cell (``params["bounds"]``) and the periods
    (``params["period"]``), which the DEM files write as a periodic box.

    Parameters
    ----------
    shape : Oracle
        A bounded shape; its bounds are the cell.
    axes : int, sequence of int, or sequence of bool, optional
        The periodic axes; default all.
    """

    _by_operator = staticmethod(lambda child, axes=None: child)  # an empty set stays one

    def __init__(self, shape: Oracle, axes=None):
        super().__init__(shape)
        if not shape.is_bounded:
            raise ShapeError(f"a periodic domain needs a bounded shape, whose bounds are the cell; {shape!r} is "
                             "unbounded: intersect it with a box")
        mask = _axes_mask(axes, self.dim)
        lower, upper = shape.bounds
        self.period = Period(lower, upper, mask)
        self._keep = (~mask).astype(np.float64)
        self._shift = np.where(mask, (lower + upper) / 2, 0.0)
        self._bounds = shape.bounds.copy()
        self.exact_inside = self.exact_outside = False  # a bound of the extended cross-section's distance

    def _to_child(self, points):
        return points * self._keep + self._shift

    def _from_child_gradient(self, gradients):
        return gradients * self._keep

    def _exact_volume(self):
        # Any cross-section of a box is its middle one; other shapes are measured (Monte Carlo).
        return self.child._exact_volume() if isinstance(self.child, Box) else None

    def _kernel(self, program):
        # [keep (D): 1 along a free axis, 0 along a periodic one; shift (D): the middle there].
        o = program.add_params([*self._keep, *self._shift])
        child = program.shape(self.child)
        return program.define(
            "def _(p, prm):\n"
            "    q = point()\n"
            "    for i in range(D):\n"
            f"        q[i] = p[i] * prm[{o} + i] + prm[{o} + D + i]\n"
            f"    return {child}(q, prm)\n"
        )

    def _tape(self, tape):
        with tape.transformed(np.diag(self._keep), self._shift):
            tape.add(self.child)

    def __repr__(self):
        axes = np.flatnonzero(self.period.axes).tolist()
        every = len(axes) == self.dim
        return f"Periodic({self.child!r})" if every else f"Periodic({self.child!r}, axes={axes})"


def _axes_mask(axes, dim: int) -> np.ndarray:
    """(dim,) bool from ``axes``: None (all), an axis, axis numbers, or one flag per axis."""
    if axes is None:
        return np.ones(dim, dtype=bool)
    values = [axes] if np.ndim(axes) == 0 else list(axes)
    if values and all(isinstance(value, (bool, np.bool_)) for value in values):
        if len(values) != dim:
            raise ShapeError(f"periodic axes given as flags need one per axis ({dim}), got {len(values)}")
        mask = np.array(values, dtype=bool)
    else:
        mask = np.zeros(dim, dtype=bool)
        for value in values:
            if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)) or \
                    not -dim <= value < dim:
                raise ShapeError(f"periodic axes must be axis numbers from 0 to {dim - 1} (or one flag per axis), "
                                 f"got {axes!r}")
            mask[value] = True
    if not mask.any():
        raise ShapeError(f"no periodic axis given ({axes!r}); leave out Periodic for a shape with walls all round")
    return mask
