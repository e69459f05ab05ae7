"""Which way is up in a picture of a 3-D packing: chosen from the shape, or asked for.

``up="auto"`` (:func:`choose_up`) stands a 3-D packing on its base, found from its spheres
(:func:`bases`): for each of the six axis directions, the ground is the plane the lowest sphere
touches, and the base is the convex hull of the spheres that reach within :data:`BASE_BAND` of it
(a flat face, four hooves, two feet). A base counts when it holds the centre of mass above it and
covers at least :data:`MIN_BASE` of the footprint (the convex hull of the whole packing seen from
above); the broadest such base wins. A scan stored z-up in an OBJ file (whose convention says y)
stands on its base, not on its side; a bracket lies on its large face, not on its longest axis.
Among bases within :data:`BASE_TIE` of the broadest (a box has six), the mesh file's convention
decides, then the axis with the lowest centre of mass (a plate lies flat; z, y, x where that
ties), its + end up where both ends are bases (a table on its legs). The spheres, not
the shape, decide, so that a packing gets the same up in Python and from its file on the
command line.

Where no base counts (a ball, a column of a few spheres):

1. the file convention, when the packing records a mesh file of such a format as its source
   (``packing.params["source"]``, what ``ndpack pack`` writes, or the name of its
   :class:`~ndpack.TriangleMesh`, which keeps the file's name). glTF/GLB and OBJ (games, film,
   scanning: Stanford's, Keenan Crane's and most OBJ collections) put up along +y; STL and 3MF
   (CAD, 3-D printing) along +z; PLY and OFF have none;
2. otherwise the longest extent of the shape's bounds (of the spheres, for a packing loaded from
   a file) when it is at least :data:`CLEARLY_LONGEST` times the next: a tower, a bottle;
3. otherwise +z.

Given axes (``axes=(2, 0, 1)``) keep their old meaning: the last of them points up. Beyond three
dimensions, up is the third axis of the 3-D slice. The :class:`Up` chosen says why in words.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import ParameterError

#: What ``up`` accepts: a coordinate axis of the packing, ``-`` for pointing down.
UP_CHOICES = ("auto", "x", "y", "z", "-x", "-y", "-z")
AXIS_NAMES = "xyz"
#: The up axis of mesh formats with a convention (suffix -> axis).
FORMAT_UP = {".obj": 1, ".gltf": 1, ".glb": 1, ".stl": 2, ".3mf": 2}
#: Mesh formats without one: the file is recognised, the extent decides.
OTHER_MESH_FORMATS = (".ply", ".off", ".dae")
#: How many times longer than the next the longest extent must be to stand up.
CLEARLY_LONGEST = 2.0
#: Spheres whose lowest point lies within this fraction of the packing's diagonal of the ground
#: touch it. Twice as much takes a cow's flank for a base: its belly curves away slowly.
BASE_BAND = 0.015
#: The least fraction of the footprint a base must cover: four hooves span half a cow's, two feet
#: 30% of the armadillo's; a side of either, under 10%.
MIN_BASE = 0.15
#: Bases at least this fraction of the broadest are as good (six faces of a box, two of a plate).
BASE_TIE = 0.8
#: Centres of mass at most this many times the lowest above the ground are as low (a plate's
#: two faces: the spheres lie a little differently at each).
LOW_TIE = 1.1


@dataclass(frozen=True)
class Up:
    """The axis that points up in a picture, and why it was chosen.

    Attributes
    ----------
    axis : int
        The packing's coordinate axis: 0, 1 or 2 (``x``, ``y``, ``z``).
    sign : int
        +1 when the axis points up, -1 when it points down.
    reason : str
        Why, in words (``"asked for"``, ``"cow.obj: .obj files are y-up by convention"``, ...).
    """

    axis: int
    sign: int
    reason: str

    @property
    def name(self) -> str:
        """``"y"``, ``"-z"``, ...: what ``up=`` takes to get this again."""
        return ("-" if self.sign < 0 else "") + _axis_name(self.axis)

    def __str__(self) -> str:
        return f"{self.name} ({self.reason})"


@dataclass(frozen=True)
class Base:
    """A face a 3-D packing can stand on (:func:`bases`).

    Attributes
    ----------
    axis, sign : int
        The up direction it stands: ``sign`` times coordinate axis ``axis``.
    fraction : float
        Its area over the footprint's: the convex hulls, seen from above, of the spheres that
        touch the ground and of all of them.
    height : float
        The centre of mass above the ground.
    """

    axis: int
    sign: int
    fraction: float
    height: float


def bases(centers, radii) -> list[Base]:
    """The axis directions a 3-D packing stands on a base, by the rule of the module's notes.

    Parameters
    ----------
    centers : (n, 3) float64
    radii : (n,) float64

    Returns
    -------
    list of Base
        Those that hold the centre of mass (the spheres' volume-weighted centre) above the base
        and cover at least :data:`MIN_BASE` of the footprint; empty for fewer than four spheres,
        or spheres in a line.
    """
    from scipy.spatial import ConvexHull, QhullError

    centers = np.asarray(centers, dtype=np.float64)
    radii = np.asarray(radii, dtype=np.float64)
    if centers.ndim != 2 or centers.shape[1] != 3 or len(radii) < 4:
        return []
    weights = radii**3 if np.sum(radii**3) > 0 else np.ones(len(radii))  # points (radius 0) weigh alike
    center_of_mass = weights @ centers / weights.sum()
    band = BASE_BAND * np.linalg.norm((centers + radii[:, None]).max(axis=0) - (centers - radii[:, None]).min(axis=0))
    try:  # the footprints are the shadows of the centres' hull: fewer points to project
        outer = centers[ConvexHull(centers).vertices]
    except (QhullError, ValueError):  # flat or fewer than four distinct centres
        outer = centers
    found = []
    for axis in range(3):
        across = [k for k in range(3) if k != axis]
        footprint = _hull_2d(outer[:, across])
        if footprint is None:
            continue
        for sign in (1, -1):
            bottoms = sign * centers[:, axis] - radii
            ground = bottoms.min()
            base = _hull_2d(centers[bottoms <= ground + band][:, across])
            if base is None or base.volume < MIN_BASE * footprint.volume:
                continue
            point = np.append(center_of_mass[across], 1.0)
            if np.all(base.equations @ point <= 1e-12 * band):  # inside: on no hull edge's outer side
                found.append(Base(axis, sign, base.volume / footprint.volume,
                                  float(sign * center_of_mass[axis] - ground)))
    return found


def parse_up(up) -> tuple[int, int] | None:
    """``(axis, sign)`` of ``"y"``, ``"-z"``, ... or of an :class:`Up`; None for ``"auto"``; a clear
    error otherwise."""
    if isinstance(up, Up):
        return up.axis, up.sign
    text = up.strip().lower() if isinstance(up, str) else None
    if text not in UP_CHOICES:
        raise ParameterError(f"up must be one of {', '.join(UP_CHOICES)} (the axis that points up on screen; "
                             f"'-y': y points down), got {up!r}")
    if text == "auto":
        return None
    return AXIS_NAMES.index(text[-1]), -1 if text.startswith("-") else 1


def choose_up(packing, up="auto", axes=None) -> Up:
    """The axis a picture of ``packing`` stands up (see the module's notes for ``"auto"``).

    Parameters
    ----------
    packing : Packing
    up : str or Up
        ``"auto"``, or ``"x"``, ``"y"``, ``"z"``, ``"-x"``, ``"-y"``, ``"-z"``, or an :class:`Up`
        chosen before (returned as it is, its reason kept).
    axes : sequence of int, optional
        The axes the picture draws, when given: an asked-for up must be one of them, and
        ``"auto"`` takes the last (``axes=(2, 0, 1)`` stands y up, as it always has).

    Returns
    -------
    Up

    Examples
    --------
    >>> import numpy as np, ndpack as nd
    >>> corners = np.array([[x, y, 0.0] for x in (0, 2) for y in (0, 1)])  # four spheres, lying flat
    >>> up = choose_up(nd.Packing(corners, np.full(4, 0.5), np.zeros(4, dtype=np.int64), 1.0))
    >>> up.name, up.reason.split(";")[0]
    ('z', 'it stands on its base: 100% of its footprint, the centre of mass above it')
    """
    parsed = parse_up(up)
    dim = packing.dim
    if axes is None and dim != 3:
        axes = (0, 1, 2)[: min(dim, 3)]
    if axes is not None:
        axes = tuple(int(axis) for axis in axes)
    if parsed is not None:
        axis, sign = parsed
        if axis >= dim or (axes is not None and axis not in axes):
            drawn = "the packing's axes" if axes is None else f"the axes drawn, {axes}"
            name = up.name if isinstance(up, Up) else up
            raise ParameterError(f"up={name!r} is not one of {drawn}: pick another, or other axes")
        return up if isinstance(up, Up) else Up(axis, sign, "asked for")
    if axes is not None:
        if dim > 3 and len(axes) == 3 and axes == (0, 1, 2):
            return Up(2, 1, "the third axis of the 3-D slice")
        return Up(axes[-1], 1, f"the last of the axes {axes}")
    convention = _convention(packing)
    found = bases(packing.centers, packing.radii)
    if found:
        return _stand_on(found, convention)
    if convention is not None:
        axis, why = convention
        return Up(axis, 1, why)
    extents = _extents(packing)
    if extents is not None:
        order = np.argsort(extents)[::-1]
        longest, second = extents[order[0]], extents[order[1]]
        if second > 0 and longest >= CLEARLY_LONGEST * second:
            return Up(int(order[0]), 1, f"the longest extent, {longest / second:.1f}x the next")
    return Up(2, 1, "the default: no mesh-file convention, no clearly longest extent")


def mesh_file(packing) -> str | None:
    """The mesh file the packing was made from, where it says: ``params["source"]`` (written by
    ``ndpack pack``), else the file name its :class:`~ndpack.TriangleMesh` shape keeps."""
    candidates = [(packing.params or {}).get("source"), getattr(packing.shape, "name", None)]
    for candidate in candidates:
        if isinstance(candidate, str):
            suffix = Path(candidate.strip()).suffix.lower()
            if suffix in FORMAT_UP or suffix in OTHER_MESH_FORMATS:
                return candidate.strip()
    return None


def screen_frame(position: int, sign: int) -> np.ndarray:
    """The rotation that stands coordinate ``position`` (0, 1 or 2) of a 3-D picture up.

    Returns
    -------
    (3, 3) float64
        Rows: the new first, second and third axes in the old coordinates; the third (which the
        camera keeps up) is ``sign`` times axis ``position``, the first the axis after it
        (cyclically). A rotation: the picture is not mirrored.
    """
    frame = np.zeros((3, 3))
    frame[0, (position + 1) % 3] = 1.0
    frame[1, (position + 2) % 3] = float(sign)
    frame[2, position] = float(sign)
    return frame


def plane_axes(up: Up, axes=None) -> tuple[int, int]:
    """The (horizontal, vertical) axes of a 2-D slice that shows ``up`` vertical.

    ``axes``: the two given, reordered so that the up axis is the second; default the first of
    x, y, z that is not up, and up (y up: (0, 1); z up: (0, 2); x up: (1, 0)).
    """
    if axes is not None:
        first, second = (int(axis) for axis in axes)
        return (second, first) if first == up.axis else (first, second)
    return next(axis for axis in range(3) if axis != up.axis), up.axis


def _axis_name(axis: int) -> str:
    return AXIS_NAMES[axis] if axis < len(AXIS_NAMES) else f"x{axis}"


def _convention(packing) -> tuple[int, str] | None:
    """The up axis of the recorded mesh file's format, and the reason in words; None without."""
    found = mesh_file(packing)
    suffix = None if found is None else Path(found).suffix.lower()
    if suffix not in FORMAT_UP:
        return None
    axis = FORMAT_UP[suffix]
    return axis, f"{Path(found).name}: {suffix} files are {_axis_name(axis)}-up by convention"


def _stand_on(found: list[Base], convention) -> Up:
    """The base to stand on: the broadest, or among those about as broad the file convention's,
    else the one on the axis with the lowest centre of mass, its + end up where both ends are
    bases (see the module's notes)."""
    broadest = max(base.fraction for base in found)
    close = [base for base in found if base.fraction >= BASE_TIE * broadest]
    convention_up = None if convention is None else (convention[0], 1)
    chosen = next((base for base in close if (base.axis, base.sign) == convention_up), None)
    how = "the file's convention"
    if chosen is None:
        # The axis it lies lowest on (a plate lies flat), then the axis's + end up where both ends
        # are bases: models are made standing the positive way up more often than not.
        lowest = min(base.height for base in close)
        axes = {base.axis for base in close if base.height <= lowest * LOW_TIE}
        axis = max(axes)
        chosen = max((base for base in close if base.axis == axis), key=lambda base: base.sign)
        how = "the lowest centre of mass" + (", then the order z, y, x" if len(axes) > 1 else "")
        if sum(base.axis == axis for base in close) > 1:
            how += f", then +{_axis_name(axis)} rather than -{_axis_name(axis)}"
    reason = f"it stands on its base: {chosen.fraction:.0%} of its footprint, the centre of mass above it"
    if len(close) > 1:
        reason += f"; one of {len(close)} bases as broad, picked by {how}"
    if convention is not None:
        why = convention[1].split(": ", 1)[-1]
        if (chosen.axis, chosen.sign) == convention_up:
            reason += f"; {why}" + ("" if len(close) > 1 else " too")
        else:
            reason += f"; {why}, but that way it has no base as broad"
    return Up(chosen.axis, chosen.sign, reason)


def _hull_2d(points):
    """The convex hull of (k, 2) points, or None where they span no area (fewer than three, in a line)."""
    from scipy.spatial import ConvexHull, QhullError

    if len(points) < 3:
        return None
    try:
        hull = ConvexHull(points)
    except (QhullError, ValueError):
        return None
    return hull if hull.volume > 0 else None


def _extents(packing):
    """(3,) extents of the shape's bounds where finite (a few spheres may not span the shape), else
    of the spheres (a packing loaded from a file has no shape); None where neither is known."""
    bounds = getattr(packing.shape, "bounds", None)
    if bounds is not None and np.all(np.isfinite(bounds)):
        return np.asarray(bounds[1] - bounds[0], dtype=np.float64)[:3]
    if len(packing.radii):
        centers, radii = packing.centers[:, :3], packing.radii[:, None]
        return (centers + radii).max(axis=0) - (centers - radii).min(axis=0)
    return None
