"""Pictures of packings with Matplotlib (imported only when a picture is asked for).

A 2-D packing is drawn as its circles; a packing in any higher dimension as a slice: the circles
in which the spheres meet a 2-D plane through ``at``, spanned by two coordinate ``axes``.
"""

from __future__ import annotations

import numpy as np

from .errors import DimensionError, NdpackError


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
    dim = centers.shape[1]
    i, j = axes
    if not (0 <= i < dim and 0 <= j < dim and i != j):
        raise DimensionError(f"axes must be two different axes of a {dim}-D packing, got {axes}")
    at = centers.mean(axis=0) if at is None else np.asarray(at, dtype=np.float64)
    others = [k for k in range(dim) if k not in (i, j)]
    offset_sq = ((centers[:, others] - at[others]) ** 2).sum(axis=1)
    index = np.flatnonzero(offset_sq < radii**2)
    return centers[index][:, [i, j]], np.sqrt(radii[index] ** 2 - offset_sq[index]), index


def plot(packing, shape=None, ax=None, axes=(0, 1), at=None, cmap="viridis", outline=True):
    """Draw a packing (2-D) or a slice of it (any dimension); returns the Matplotlib ``Axes``.

    Circles are coloured by the radius of their sphere; the shape's outline in the plane is drawn
    from its distance field when the shape is known.
    """
    try:
        import matplotlib.pyplot as plt
        from matplotlib.collections import PatchCollection
        from matplotlib.patches import Circle
    except ImportError as error:  # pragma: no cover - matplotlib is a dependency
        raise NdpackError(f"plotting needs matplotlib: pip install matplotlib ({error})") from error
    shape = packing.shape if shape is None else shape
    centers2, radii2, index = slice_circles(packing.centers, packing.radii, axes, at)
    if ax is None:
        _, ax = plt.subplots(figsize=(6, 6))
    patches = PatchCollection([Circle(c, r) for c, r in zip(centers2, radii2)], cmap=cmap, linewidths=0)
    patches.set_array(packing.radii[index])
    ax.add_collection(patches)
    if shape is not None:
        lower, upper = shape.bounds[0][list(axes)], shape.bounds[1][list(axes)]
    elif len(centers2):
        lower, upper = (centers2 - radii2[:, None]).min(axis=0), (centers2 + radii2[:, None]).max(axis=0)
    else:
        lower, upper = np.zeros(2), np.ones(2)
    if outline and shape is not None:
        plane_point = packing.centers.mean(axis=0) if at is None else np.asarray(at, dtype=np.float64)
        _draw_outline(ax, shape, axes, plane_point, lower, upper)
    pad = 0.03 * (upper - lower).max()
    ax.set_xlim(lower[0] - pad, upper[0] + pad)
    ax.set_ylim(lower[1] - pad, upper[1] + pad)
    ax.set_aspect("equal")
    ax.set_xlabel(f"x{axes[0]}")
    ax.set_ylabel(f"x{axes[1]}")
    title = f"{len(packing)} spheres, fill {packing.fill:.3f}"
    if packing.dim > 2:
        title += f" (slice: {len(index)} cut)"
    ax.set_title(title)
    ax.figure.colorbar(patches, ax=ax, label="radius", shrink=0.8)
    return ax


def _draw_outline(ax, shape, axes, at, lower, upper, resolution=400):
    """The zero contour of the shape's distance on the plane, sampled on a grid."""
    # Sample beyond the bounds: a shape touching its bounding box still gets a closed outline.
    pad = 0.02 * (upper - lower).max()
    u = np.linspace(lower[0] - pad, upper[0] + pad, resolution)
    v = np.linspace(lower[1] - pad, upper[1] + pad, resolution)
    grid_u, grid_v = np.meshgrid(u, v)
    points = np.tile(at, (grid_u.size, 1))
    points[:, axes[0]] = grid_u.ravel()
    points[:, axes[1]] = grid_v.ravel()
    distance = shape.distance(points).reshape(grid_u.shape)
    ax.contour(grid_u, grid_v, distance, levels=[0.0], colors="black", linewidths=1.0)
