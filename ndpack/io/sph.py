"""Sphere trees (``sph``, ``.sph``, 3-D): Bradshaw & O'Sullivan's sphere-tree toolkit's text format.

A packing is written as a tree of two levels: a root that encloses every sphere
(:func:`ndpack.geometry.ball_union.enclosing_sphere`), then the spheres. :func:`read_sph` reads any level
of any such file, the toolkit's own among them; :func:`~ndpack.io.load` reads the deepest.
(:meth:`ndpack.drivers.collision.sphere_tree.SphereTree.save` writes deeper trees in the same format.)
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..geometry.ball_union import enclosing_sphere
from ..errors import NdpackError
from ..packing import Packing
from .metadata import packing_from
from .registry import FORMATS, Format, existing, reading, register, require_dim


def _write_sph(packing: Packing, path: Path) -> None:
    """Bradshaw & O'Sullivan's sphere-tree text format, as their toolkit's ``SphereTree`` reads it.

    Layout (whitespace-separated text; the toolkit reads it with ``%f``)::

        2 n                          levels and branching factor (degree)
        cx cy cz R 1                 level 0: the root, a bounding sphere of every sphere
        x y z r 1                    level 1: the n spheres, in insertion order
        ...

    The nodes are listed level by level (the toolkit's breadth-first array: node ``i``'s
    children are ``i * degree + 1 ...``). Each line is ``x y z r occupancy``: the toolkit
    writes its nodes' occupancy as the fifth column, 1 for a node it has not refined, and reads
    only the first four. An empty packing is ``2 1`` with two unused slots of radius 0 (the
    toolkit marks unused slots by a radius <= 0). The root is
    :func:`~ndpack.geometry.ball_union.enclosing_sphere` of the spheres: it encloses every sphere, within
    about 1% of the smallest that does. Numbers are written with 17 significant digits, so a
    read-back is exact.
    """
    require_dim(packing.dim, range(3, 4), "the sphere-tree format (.sph)")
    if len(packing):
        center, radius = enclosing_sphere(packing.centers, packing.radii)
        rows = np.vstack([np.append(center, radius), np.column_stack([packing.centers, packing.radii])])
        degree = len(packing)
    else:
        rows, degree = np.zeros((2, 4)), 1
    table = np.column_stack([rows, np.ones(len(rows))])
    np.savetxt(path, table, fmt=["%.17g"] * 4 + ["%d"], header=f"2 {degree}", comments="")


def read_sph(path, level: int = -1) -> tuple[np.ndarray, np.ndarray]:
    """The spheres of one level of a ``.sph`` sphere tree (default: the deepest, the leaves).

    Reads the toolkit's files too: any number of levels, the optional auxiliary-sphere columns,
    and its trailing parameter text (after the last node). Slots with a radius <= 0 are unused
    and dropped.

    Returns
    -------
    centers : (k, 3) float64
    radii : (k,) float64
    """
    path = existing(path)
    return reading(FORMATS["sph"], path, lambda path: _read_sph_level(path, level))


def _read_sph_level(path: Path, level: int) -> tuple[np.ndarray, np.ndarray]:
    lines = [line.split() for line in path.read_text().splitlines()]
    lines = [words for words in lines if words]
    if not lines or len(lines[0]) != 2:
        raise ValueError("its first line is not 'levels branching'")
    levels, degree = int(lines[0][0]), int(lines[0][1])
    if levels < 1 or degree < 1:
        raise ValueError(f"its header '{levels} {degree}' has no spheres")
    # Level i holds degree**i nodes: summed only while the file's lines can hold them, so that a
    # header of a billion levels or branches is refused at once, not computed.
    nodes, sizes, total = len(lines) - 1, [1], 1
    while total <= nodes and len(sizes) < levels:
        sizes.append(sizes[-1] * degree)
        total += sizes[-1]
    if total > nodes:
        most = "" if len(sizes) == levels else "at least "
        raise ValueError(f"a {levels}-level tree of branching {degree} has {most}{total:,} nodes; found {nodes:,}")
    if not -levels <= level < levels:
        raise NdpackError(f"{path} has {levels} levels; there is no level {level}")
    level = level % levels
    start = 1 + sum(sizes[:level])
    rows = np.array([[float(word) for word in words[:4]] for words in lines[start : start + sizes[level]]])
    rows = rows[rows[:, 3] > 0]
    return rows[:, :3].reshape(-1, 3), rows[:, 3]


def _read_sph(path: Path) -> Packing:
    centers, radii = _read_sph_level(path, -1)
    return packing_from(None, centers, radii)


register(Format("sph", (".sph",), "3", "spheres, as a 2-level sphere tree", {}, _write_sph, _read_sph),
         default_for=(".sph",))
