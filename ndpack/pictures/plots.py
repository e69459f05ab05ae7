"""Pictures of packings with Matplotlib (imported only when a picture is asked for).

A 2-D packing is drawn as its circles; a packing in any higher dimension as a slice: the circles
in which the spheres meet a 2-D plane through ``at``, spanned by two coordinate ``axes``
(:func:`ndpack.pictures.slices.slice_circles`); a 3-D packing's slice stands its up axis
vertical (:func:`ndpack.pictures.view.choose_up`). :func:`save_figure` writes that picture to
``.png``, ``.svg`` or ``.pdf`` in one call; :func:`plot_fill` and :func:`save_fill_figure` draw
the fill against the sphere count. Shaded 3-D pictures are in :mod:`ndpack.pictures.raycast`.
"""

from __future__ import annotations

import numpy as np

from ..errors import DimensionError, NdpackError, ParameterError
from .colours import radius_norm
from .slices import slice_circles
from .view import choose_up, plane_axes


def circle_collection(centers, radii, **options):
    """A Matplotlib collection of circles in data coordinates, one path each.

    Built from one unit circle scaled and shifted in NumPy: ten times faster than a collection of
    ``Circle`` patches (about 1 s for 100,000 circles).

    Parameters
    ----------
    centers : (k, 2) float64
    radii : (k,) float64
    **options
        Passed to ``PathCollection``.
    """
    from matplotlib.collections import PathCollection
    from matplotlib.path import Path

    unit = Path.unit_circle()
    vertices = np.asarray(centers)[:, None, :] + np.asarray(radii)[:, None, None] * unit.vertices[None]
    return PathCollection([Path(ring, unit.codes, readonly=True) for ring in vertices], **options)


def plot(packing, shape=None, ax=None, axes=None, at=None, cmap="viridis", outline=True, rasterized=None,
         up="auto"):
    """Draw a packing (2-D) or a slice of it (any dimension); returns the Matplotlib ``Axes``.

    Circles are coloured by the radius of their sphere (on a log scale when the radii span more
    than 10x); the shape's outline in the plane is drawn where the shape is known: a triangle
    mesh's as its exact section (trimesh), any other shape's as the zero contour of its
    distance. A packing loaded from a file has no shape: pass ``shape=``, or it draws the mesh
    file it records (``params["source"]``, what ``ndpack pack`` writes) where that file is there.

    Parameters
    ----------
    shape : Oracle or trimesh.Trimesh, optional
        Whose outline to draw; default the packing's shape.
    axes : (int, int), optional
        The horizontal and vertical axes of the plane. Default: (0, 1), except in 3-D, where
        the plane through ``at`` holds the up axis (vertical) and the first other of x, y, z.
    at : (d,) array_like, optional
        A point of the plane; default the centres' mean.
    rasterized : bool, optional
        Draw the circles as an image inside vector output (SVG, PDF); default: above
        :data:`RASTERIZE_ABOVE` circles. The outline, axes and text stay vector.
    up : str or Up
        Which axis points up, as in :func:`ndpack.pictures.render`: ``"auto"`` (default: from
        the shape, :func:`ndpack.pictures.view.choose_up`; the second of ``axes`` when they are
        given), ``"x"``, ``"y"``, ``"z"``, or ``"-x"``, ``"-y"``, ``"-z"`` (pointing down).
    """
    try:
        import matplotlib.pyplot as plt
    except ImportError as error:  # pragma: no cover - matplotlib is a dependency
        raise NdpackError(f"plotting needs matplotlib: pip install matplotlib ({error})") from error
    from matplotlib.colors import LogNorm

    if axes is None and packing.dim != 3:
        axes = (0, 1)
    if axes is not None and len(axes) != 2:
        raise DimensionError(f"a plane has two axes (horizontal, vertical), got {tuple(axes)}")
    chosen = choose_up(packing, up, axes)
    axes = plane_axes(chosen, axes)
    shape = packing.shape if shape is None else shape
    if shape is None and outline and packing.dim == 3:
        shape = recorded_mesh(packing)
    centers2, radii2, index = slice_circles(packing.centers, packing.radii, axes, at)
    if ax is None:
        _, ax = plt.subplots(figsize=(6, 6))
    circles = circle_collection(centers2, radii2, cmap=cmap, linewidths=0)
    circles.set_array(packing.radii[index])
    circles.set_norm(radius_norm(packing.radii[index]))
    circles.set_rasterized(len(index) > RASTERIZE_ABOVE if rasterized is None else bool(rasterized))
    ax.add_collection(circles)
    if shape is not None:
        lower, upper = shape.bounds[0][list(axes)], shape.bounds[1][list(axes)]
    elif len(centers2):
        lower, upper = (centers2 - radii2[:, None]).min(axis=0), (centers2 + radii2[:, None]).max(axis=0)
    else:
        lower, upper = np.zeros(2), np.ones(2)
    if outline and shape is not None:
        plane_point = packing.centers.mean(axis=0) if at is None else np.asarray(at, dtype=np.float64)
        draw_outline(ax, shape, axes, plane_point, lower, upper)
    pad = 0.03 * (upper - lower).max()
    ax.set_xlim(lower[0] - pad, upper[0] + pad)
    ax.set_ylim(*(lower[1] - pad, upper[1] + pad)[:: chosen.sign])
    ax.set_aspect("equal")
    ax.set_xlabel(f"x{axes[0]}")
    ax.set_ylabel(f"x{axes[1]}")
    title = f"{len(packing)} spheres, fill {packing.fill:.3f}"
    if packing.dim > 2:
        title += f" (slice: {len(index)} cut)"
    ax.set_title(title)
    _edge_circles(ax, circles, radii2, upper - lower + 2 * pad)
    colorbar = ax.figure.colorbar(circles, ax=ax, label="sphere radius", shrink=0.8)
    if isinstance(circles.norm, LogNorm):
        _plain_log_ticks(colorbar, circles.norm)
    return ax


def _edge_circles(ax, circles, radii, span):
    """Thin white rims that keep touching circles apart, thinner on small circles (a rim as wide
    as a small circle would paint it white)."""
    box = ax.get_position()  # figure fraction, before the colour bar takes its share
    width, height = ax.figure.get_size_inches()
    points_per_unit = 72.0 * min(box.width * width / span[0], box.height * height / span[1])
    circles.set_edgecolor("white")
    circles.set_linewidths(np.clip(0.12 * radii * points_per_unit, 0.0, 0.6))


def _plain_log_ticks(colorbar, norm):
    """Tick labels 0.01, 0.02, 0.05 instead of powers of ten; minor labels only across few decades."""
    from matplotlib.ticker import FuncFormatter

    decades = np.log10(norm.vmax / norm.vmin)

    def minor(value, _position):
        mantissa = value / 10 ** np.floor(np.log10(value) + 1e-9)
        wanted = (2, 5) if decades > 1 else (2, 3, 5)
        return f"{value:g}" if decades <= 2 and any(abs(mantissa - m) < 1e-6 for m in wanted) else ""

    colorbar.ax.yaxis.set_major_formatter(FuncFormatter(lambda value, _position: f"{value:g}"))
    colorbar.ax.yaxis.set_minor_formatter(FuncFormatter(minor))


#: Above this many circles, vector output holds them as one embedded image (an SVG of 100,000
#: circle paths is tens of megabytes and slow to open).
RASTERIZE_ABOVE = 5000
#: File types Matplotlib writes for :func:`save_figure` and :func:`save_fill_figure`.
FIGURE_SUFFIXES = (".png", ".svg", ".pdf")


def save_figure(packing, path, shape=None, axes=None, at=None, dpi=200, figsize=(6, 6), cmap="viridis",
                outline=True, rasterized=None, up="auto"):
    """Draw a 2-D packing, or a 2-D slice of any packing, to a ``.png``, ``.svg`` or ``.pdf`` file.

    See :func:`plot` for the picture; ``dpi`` sets the PNG's resolution and that of the circles
    when they are rasterized inside an SVG or PDF. Returns the path.
    """
    path = _figure_path(path)
    figure = _figure(figsize)
    plot(packing, shape=shape, ax=figure.add_subplot(), axes=axes, at=at, cmap=cmap, outline=outline,
         rasterized=rasterized, up=up)
    figure.savefig(path, dpi=dpi, bbox_inches="tight")
    return path


def plot_fill(packings, ax=None, log=True, uncovered=False, labels=None):
    """Fill fraction (or the uncovered fraction ``1 - fill``) against sphere count, one line a packing.

    One point a round, from :attr:`Packing.stats`.

    Parameters
    ----------
    packings : Packing or sequence of Packing
    ax : Axes, optional
    log : bool
        Logarithmic count axis (and, for ``uncovered``, a logarithmic fraction axis: the
        uncovered fraction of a greedy packing falls about as a power of the count).
    uncovered : bool
        Plot ``1 - fill`` instead of ``fill``.
    labels : sequence of str, optional
        Legend entries; default the dimension, mode and backend of each run (a legend only
        for more than one packing).

    Returns
    -------
    Axes
    """
    import matplotlib.pyplot as plt

    packings = [packings] if hasattr(packings, "stats") else list(packings)
    if labels is not None and len(labels) != len(packings):
        raise NdpackError(f"got {len(labels)} labels for {len(packings)} packings")
    for number, packing in enumerate(packings):
        if len(packing.stats.count) == 0:
            raise NdpackError(
                f"packing {number} has no per-round statistics (a packing loaded from .csv keeps none; "
                "save to .npz to keep them)"
            )
    if ax is None:
        _, ax = plt.subplots(figsize=(6, 4.5))
    for number, packing in enumerate(packings):
        count = np.asarray(packing.stats.count)
        fill = np.asarray(packing.stats.fill)
        label = labels[number] if labels is not None else _run_label(packing)
        values = 1.0 - fill if uncovered else fill
        ax.plot(count, values, marker="o" if len(count) <= 40 else None, markersize=3, linewidth=1.2, label=label)
    if log:
        ax.set_xscale("log")
        if uncovered:
            ax.set_yscale("log")
    ax.set_xlabel("spheres")
    ax.set_ylabel("uncovered fraction (1 - fill)" if uncovered else "fill fraction")
    ax.grid(True, which="major", alpha=0.35)
    if log:
        ax.grid(True, which="minor", alpha=0.12)
    if len(packings) > 1:
        ax.legend(fontsize="small")
    return ax


def save_fill_figure(packings, path, log=True, labels=None, dpi=150, figsize=(11, 4.5)):
    """Fill and uncovered fraction against sphere count side by side (:func:`plot_fill`), to a file.

    Returns the path.
    """
    path = _figure_path(path)
    figure = _figure(figsize)
    fill_axes, uncovered_axes = figure.subplots(1, 2)
    plot_fill(packings, ax=fill_axes, log=log, labels=labels)
    plot_fill(packings, ax=uncovered_axes, log=log, uncovered=True, labels=labels)
    figure.tight_layout()
    figure.savefig(path, dpi=dpi)
    return path


def _run_label(packing):
    params = packing.params or {}
    parts = [f"{packing.dim}-D"] + [str(params[key]) for key in ("mode", "backend") if params.get(key)]
    return ", ".join(parts)


def _figure(figsize):
    """A figure outside pyplot's registry (no window, nothing left open), with an Agg canvas."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    figure = Figure(figsize=figsize)
    FigureCanvasAgg(figure)
    return figure


def _figure_path(path):
    from pathlib import Path

    path = Path(path)
    if path.suffix.lower() not in FIGURE_SUFFIXES:
        raise ParameterError(
            f"cannot write a figure to {path.name!r}: the file name must end in {', '.join(FIGURE_SUFFIXES)}"
        )
    return path


def draw_outline(ax, shape, axes, at, lower, upper, resolution=400):
    """Draw the shape's outline on a plane: a triangle mesh's section (:func:`draw_section`),
    else the zero contour of its distance, sampled on a grid.

    Parameters
    ----------
    ax : Axes
    shape : Oracle
    axes : (int, int)
        The plane's horizontal and vertical axes.
    at : (d,) float64
        A point of the plane.
    lower, upper : (2,) float64
        The corners of the region drawn, in the plane's coordinates.
    resolution : int
        Samples along each side.
    """
    surface = _surface(shape)
    if surface is not None and len(at) == 3:
        return draw_section(ax, *surface, axes, at)
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


def draw_section(ax, vertices, faces, axes, at):
    """Draw where a triangle mesh meets the plane through ``at`` spanned by ``axes``: its section,
    exact, as trimesh cuts it (``Trimesh.section``).

    Parameters
    ----------
    ax : Axes
    vertices : (n, 3) float64
    faces : (m, 3) int64
    axes : (int, int)
        The plane's horizontal and vertical axes.
    at : (3,) float64
        A point of the plane.

    Returns
    -------
    LineCollection or None
        The section's polylines in the plane's coordinates (labelled ``"outline"``); None where
        the plane misses the mesh.
    """
    import trimesh
    from matplotlib.collections import LineCollection

    normal = np.zeros(3)
    normal[3 - axes[0] - axes[1]] = 1.0
    section = trimesh.Trimesh(vertices, faces, process=False).section(plane_origin=np.asarray(at, dtype=np.float64),
                                                                       plane_normal=normal)
    if section is None:
        return None
    # Each entity, not each closed path (``discrete``): the section of an open mesh (a scan with
    # holes) is open where the plane crosses a hole.
    polylines = [entity.discrete(section.vertices)[:, list(axes)] for entity in section.entities]
    lines = LineCollection(polylines, colors="black", linewidths=1.0, label="outline")
    ax.add_collection(lines)
    return lines


def recorded_mesh(packing):
    """The mesh file a packing records as its source (``params["source"]``), read by trimesh as a
    surface to draw; None where it records none, or the file is not there or not a mesh."""
    from pathlib import Path

    from .view import mesh_file

    found = mesh_file(packing)
    if found is None or not Path(found).expanduser().is_file():
        return None
    import trimesh

    try:
        mesh = trimesh.load(Path(found).expanduser(), force="mesh")
    except Exception:  # noqa: BLE001 - an outline is a nicety: a file trimesh cannot read draws none
        return None
    return mesh if isinstance(mesh, trimesh.Trimesh) and len(mesh.faces) else None


def _surface(shape):
    """(vertices, faces) of a triangle mesh shape (an ndpack ``TriangleMesh``, its holes capped, or a
    ``trimesh.Trimesh``); None for any other shape."""
    vertices, faces = getattr(shape, "vertices", None), getattr(shape, "faces", None)
    if vertices is None or faces is None:
        return None
    vertices, faces = np.asarray(vertices), np.asarray(faces)
    if vertices.ndim != 2 or vertices.shape[1] != 3 or faces.ndim != 2 or faces.shape[1] != 3:
        return None
    return vertices, faces
