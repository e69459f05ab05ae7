"""Colours shared by every picture: spheres coloured by radius, on a log scale when the radii
span more than :data:`LOG_SPAN` (Matplotlib is imported only when a colour is asked for)."""

from __future__ import annotations

import numpy as np

from ..errors import ParameterError

#: Radii spanning more than this ratio are coloured on a log scale.
LOG_SPAN = 10.0
#: The part of the colormap a shaded render uses: the darkest end of most maps (viridis' near
#: black) would leave small spheres without visible shading.
COLOUR_RANGE = (0.12, 1.0)


def radius_norm(radii):
    """The Matplotlib norm for colouring by radius: logarithmic when the radii span more than 10x.

    Parameters
    ----------
    radii : (n,) float64
    """
    from matplotlib.colors import LogNorm, Normalize

    if len(radii) == 0:
        return Normalize(0.0, 1.0)
    low, high = float(np.min(radii)), float(np.max(radii))
    if low > 0 and high > LOG_SPAN * low:
        return LogNorm(low, high)
    return Normalize(low, high if high > low else low + 1.0)


def radius_colours(radii, cmap):
    """RGB in [0, 1] of each radius through the colormap (its :data:`COLOUR_RANGE`), log-scaled
    when radii span more than 10x.

    Parameters
    ----------
    radii : (n,) float64
    cmap : str or Colormap

    Returns
    -------
    (n, 3) float64
    """
    import matplotlib

    colormap = matplotlib.colormaps[cmap] if isinstance(cmap, str) else cmap
    position = np.clip(np.ma.filled(radius_norm(radii)(radii), 0.0), 0.0, 1.0)
    low, high = COLOUR_RANGE
    return colormap(low + (high - low) * position)[:, :3].astype(np.float64)


def rgb(colour):
    """A colour Matplotlib reads (a name, ``'#rrggbb'``, a tuple) as ``(r, g, b)`` in [0, 1]."""
    from matplotlib.colors import to_rgb

    try:
        return to_rgb(colour)
    except ValueError:
        raise ParameterError(f"cannot read {colour!r} as a colour: use a name ('white') or '#rrggbb'") from None
