"""Shaded pictures of 3-D packings without a display: a ray-caster in Numba.

:func:`render` ray-casts the spheres with Numba on every core: an orthographic camera looks at
the packing from ``view`` (azimuth and elevation in degrees, about the axis that stands up:
:func:`ndpack.pictures.view.choose_up`); the spheres are binned into square tiles of the screen
by their projected discs, nearest first, so that a pixel tests only its tile's spheres and stops
at the first one whose front lies behind the nearest hit so far: hidden spheres cost little.
Each pixel averages ``supersample**2`` rays (anti-aliasing) shaded with ambient + Lambert + a
little Blinn-Phong specular light from the upper left, coloured by radius.

A 2-D packing is drawn as circles (:func:`ndpack.pictures.plot`); a packing in more than three
dimensions as the 3-D slice through ``at`` along three ``axes``
(:func:`ndpack.pictures.slices.slice_balls`). Numba and Matplotlib are imported only when a
picture is made.
"""

from __future__ import annotations

import functools
import math
from pathlib import Path

import numpy as np

from ..errors import DimensionError, ParameterError
from .colours import radius_colours, rgb
from .slices import slice_balls
from .plots import plot
from .view import choose_up, screen_frame

#: File types a shaded render is written to.
RENDER_SUFFIXES = (".png",)

#: Tile side in output pixels: small enough that a tile's list is short, large enough that few
#: spheres fall into many tiles.
TILE = 16
#: Empty space on each side of the framed spheres, as a fraction of their extent.
FRAME_MARGIN = 0.04
#: Light direction in camera coordinates (x right, y up, z towards the viewer): upper left, front.
LIGHT = (-0.45, 0.6, 0.66)
AMBIENT = 0.38
DIFFUSE = 0.72
SPECULAR = 0.22
SHININESS = 40.0
#: How much darker the farthest visible point is than the nearest (depth cue for deep gaps).
DEPTH_CUE = 0.25
#: Silhouette width in output pixels, and the disc radius (pixels) under which spheres get none:
#: a dark ring would swallow a sphere a few pixels wide.
OUTLINE_WIDTH = 0.9
OUTLINE_MIN_RADIUS = 2.0
#: Screen-space ambient occlusion: its strength, reach (a fraction of the picture's smaller
#: side) and samples a pixel. It darkens gaps, bores and pockets that direct light leaves flat.
OCCLUSION = 0.6
OCCLUSION_RADIUS = 0.025
OCCLUSION_SAMPLES = 24

prange = range  # replaced by numba.prange when the kernels are compiled (numba is imported late)


# ---------------------------------------------------------------------------------------------- 3-D
def render(packing, path=None, size=(900, 900), view=(35.0, 25.0), cmap="viridis", background="white",
           clip=None, axes=None, at=None, supersample=3, outline=True, occlusion=True, up="auto"):
    """A shaded picture of the packing as an image; also written to ``path`` (PNG) when given.

    Parameters
    ----------
    packing : Packing
        Any dimension >= 2: 2-D packings are drawn as circles, packings in more than three
        dimensions as the 3-D slice through ``at`` along ``axes``.
    path : str or Path
        Where to write the PNG (its text records the up axis and the view).
    size : (int, int)
        Width and height in pixels.
    view : (float, float)
        Azimuth (degrees about the up axis, from the axis after it: x after z, z after y, y
        after x) and elevation (degrees above the plane across the up axis) of the direction
        the camera looks from.
    cmap : str or Colormap
        Colours by sphere radius (log scale when the radii span more than 10x).
    background : colour
        Anything Matplotlib reads as a colour.
    clip : (point, normal), optional
        A half-space cut, both ``(d,)`` in the packing's coordinates: spheres whose centre lies
        beyond the plane (on the side ``normal`` points to) are left out, to look inside.
    axes : (int, int, int), optional
        The three axes of the slice in more than three dimensions (default 0, 1, 2), and their
        order. Given (and ``up="auto"``), the third points up: ``axes=(2, 0, 1)`` stands y up (a
        cyclic order; any other order mirrors the picture).
    at : (d,) array_like, optional
        A point of the 3-D slice; default the centres' mean. Unused in 2-D and 3-D.
    supersample : int
        Rays per pixel along each side (anti-aliasing); 1 is fastest.
    outline : bool
        A thin dark silhouette around spheres more than a few pixels wide.
    occlusion : bool
        Darken where nearer spheres surround a point (screen-space ambient occlusion): gaps,
        bores and pockets read as such.
    up : str or Up
        The axis that points up on screen: ``"x"``, ``"y"``, ``"z"``, or ``"-x"``, ``"-y"``,
        ``"-z"`` (pointing down). ``"auto"`` (default): from the shape, by
        :func:`ndpack.pictures.view.choose_up`: the packing stands on its broadest base that
        holds its centre of mass (a flat face, its feet), else the mesh file's convention (OBJ
        and glTF y-up, STL z-up), else the longest extent when it is clearly longest, else z.

    Returns
    -------
    image : (height, width, 3) uint8
    """
    width, height = _check_size(size)
    if path is not None:
        _check_suffix(path, RENDER_SUFFIXES, "a shaded render")
    dim = packing.dim
    if dim < 2:
        raise DimensionError(f"cannot draw a {dim}-D packing: pictures need 2 or more dimensions")
    described = ""
    if dim == 2:
        if up != "auto":
            choose_up(packing, up)  # a bad value is still explained
            raise ParameterError(f"up={up!r} applies to pictures of 3-D packings; a 2-D one is drawn as it is")
        image = _circles_image(packing, width, height, cmap=cmap, background=background)
    else:
        picked = None if axes is None else _check_axes(axes, dim)
        chosen = choose_up(packing, up, picked)
        axes = (0, 1, 2) if picked is None else picked
        frame = screen_frame(axes.index(chosen.axis), chosen.sign)
        centers, radii, colour_radii = _visible_balls(packing, axes, at, clip)
        frame_centers, frame_radii = _frame_balls(packing, axes, at)
        image = cast_spheres(centers @ frame.T, radii, radius_colours(colour_radii, cmap), size=(width, height),
                             view=view, background=background, supersample=supersample, outline=outline,
                             occlusion=occlusion, frame=(frame_centers @ frame.T, frame_radii))
        described = f"ndpack render: up {chosen}; view {tuple(float(v) for v in view)}; axes {axes}"
    if path is not None:
        import matplotlib.image

        matplotlib.image.imsave(Path(path), image, metadata={"Description": described} if described else None)
    return image


def cast_spheres(centers, radii, colours, size=(900, 900), view=(35.0, 25.0), background="white",
                 supersample=3, outline=True, occlusion=True, frame=None):
    """Ray-cast 3-D spheres with an orthographic camera; the work behind :func:`render`.

    Parameters
    ----------
    centers : (n, 3) float64
    radii : (n,) float64
    colours : (n, 3) float64
        RGB in [0, 1] of each sphere.
    size, view, background, supersample, outline, occlusion
        As in :func:`render`.
    frame : ((m, 3) float64, (m,) float64), optional
        Centres and radii of the spheres whose projection the picture frames; default the
        spheres drawn (a clipped picture passes the whole packing so that the view stays put).

    Returns
    -------
    image : (height, width, 3) uint8
    """
    width, height = _check_size(size)
    centers = np.ascontiguousarray(centers, dtype=np.float64).reshape(-1, 3)
    radii = np.ascontiguousarray(radii, dtype=np.float64).reshape(-1)
    colours = np.ascontiguousarray(colours, dtype=np.float64).reshape(-1, 3)
    supersample = int(supersample)
    if supersample < 1:
        raise ParameterError(f"supersample must be a positive integer, got {supersample}")
    background = np.asarray(rgb(background), dtype=np.float64)
    right, up, towards = camera_axes(*view)
    frame_centers, frame_radii = (centers, radii) if frame is None else frame
    frame_centers = np.asarray(frame_centers, dtype=np.float64).reshape(-1, 3)
    frame_radii = np.asarray(frame_radii, dtype=np.float64).reshape(-1)
    if len(frame_centers) == 0:
        image = np.empty((height, width, 3), dtype=np.uint8)
        image[:] = np.round(background * 255).astype(np.uint8)
        return image
    # Frame the projected discs with a margin; keep the aspect ratio (square pixels).
    frame_u, frame_v = frame_centers @ right, frame_centers @ up
    u_low, u_high = (frame_u - frame_radii).min(), (frame_u + frame_radii).max()
    v_low, v_high = (frame_v - frame_radii).min(), (frame_v + frame_radii).max()
    span_u, span_v = max(u_high - u_low, 1e-300), max(v_high - v_low, 1e-300)
    scale = min(width / span_u, height / span_v) / (1.0 + 2.0 * FRAME_MARGIN)  # pixels per unit length
    u_mid, v_mid = 0.5 * (u_low + u_high), 0.5 * (v_low + v_high)
    # Pixel coordinates: x to the right, y down; depth grows towards the viewer, in pixels too.
    pixel_x = width / 2 + (centers @ right - u_mid) * scale
    pixel_y = height / 2 - (centers @ up - v_mid) * scale
    pixel_r = radii * scale
    depth = centers @ towards * scale
    # Nearest front first: a tile's list is then sorted, and a pixel stops early. The lists hold
    # about n + (covered area / tile area) entries: the framed spheres do not overlap in space, so
    # only few can be large on screen.
    order = np.argsort(-(depth + pixel_r), kind="stable")
    pixel_x, pixel_y, pixel_r = pixel_x[order], pixel_y[order], pixel_r[order]
    depth, colours = depth[order], colours[order]
    tiles_x, tiles_y = -(-width // TILE), -(-height // TILE)
    bin_spheres, cast, occlude = _kernels()
    starts, entries = bin_spheres(pixel_x, pixel_y, pixel_r, TILE, tiles_x, tiles_y)
    light = np.asarray(LIGHT) / np.linalg.norm(LIGHT)
    halfway = light + np.array([0.0, 0.0, 1.0])
    halfway /= np.linalg.norm(halfway)
    shading = np.array([AMBIENT, DIFFUSE, SPECULAR, SHININESS, OUTLINE_WIDTH if outline else 0.0,
                        OUTLINE_MIN_RADIUS])
    colour = np.empty((height, width, 3), dtype=np.float64)
    front = np.empty((height, width), dtype=np.float64)
    cast(starts, entries, pixel_x, pixel_y, pixel_r, depth, colours, background, light, halfway, shading,
         TILE, tiles_x, tiles_y, supersample, _coprime_stride(tiles_x * tiles_y), colour, front)
    image = np.empty((height, width, 3), dtype=np.uint8)
    radius = OCCLUSION_RADIUS * min(width, height)
    hit = front > -1e299
    near, far = (front[hit].max(), front[hit].min()) if hit.any() else (1.0, 0.0)
    occlude(colour, front, _spiral(OCCLUSION_SAMPLES, radius), radius, OCCLUSION if occlusion else 0.0,
            near, max(near - far, 1e-300), DEPTH_CUE, image)
    return image


def camera_axes(azimuth, elevation):
    """The camera's right, up and towards-the-viewer unit vectors for a view (degrees).

    Returns
    -------
    right, up, towards : (3,) float64
        ``towards`` points from the scene to the camera; ``right x up = towards``.
    """
    a, e = math.radians(azimuth), math.radians(elevation)
    towards = np.array([math.cos(e) * math.cos(a), math.cos(e) * math.sin(a), math.sin(e)])
    right = np.array([-math.sin(a), math.cos(a), 0.0])
    up = np.cross(towards, right)
    return right, up, towards


def _visible_balls(packing, axes, at, clip):
    """The 3-D balls drawn: the slice along ``axes`` through ``at``, less those clipped away.

    Returns
    -------
    centers : (k, 3) float64
    radii : (k,) float64
        Radii of the cut balls (the spheres' own in 3-D).
    sphere_radii : (k,) float64
        Radii of the spheres they come from, for the colours.
    """
    centers, radii, index = slice_balls(packing.centers, packing.radii, axes, at)
    if clip is not None:
        point, normal = _check_clip(clip, packing.dim)
        keep = (packing.centers[index] - point) @ normal <= 0.0
        centers, radii, index = centers[keep], radii[keep], index[keep]
    return centers, radii, packing.radii[index]


def _frame_balls(packing, axes, at):
    """The balls the picture frames: the whole slice, clipped or not."""
    centers, radii, _ = slice_balls(packing.centers, packing.radii, axes, at)
    return centers, radii


def _check_axes(axes, dim):
    axes = tuple(int(axis) for axis in axes)
    if len(axes) != 3 or len(set(axes)) != 3 or not all(0 <= axis < dim for axis in axes):
        raise DimensionError(f"axes must be three different axes of a {dim}-D packing, got {axes}")
    return axes


def _check_clip(clip, dim):
    try:
        point, normal = clip
        point = np.asarray(point, dtype=np.float64).reshape(-1)
        normal = np.asarray(normal, dtype=np.float64).reshape(-1)
    except (TypeError, ValueError):
        raise ParameterError(f"clip must be (point, normal), two {dim}-vectors; got {clip!r}") from None
    if point.shape != (dim,) or normal.shape != (dim,) or not np.any(normal):
        raise ParameterError(f"clip must be (point, normal), two {dim}-vectors with a nonzero normal; got {clip!r}")
    return point, normal


def _check_size(size):
    try:
        width, height = (int(value) for value in size)
    except (TypeError, ValueError):
        raise ParameterError(f"size must be (width, height) in pixels, got {size!r}") from None
    if width < 1 or height < 1:
        raise ParameterError(f"size must be (width, height) in pixels, both positive; got {size!r}")
    return width, height


def _coprime_stride(count):
    """A step coprime to ``count``: tile ``(job * step) % count`` visits every tile once, and
    scatters neighbouring (similarly busy) tiles over the threads' contiguous chunks of jobs."""
    stride = int(count * 0.618) | 1
    while math.gcd(stride, count) != 1:
        stride += 2
    return stride


def _circles_image(packing, width, height, cmap, background, dpi=100):
    """A 2-D packing drawn by :func:`ndpack.pictures.plot`, as a (height, width, 3) uint8 image."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    figure = Figure(figsize=(width / dpi, height / dpi), dpi=dpi, facecolor=rgb(background))
    canvas = FigureCanvasAgg(figure)
    plot(packing, ax=figure.add_subplot(), cmap=cmap)
    figure.tight_layout()
    canvas.draw()
    return np.asarray(canvas.buffer_rgba())[:, :, :3].copy()


# ---------------------------------------------------------------------------------------------- kernels
@functools.cache
def _kernels():
    """The binning and ray-casting kernels, compiled by Numba (cached on disk after the first run)."""
    import numba

    global prange, _tile_span
    prange = numba.prange
    if not isinstance(_tile_span, numba.core.dispatcher.Dispatcher):  # called from the binning kernel
        _tile_span = numba.njit(cache=True)(_tile_span)
    bin_spheres = numba.njit(cache=True)(_bin_spheres)
    cast = numba.njit(parallel=True, cache=True, fastmath=True)(_cast)
    occlude = numba.njit(parallel=True, cache=True, fastmath=True)(_occlude)
    return bin_spheres, cast, occlude


def _tile_span(x, y, r, tile, tiles_x, tiles_y):
    """The first and last tile column and row that a circle of centre ``(x, y)`` and radius ``r``
    (pixels) touches, clipped to the screen."""
    x0 = max(int(math.floor((x - r) / tile)), 0)
    x1 = min(int(math.floor((x + r) / tile)), tiles_x - 1)
    y0 = max(int(math.floor((y - r) / tile)), 0)
    y1 = min(int(math.floor((y + r) / tile)), tiles_y - 1)
    return x0, x1, y0, y1


def _bin_spheres(pixel_x, pixel_y, pixel_r, tile, tiles_x, tiles_y):
    """Lists of the spheres each tile's pixels can see, in the spheres' order (nearest first).

    Returns
    -------
    starts : (tiles + 1,) int64
        Tile ``t`` holds ``entries[starts[t]:starts[t + 1]]``; tiles are numbered row by row.
    entries : (m,) int32
        Sphere indices.
    """
    n = pixel_x.shape[0]
    starts = np.zeros(tiles_x * tiles_y + 1, dtype=np.int64)
    for k in range(n):
        x0, x1, y0, y1 = _tile_span(pixel_x[k], pixel_y[k], pixel_r[k], tile, tiles_x, tiles_y)
        for ty in range(y0, y1 + 1):
            for tx in range(x0, x1 + 1):
                starts[ty * tiles_x + tx + 1] += 1
    for t in range(tiles_x * tiles_y):
        starts[t + 1] += starts[t]
    cursor = starts[:-1].copy()
    entries = np.empty(starts[-1], dtype=np.int32)
    for k in range(n):
        x0, x1, y0, y1 = _tile_span(pixel_x[k], pixel_y[k], pixel_r[k], tile, tiles_x, tiles_y)
        for ty in range(y0, y1 + 1):
            for tx in range(x0, x1 + 1):
                t = ty * tiles_x + tx
                entries[cursor[t]] = k
                cursor[t] += 1
    return starts, entries


def _cast(starts, entries, pixel_x, pixel_y, pixel_r, depth, colours, background, light, halfway, shading,
          tile, tiles_x, tiles_y, supersample, stride, colour, front):
    """Shade every pixel, one tile per job, all cores.

    Writes ``colour`` ((height, width, 3) float64, RGB in [0, 1], the samples' mean) and
    ``front`` ((height, width) float64, the nearest hit's depth, -1e300 where no ray hit).

    ``shading`` holds ambient, diffuse, specular, shininess, outline width and the smallest
    outlined radius (pixels).
    """
    height, width = front.shape
    ambient, diffuse, specular, shininess = shading[0], shading[1], shading[2], shading[3]
    outline_width, outline_min_radius = shading[4], shading[5]
    tiles = tiles_x * tiles_y
    samples = supersample * supersample
    for job in prange(tiles):
        t = (job * stride) % tiles
        first, last = starts[t], starts[t + 1]
        x_start, y_start = (t % tiles_x) * tile, (t // tiles_x) * tile
        for y in range(y_start, min(y_start + tile, height)):
            for x in range(x_start, min(x_start + tile, width)):
                red = 0.0
                green = 0.0
                blue = 0.0
                nearest = -1e300
                for sample in range(samples):
                    fx = x + (sample % supersample + 0.5) / supersample
                    fy = y + (sample // supersample + 0.5) / supersample
                    best = -1e300  # fastmath assumes no infinities
                    hit = -1
                    hit_dx = 0.0
                    hit_dy = 0.0
                    hit_dz = 0.0
                    for e in range(first, last):
                        k = entries[e]
                        r = pixel_r[k]
                        if depth[k] + r <= best:  # this and every later sphere lie behind the hit
                            break
                        dx = fx - pixel_x[k]
                        dy = fy - pixel_y[k]
                        q = r * r - dx * dx - dy * dy
                        if q > 0.0:
                            dz = math.sqrt(q)
                            if depth[k] + dz > best:
                                best = depth[k] + dz
                                hit = k
                                hit_dx = dx
                                hit_dy = dy
                                hit_dz = dz
                    if hit < 0:
                        red += background[0]
                        green += background[1]
                        blue += background[2]
                        continue
                    nearest = max(nearest, best)
                    r = pixel_r[hit]
                    # Unit normal in camera coordinates (pixel y points down, camera y up).
                    nx, ny, nz = hit_dx / r, -hit_dy / r, hit_dz / r
                    lambert = max(nx * light[0] + ny * light[1] + nz * light[2], 0.0)
                    gloss = max(nx * halfway[0] + ny * halfway[1] + nz * halfway[2], 0.0) ** shininess
                    brightness = ambient + diffuse * lambert
                    if outline_width > 0.0 and r > outline_min_radius:
                        # Darken within outline_width pixels of the rim, fading in over a few pixels of radius.
                        rim = (r - math.sqrt(hit_dx * hit_dx + hit_dy * hit_dy)) / outline_width
                        strength = min((r - outline_min_radius) / 2.0, 1.0) * 0.8
                        brightness *= 1.0 - strength * max(1.0 - rim, 0.0)
                        gloss *= min(rim, 1.0)
                    red += min(colours[hit, 0] * brightness + specular * gloss, 1.0)
                    green += min(colours[hit, 1] * brightness + specular * gloss, 1.0)
                    blue += min(colours[hit, 2] * brightness + specular * gloss, 1.0)
                colour[y, x, 0] = red / samples
                colour[y, x, 1] = green / samples
                colour[y, x, 2] = blue / samples
                front[y, x] = nearest


def _occlude(colour, front, offsets, radius, strength, near, depth_range, depth_cue, image):
    """Darken pixels that nearer neighbours surround (screen-space ambient occlusion) and distant
    ones (depth cue: ``depth_cue`` darker at the farthest visible point); write the uint8 image.

    A neighbour at most ``offsets`` away that rises above the pixel by ``rise`` (pixels of depth)
    occludes it by ``min(rise / radius, 1)``; one rising more than four radii is a separate object
    in front and occludes nothing (no dark halo around foreground spheres).

    Parameters
    ----------
    colour : (height, width, 3) float64
    front : (height, width) float64
    offsets : (m, 2) float64
        Neighbour offsets in pixels.
    image : (height, width, 3) uint8
        Output.
    """
    height, width = front.shape
    count = offsets.shape[0]
    for y in prange(height):
        for x in range(width):
            depth = front[y, x]
            factor = 1.0
            if depth > -1e299:
                factor = 1.0 - depth_cue * (near - depth) / depth_range
            if strength > 0.0 and depth > -1e299:
                occlusion = 0.0
                for s in range(count):
                    xs = x + int(math.floor(offsets[s, 0] + 0.5))
                    ys = y + int(math.floor(offsets[s, 1] + 0.5))
                    if 0 <= xs < width and 0 <= ys < height:
                        rise = front[ys, xs] - depth
                        if rise > 0.0 and rise < 4.0 * radius:
                            occlusion += min(rise / radius, 1.0)
                factor *= 1.0 - strength * occlusion / count
            for c in range(3):
                image[y, x, c] = np.uint8(min(max(colour[y, x, c] * factor, 0.0), 1.0) * 255.0 + 0.5)


def _spiral(count, radius):
    """``count`` offsets filling a disc of ``radius`` pixels evenly (a Vogel spiral).

    Returns
    -------
    (count, 2) float64
    """
    index = np.arange(count) + 0.5
    distance = radius * np.sqrt(index / count)
    angle = index * math.pi * (3.0 - math.sqrt(5.0))
    return np.column_stack([distance * np.cos(angle), distance * np.sin(angle)])


def _check_suffix(path, allowed, what):
    suffix = Path(path).suffix.lower()
    if suffix not in allowed:
        raise ParameterError(
            f"cannot write {what} to {Path(path).name!r}: the file name must end in {', '.join(allowed)}"
        )
    return suffix
