"""Which way is up in a picture of a 3-D packing: chosen from the shape, or asked for.

Mesh files follow conventions: glTF/GLB and OBJ (games, film, scanning: Stanford's, Keenan
Crane's and most OBJ collections) put up along +y; STL and 3MF (CAD, 3-D printing) along +z.
PLY and OFF have no convention (the Stanford scans come as y-up PLY, CAD exports as z-up).
``up="auto"`` (:func:`choose_up`) therefore decides, for a 3-D packing:

1. the file convention, when the packing records a mesh file of such a format as its source
   (``packing.params["source"]``, what ``ndpack pack`` writes, or the name of its
   :class:`~ndpack.TriangleMesh`, which keeps the file's name);
2. otherwise the longest extent of the shape's bounds (of the spheres, for a packing loaded from
   a file) when it is at least :data:`CLEARLY_LONGEST` times the next: a standing figure, a
   tower, a bottle;
3. otherwise +z: machined parts, plates and boxes lie on their largest face.

Given axes (``axes=(2, 0, 1)``) keep their old meaning: the last of them points up. Beyond three
dimensions, up is the third axis of the 3-D slice.
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


def parse_up(up) -> tuple[int, int] | None:
    """``(axis, sign)`` of ``"y"``, ``"-z"``, ...; None for ``"auto"``; a clear error otherwise."""
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
    up : str
        ``"auto"``, or ``"x"``, ``"y"``, ``"z"``, ``"-x"``, ``"-y"``, ``"-z"``.
    axes : sequence of int, optional
        The axes the picture draws, when given: an asked-for up must be one of them, and
        ``"auto"`` takes the last (``axes=(2, 0, 1)`` stands y up, as it always has).

    Returns
    -------
    Up
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
            raise ParameterError(f"up={up!r} is not one of {drawn}: pick another, or other axes")
        return Up(axis, sign, "asked for")
    if axes is not None:
        if dim > 3 and len(axes) == 3 and axes == (0, 1, 2):
            return Up(2, 1, "the third axis of the 3-D slice")
        return Up(axes[-1], 1, f"the last of the axes {axes}")
    found = mesh_file(packing)
    if found is not None:
        suffix = Path(found).suffix.lower()
        if suffix in FORMAT_UP:
            axis = FORMAT_UP[suffix]
            return Up(axis, 1, f"{Path(found).name}: {suffix} files are {_axis_name(axis)}-up by convention")
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
