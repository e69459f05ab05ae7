"""The medial-axis sample (``medial``, ``.csv`` any dimension, ``.ply`` up to 3-D): the points
and clearances ProtoSphere finds before the first sphere (``packing.medial_axis`` and
``packing.medial_radii``).

Chosen by name only (``save(..., format="medial")``), and read with :func:`load_medial`, not
:func:`~ndpack.io.load`. ``.csv``: a first line ``# {"format": "ndpack-medial", ...}``, then
``x0,...,radius``, then a point a line. ``.ply``: one vertex element ``double x, y, z, radius``
(:mod:`ndpack.io.ply`'s points; option ``encoding``).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from ..errors import DimensionError, NdpackError
from ..packing import Packing
from .metadata import MEDIAL_VERSION, check_metadata, xyz
from . import limits
from .limits import parse_json, shown
from .ply import dimension_comment, points_dim, read_points, write_points
from .registry import Format, binary_encoding, existing, reading, register, resolve


def load_medial(path) -> tuple[np.ndarray, np.ndarray]:
    """Read a medial-axis sample written with ``save(..., format="medial")``.

    Returns
    -------
    points : (m, d) float64
    radii : (m,) float64
        The clearance at each point (the radius of the maximal ball there).
    """
    path = existing(path)
    fmt = resolve(path, "medial", "load")
    return reading(fmt, path, _read_medial)


def _medial_metadata(dim: int) -> dict:
    return {"format": "ndpack-medial", "version": MEDIAL_VERSION, "dim": dim}


def _write_medial(packing: Packing, path: Path, encoding: str | None = None) -> None:
    if packing.medial_axis is None or packing.medial_radii is None:
        raise NdpackError("this packing has no medial-axis sample (medial_axis is None)")
    points, radii = packing.medial_axis, packing.medial_radii
    dim = points.shape[1]
    if path.suffix.lower() == ".csv":
        header = ",".join([*(f"x{i}" for i in range(dim)), "radius"])
        comment = "# " + json.dumps(_medial_metadata(dim))
        table = np.column_stack([points, radii])
        np.savetxt(path, table, delimiter=",", fmt="%.17g", header=f"{comment}\n{header}", comments="")
        return
    if dim > 3:
        raise DimensionError(f"PLY holds points in up to 3-D, not a {dim}-D medial axis: write it to a .csv file")
    points3 = xyz(points)
    columns = [("x", "double", points3[:, 0]), ("y", "double", points3[:, 1]), ("z", "double", points3[:, 2]),
               ("radius", "double", radii)]
    comments = ["ndpack medial-axis sample: points and their clearance", *dimension_comment(dim)]
    comments.append("ndpack-metadata " + json.dumps(_medial_metadata(dim)))
    write_points(path, comments, columns, binary_encoding(encoding))


def _read_medial(path: Path) -> tuple[np.ndarray, np.ndarray]:
    if path.suffix.lower() == ".ply":
        meta, table = read_points(path)
        if meta is not None:
            check_metadata(meta, path, "ndpack-medial")
        dim = points_dim(meta)
        points = np.column_stack([table["x"], table["y"], table["z"]])[:, :dim]
        return points.astype(np.float64), table["radius"].astype(np.float64)
    with open(path) as file:
        first = file.readline()
        header = file.readline() if first.startswith("#") else first
    if first.startswith("#"):
        check_metadata(parse_json(first[1:]), path, "ndpack-medial")
    columns = header.strip().split(",")
    dim = len(columns) - 1
    if dim < 1 or dim > limits.MAX_DIM or columns != [*(f"x{i}" for i in range(dim)), "radius"]:
        raise ValueError(f"its header is {shown(header.strip())}, not x0,...,radius (at most {limits.MAX_DIM}-D)")
    table = np.loadtxt(path, delimiter=",", skiprows=2 if first.startswith("#") else 1, ndmin=2)
    table = table.reshape(-1, dim + 1)
    return table[:, :dim], table[:, dim]


register(Format("medial", (".ply", ".csv"), "any", "the medial-axis sample (.ply: up to 3-D)",
                {"encoding": "binary|ascii"}, _write_medial, None, suffix_dims={".ply": "1-3"},
                dim_message="PLY holds points in up to 3-D, not a {dim}-D medial axis: write it to a .csv file"))
