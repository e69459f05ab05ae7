"""PLY point files (``ply``, ``.ply``, 1-3-D): one vertex per sphere.

The vertex element has ``double x, y, z, radius`` and ``int round``; the metadata is a header
comment ``ndpack-metadata {...}`` and a packing of fewer than 3 dimensions says so in a comment
(its missing coordinates are 0). The ``encoding`` option is ``binary`` (little-endian, the
default) or ``ascii``. The reader takes binary files of either byte order and ASCII files of one
``vertex`` element with scalar properties; a mesh (faces, list properties) is refused, not
misread. The medial-axis sample's ``.ply`` (:mod:`ndpack.io.medial`) uses the same points layer.
"""

from __future__ import annotations

import io
import json
from pathlib import Path

import numpy as np

from ..errors import NdpackError
from ..packing import Packing
from .limits import check_count, parse_json, printable
from .metadata import check_metadata, metadata, packing_from, xyz
from .registry import Format, binary_encoding, register, require_dim

# PLY's scalar types and their NumPy codes (both the old and the sized names).
_PLY_TYPES = {
    "char": "i1", "int8": "i1", "uchar": "u1", "uint8": "u1", "short": "i2", "int16": "i2",
    "ushort": "u2", "uint16": "u2", "int": "i4", "int32": "i4", "uint": "u4", "uint32": "u4",
    "float": "f4", "float32": "f4", "double": "f8", "float64": "f8",
}
_PLY_ORDERS = {"binary_little_endian": "<", "binary_big_endian": ">", "ascii": "<"}


def write_points(path: Path, comments: list[str], columns: list[tuple], binary: bool) -> None:
    """A PLY file of one ``vertex`` element.

    Parameters
    ----------
    path : Path
    comments : list of str
        Header comment lines.
    columns : list of (name, ply type, (n,) values)
        One property each, such as ``("x", "double", xs)``.
    binary : bool
        Binary little-endian, else ASCII (``%.17g`` for floats).
    """
    count = len(columns[0][2])
    header = ["ply", f"format {'binary_little_endian' if binary else 'ascii'} 1.0"]
    header += [f"comment {line}" for line in comments]
    header += [f"element vertex {count}", *(f"property {kind} {name}" for name, kind, _ in columns), "end_header"]
    with open(path, "wb") as file:
        file.write(("\n".join(header) + "\n").encode("ascii"))
        if binary:
            table = np.empty(count, dtype=[(name, "<" + _PLY_TYPES[kind]) for name, kind, _ in columns])
            for name, _, values in columns:
                table[name] = values
            file.write(table.tobytes())
        elif count:
            formats = ["%.17g" if _PLY_TYPES[kind][0] == "f" else "%d" for _, kind, _ in columns]
            np.savetxt(file, np.column_stack([values for _, _, values in columns]), fmt=formats)


def read_points(path: Path) -> tuple[dict | None, np.ndarray]:
    """The ndpack metadata (or None) and the vertex table of a points-only PLY file.

    Reads binary (either byte order) and ASCII files whose only element is ``vertex`` with
    scalar properties; a mesh (faces, list properties) is refused, not misread.

    Returns
    -------
    metadata : dict or None
        From the ``ndpack-metadata`` comment, unchecked.
    table : (n,) structured array
        One field per property; ``x``, ``y``, ``z`` and ``radius`` are there.
    """
    raw = path.read_bytes()
    end = raw.find(b"end_header")
    if not raw.startswith(b"ply") or end < 0:
        raise ValueError("it is not a PLY file (no 'ply' ... 'end_header' header)")
    body = raw[raw.index(b"\n", end) + 1 :]
    layout, meta, elements = None, None, []
    for line in raw[:end].decode("ascii", errors="replace").splitlines()[1:]:
        words = line.split()
        if not words or words[0] == "obj_info":
            continue
        if words[0] == "comment":
            text = line.strip()[len("comment") :].strip()
            if text.startswith("ndpack-metadata "):
                meta = parse_json(text[len("ndpack-metadata ") :])
        elif words[0] == "format":
            layout = words[1]
        elif words[0] == "element":
            elements.append((words[1], int(words[2]), []))
        elif words[0] == "property" and elements:
            if words[1] == "list":
                raise ValueError(f"its {elements[-1][0]} element has a list property: a mesh, not spheres")
            if words[1] not in _PLY_TYPES:
                raise ValueError(f"unknown PLY property type {words[1]!r}")
            elements[-1][2].append((words[2], _PLY_TYPES[words[1]]))
        else:
            raise ValueError(f"unexpected PLY header line {line.strip()!r}")
    if layout not in _PLY_ORDERS:
        raise ValueError(f"unknown PLY format {layout!r}")
    if [name for name, _, _ in elements] != ["vertex"]:
        found = printable(", ".join(name for name, _, _ in elements) or "none")
        raise ValueError(f"it has the elements {found}; ndpack reads PLY files of one 'vertex' element (points)")
    _, count, properties = elements[0]
    dtype = np.dtype([(name, _PLY_ORDERS[layout] + code) for name, code in properties])
    missing = [name for name in ("x", "y", "z", "radius") if name not in dtype.names]
    if missing:
        raise ValueError(f"its vertices have no {', '.join(missing)} (ndpack writes x, y, z, radius)")
    if count < 0:
        raise ValueError(f"it declares {count} vertices")
    if layout == "ascii":
        # A row of text holds at least a digit and a space or newline per property: the declared
        # count is checked against that before the table is allocated.
        check_count(count, "vertices", (len(body) + 1) // (2 * len(properties)), f"its {len(body):,} bytes of rows")
        table = np.zeros(count, dtype=dtype)
        if count:
            values = np.loadtxt(io.BytesIO(body), ndmin=2, max_rows=count)
            if values.shape != (count, len(properties)):
                raise ValueError(f"it should hold {count} rows of {len(properties)} numbers, found {values.shape}")
            for i, (name, _) in enumerate(properties):
                table[name] = values[:, i]
    else:
        if len(body) < count * dtype.itemsize:
            raise ValueError(
                f"it is truncated: {count} vertices need {count * dtype.itemsize} bytes, found {len(body)}"
            )
        table = np.frombuffer(body, dtype=dtype, count=count)
    return meta, table


def points_dim(meta: dict | None) -> int:
    """The dimension checked metadata gives points stored with 3 coordinates (PLY, VTP): 3 without
    metadata; a ValueError for more than 3."""
    dim = meta.get("dim", 3) if meta else 3
    if dim > 3:
        raise ValueError(f"its metadata says {dim}-D, but its points have 3 coordinates")
    return dim


def dimension_comment(dim: int) -> list[str]:
    """The header comment that says the points are ``dim``-D (none for 3-D)."""
    if dim == 3:
        return []
    return [f"ndpack-dimension {dim}: the coordinates past x{dim - 1} are 0"]


def _write_ply(packing: Packing, path: Path, encoding: str | None = None) -> None:
    require_dim(packing.dim, range(1, 4), "PLY (.ply)")
    if len(packing) and packing.rounds.max() > np.iinfo(np.int32).max:
        raise NdpackError("a round number exceeds PLY's 32-bit int: use .npz, .csv or .json")
    points = xyz(packing.centers)
    columns = [
        ("x", "double", points[:, 0]),
        ("y", "double", points[:, 1]),
        ("z", "double", points[:, 2]),
        ("radius", "double", packing.radii),
        ("round", "int", packing.rounds),
    ]
    comments = ["ndpack packing: one vertex per sphere", *dimension_comment(packing.dim)]
    comments.append("ndpack-metadata " + json.dumps(metadata(packing)))
    write_points(path, comments, columns, binary_encoding(encoding))


def _read_ply(path: Path) -> Packing:
    meta, table = read_points(path)
    if meta is not None:
        check_metadata(meta, path)
    dim = points_dim(meta)
    points = np.column_stack([table["x"], table["y"], table["z"]])[:, :dim]
    rounds = table["round"] if "round" in table.dtype.names else None
    return packing_from(meta, points, table["radius"], rounds)


register(Format("ply", (".ply",), "1-3", "spheres, rounds, metadata (points with radius)",
                {"encoding": "binary|ascii"}, _write_ply, _read_ply), default_for=(".ply",))
