"""Pictures of packings, and one entry point for every picture: :func:`picture`.

One concept a module, none importing another that imports it:

- :mod:`ndpack.pictures.slices`: the balls and circles in which spheres meet a flat (geometry).
- :mod:`ndpack.pictures.colours`: colours by radius, shared by every picture.
- :mod:`ndpack.pictures.view`: which axis points up (``up="auto"``: from the shape).
- :mod:`ndpack.pictures.plots`: Matplotlib circles of 2-D packings and slices, fill plots.
- :mod:`ndpack.pictures.raycast`: the shaded 3-D picture, a ray-caster in Numba.

:func:`picture` picks the right picture for a packing and a file name (``.png``, ``.svg``,
``.pdf``). Matplotlib and Numba are imported only when a picture is made.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from ..errors import DimensionError, ParameterError
from ..packing import SERVICES
from .colours import radius_norm
from .plots import circle_collection, plot, plot_fill, save_figure, save_fill_figure
from .raycast import RENDER_SUFFIXES, _check_axes, _check_suffix, camera_axes, cast_spheres, render
from .slices import slice_balls, slice_circles
from .view import UP_CHOICES, Up, choose_up

__all__ = ["picture", "render", "cast_spheres", "camera_axes", "plot", "save_figure", "plot_fill", "save_fill_figure",
           "slice_balls", "slice_circles", "circle_collection", "radius_norm", "choose_up", "Up", "UP_CHOICES",
           "PictureFile"]

SERVICES["plot"] = plot  # Packing.plot: a packing draws itself

#: File types :func:`picture` writes: circles and plots go to all three, shaded renders to PNG.
SUFFIXES = (".png", ".svg", ".pdf")
KINDS = ("auto", "render", "slice", "fill")


def picture(packing, path, kind="auto", **options) -> PictureFile:
    """Write a picture of a packing; the file type follows the suffix.

    Parameters
    ----------
    packing : Packing, or a list of them for ``kind="fill"``
    path : str or Path
        ``.png``, ``.svg`` or ``.pdf``.
    kind : str
        ``"auto"``: circles for a 2-D packing; in 3-D and more, the shaded :func:`render` for a
        ``.png`` (of the 3-D slice beyond three dimensions) and a 2-D slice
        (:func:`save_figure`) for ``.svg`` and ``.pdf``.
        ``"render"``: the shaded render (PNG only). ``"slice"``: the circles of a 2-D packing
        or of a 2-D slice (``axes=``, ``at=``). ``"fill"``: fill and uncovered fraction against
        sphere count (:func:`save_fill_figure`).
    **options
        Passed on: to :func:`render` (``size``, ``view``, ``up``, ``cmap``, ``background``,
        ``clip``, ``axes``, ``at``, ...), :func:`save_figure` (``shape``, ``axes``, ``at``,
        ``up``, ``dpi``, ...) or :func:`save_fill_figure` (``log``, ``labels``, ``dpi``). 3-D
        pictures stand up the axis :func:`choose_up` picks (``up="auto"``) or the one asked for.

    Returns
    -------
    PictureFile
        The file written (``.path``; a :class:`PictureFile` is path-like), the kind drawn, and
        ``.up``: which axis points up, and why.

    Examples
    --------
    >>> shot = picture(packing, "cow.png")  # doctest: +SKIP
    >>> print(shot.up)  # doctest: +SKIP
    y (it stands on its base: 53% of its footprint, the centre of mass above it; .obj files are y-up ...)
    """
    path = Path(path)
    suffix = _check_suffix(path, SUFFIXES, "a picture")
    if kind not in KINDS:
        raise ParameterError(f"unknown picture kind {kind!r}; use one of: {', '.join(KINDS)}")
    if kind == "fill":
        _check_options(save_fill_figure, options, "fill")
        save_fill_figure(packing, path, **options)
        return PictureFile(path, kind)
    dim = packing.dim
    if dim < 2:
        raise DimensionError(f"cannot draw a {dim}-D packing: pictures need 2 or more dimensions")
    if kind == "auto":
        kind = "render" if dim >= 3 and suffix in RENDER_SUFFIXES else "slice"
    if kind == "render" and suffix not in RENDER_SUFFIXES:
        raise ParameterError(
            f"a shaded render is written as {' or '.join(RENDER_SUFFIXES)}, not {suffix}; "
            f"use kind='slice' for a vector picture of a slice"
        )
    draw = render if kind == "render" else save_figure
    _check_options(draw, options, kind)
    up = None
    axes = options.get("axes")
    if dim >= 3 and (kind == "render" or axes is None or len(axes) == 2):  # else the drawing says what is wrong
        if kind == "render":
            axes = None if axes is None else _check_axes(axes, dim)
        elif axes is None and dim > 3:
            axes = (0, 1)
        up = options["up"] = choose_up(packing, options.get("up", "auto"), axes)  # chosen once, drawn so
    draw(packing, path, **options)
    return PictureFile(path, kind, up)


@dataclass(frozen=True)
class PictureFile:
    """What :func:`picture` wrote; path-like (``open(picture(...))``, ``Path(picture(...))``).

    Attributes
    ----------
    path : Path
        The file.
    kind : str
        ``"render"``, ``"slice"`` (circles of a 2-D packing or of a slice) or ``"fill"``.
    up : Up or None
        The axis that points up and why (``print(picture(...).up)``: ``y (it stands on its base:
        ...)``); None for 2-D packings and fill plots.
    """

    path: Path
    kind: str
    up: Up | None = None

    def __fspath__(self) -> str:
        return str(self.path)

    def __str__(self) -> str:
        return str(self.path)


def _check_options(function, options: dict, kind: str) -> None:
    """Refuse options ``function`` does not take with one line naming those it does."""
    import inspect

    accepted = [name for name in inspect.signature(function).parameters if name not in ("packing", "packings", "path")]
    unknown = sorted(set(options) - set(accepted))
    if unknown:
        raise ParameterError(
            f"a {kind} picture has no option {', '.join(unknown)}; its options: {', '.join(accepted)}"
        )
