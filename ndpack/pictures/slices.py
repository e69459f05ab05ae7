"""Slices: the balls in which spheres meet a flat spanned by coordinate axes (pure geometry).

A d-ball of radius ``r`` whose centre lies at distance ``h`` from the flat meets it in a ball of
radius ``sqrt(r**2 - h**2)`` about the centre's projection. :func:`slice_balls` cuts a 3-D
slice (what :func:`ndpack.pictures.render` shades beyond three dimensions),
:func:`slice_circles` a plane (what :func:`ndpack.pictures.plot` draws).
"""

from __future__ import annotations

import numpy as np

from ..errors import DimensionError


def slice_balls(centers, radii, axes=(0, 1, 2), at=None):
    """Balls cut from the spheres by the flat through ``at`` spanned by ``axes``.

    A d-ball of radius ``r`` whose centre lies at distance ``h`` from the flat meets it in a ball
    of radius ``sqrt(r**2 - h**2)`` about the centre's projection.

    Parameters
    ----------
    centers : (n, d) float64
    radii : (n,) float64
    axes : sequence of k different ints
        The coordinate axes of the flat.
    at : (d,) array_like, optional
        A point of the flat (its other coordinates fix the slice); default the centres' mean.

    Returns
    -------
    ball_centers : (m, k) float64
    ball_radii : (m,) float64
    index : (m,) int64
        Which sphere each ball comes from.
    """
    centers = np.asarray(centers, dtype=np.float64)
    radii = np.asarray(radii, dtype=np.float64)
    dim = centers.shape[1]
    axes = [int(axis) for axis in axes]
    if len(set(axes)) != len(axes) or not all(0 <= axis < dim for axis in axes):
        raise DimensionError(f"axes must be {len(axes)} different axes of a {dim}-D packing, got {tuple(axes)}")
    others = [k for k in range(dim) if k not in axes]
    if not others:  # the flat is the whole space: every sphere, whole
        return centers[:, axes], radii.copy(), np.arange(len(radii))
    if at is None:
        at = centers.mean(axis=0) if len(centers) else np.zeros(dim)
    at = np.asarray(at, dtype=np.float64).reshape(-1)
    if at.shape != (dim,):
        raise DimensionError(f"at must be a point of the {dim}-D packing, got shape {at.shape}")
    offset_sq = ((centers[:, others] - at[others]) ** 2).sum(axis=1)
    index = np.flatnonzero(offset_sq < radii**2)
    return centers[index][:, axes], np.sqrt(radii[index] ** 2 - offset_sq[index]), index


def slice_circles(centers, radii, axes=(0, 1), at=None):
    """Circles cut from the spheres by the plane through ``at`` spanned by ``axes``.

    Parameters
    ----------
    centers : (n, d) float64
    radii : (n,) float64
    axes : (int, int)
        The two coordinate axes of the plane.
    at : (d,) array_like, optional
        A point of the plane (its other coordinates fix the slice); default the centres' mean.

    Returns
    -------
    circle_centers : (k, 2) float64
    circle_radii : (k,) float64
    index : (k,) int64
        Which sphere each circle comes from.
    """
    if len(axes) != 2:
        raise DimensionError(f"a plane has two axes, got {tuple(axes)}")
    return slice_balls(centers, radii, axes, at)
