"""VTK PolyData files (``vtp``, ``.vtp``, 1-3-D) for ParaView's glyphs.

One point and one vertex cell per sphere, with point data ``radius``, ``diameter`` and
``round``; the metadata is an XML comment ``<!-- ndpack-metadata {...} -->``. Options:
``encoding`` (``binary``, inline base64, the default; or ``ascii``) and ``header_type``
(``UInt64``, the default, or ``UInt32``: the size of the byte count before binary data).
Written by hand: one small XML file does not justify VTK or pyvista as dependencies. The reader
takes uncompressed files of one piece, in either byte order.
"""

from __future__ import annotations

import base64
import json
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

from ..errors import NdpackError
from ..packing import Packing
from .limits import check_count, parse_json
from .metadata import check_metadata, metadata, packing_from, xyz
from .ply import points_dim
from .registry import Format, binary_encoding, register, require_dim

_VTK_TYPES = {"Float32": "f4", "Float64": "f8", "Int8": "i1", "Int16": "i2", "Int32": "i4", "Int64": "i8",
              "UInt8": "u1", "UInt16": "u2", "UInt32": "u4", "UInt64": "u8"}


def _vtk_array(name: str, values: np.ndarray, kind: str, binary: bool, header: str, components: int = 1) -> str:
    values = np.ascontiguousarray(values, dtype="<" + _VTK_TYPES[kind])
    tags = f'type="{kind}" Name="{name}"' + (f' NumberOfComponents="{components}"' if components > 1 else "")
    if binary:
        # Inline binary: base64 of the byte count (header_type) followed by the data, one stream.
        data = values.tobytes()
        if len(data) > np.iinfo(_VTK_TYPES[header]).max:
            raise NdpackError(f"the {name} array is too large for header_type {header}: use UInt64")
        text = base64.b64encode(np.array(len(data), dtype="<" + _VTK_TYPES[header]).tobytes() + data).decode("ascii")
        return f'<DataArray {tags} format="binary">{text}</DataArray>'
    # repr/str of Python numbers: the shortest text that reads back to the same value.
    text = " ".join(map(repr if kind.startswith("Float") else str, values.ravel().tolist()))
    return f'<DataArray {tags} format="ascii">{text}</DataArray>'


def _write_vtp(packing: Packing, path: Path, encoding: str | None = None, header_type: str = "UInt64") -> None:
    require_dim(packing.dim, range(1, 4), "VTK PolyData (.vtp)")
    if header_type not in ("UInt64", "UInt32"):
        raise NdpackError(f"header_type must be 'UInt64' or 'UInt32', got {header_type!r}")
    binary = binary_encoding(encoding)
    count = len(packing)
    ids = np.arange(count, dtype=np.int64)

    def array(name, values, kind, components=1):
        return _vtk_array(name, values, kind, binary, header_type, components)

    # An XML comment may not hold "--"; JSON has it only inside strings, where "\u002d" is "-".
    meta = json.dumps(metadata(packing)).replace("--", "-\\u002d")
    lines = [
        '<?xml version="1.0"?>',
        f'<VTKFile type="PolyData" version="1.0" byte_order="LittleEndian" header_type="{header_type}">',
        f"  <!-- ndpack packing: one point and one vertex cell per sphere; {packing.dim}-D -->",
        f"  <!-- ndpack-metadata {meta} -->",
        "  <PolyData>",
        f'    <Piece NumberOfPoints="{count}" NumberOfVerts="{count}" NumberOfLines="0" '
        'NumberOfStrips="0" NumberOfPolys="0">',
        '      <PointData Scalars="radius">',
        "        " + array("radius", packing.radii, "Float64"),
        "        " + array("diameter", 2 * packing.radii, "Float64"),
        "        " + array("round", packing.rounds, "Int64"),
        "      </PointData>",
        "      <Points>",
        "        " + array("Points", xyz(packing.centers), "Float64", 3),
        "      </Points>",
        "      <Verts>",
        "        " + array("connectivity", ids, "Int64"),
        "        " + array("offsets", ids + 1, "Int64"),
        "      </Verts>",
        "    </Piece>",
        "  </PolyData>",
        "</VTKFile>",
    ]
    path.write_text("\n".join(lines) + "\n")


def _vtk_values(node, order: str, header: str) -> np.ndarray:
    """The values of one ``DataArray`` (ascii or inline binary, uncompressed), flat."""
    if node is None:
        raise ValueError("a DataArray is missing")
    kind = node.get("type", "")
    if kind not in _VTK_TYPES:
        raise ValueError(f"unknown DataArray type {kind!r}")
    dtype = np.dtype(order + _VTK_TYPES[kind])
    text = (node.text or "").strip()
    encoding = node.get("format", "ascii")
    if encoding == "ascii":
        return np.array(text.split(), dtype=dtype.newbyteorder("="))
    if encoding != "binary":
        raise ValueError(f"DataArray format {encoding!r} is not read (ndpack writes 'binary' or 'ascii')")
    header_size = np.dtype(header).itemsize
    chars = 4 * -(-header_size // 3)
    if text[chars - 1 : chars] == "=" and len(text) > chars:
        # The header encoded apart from the data (its base64 ends in padding), as VTK may write it.
        raw = base64.b64decode(text[:chars])[:header_size] + base64.b64decode(text[chars:])
    else:
        raw = base64.b64decode(text)
    size = int(np.frombuffer(raw[:header_size], dtype=header)[0])
    data = raw[header_size:]
    if len(data) != size or size % dtype.itemsize:
        raise ValueError(f"a binary DataArray holds {len(data)} bytes where its header says {size}")
    return np.frombuffer(data, dtype=dtype)


def _read_vtp(path: Path) -> Packing:
    parser = ET.XMLParser(target=ET.TreeBuilder(insert_comments=True))
    root = ET.fromstring(path.read_bytes(), parser=parser)
    if root.tag != "VTKFile" or root.get("type") != "PolyData":
        raise ValueError('it is not a VTK PolyData file (<VTKFile type="PolyData">)')
    if root.get("compressor"):
        raise ValueError(f"it is compressed ({root.get('compressor')}); ndpack reads the uncompressed files it writes")
    order = {"LittleEndian": "<", "BigEndian": ">"}[root.get("byte_order", "LittleEndian")]
    header = order + _VTK_TYPES[root.get("header_type", "UInt32")]
    meta = None
    for node in root:
        text = (node.text or "").strip()
        if node.tag is ET.Comment and text.startswith("ndpack-metadata "):
            meta = check_metadata(parse_json(text[len("ndpack-metadata ") :]), path)
    pieces = root.findall("PolyData/Piece")
    if len(pieces) != 1:
        raise ValueError(f"it has {len(pieces)} pieces; ndpack writes one")
    piece = pieces[0]
    count = int(piece.get("NumberOfPoints", "0"))
    # Every point takes at least 6 bytes (3 coordinates of a digit and a space): checked before reading.
    check_count(count, "points", path.stat().st_size // 6, f"its {path.stat().st_size:,} bytes")
    points = _vtk_values(piece.find("Points/DataArray"), order, header)
    if points.size != 3 * count:
        raise ValueError(f"it declares {count:,} points, but its Points array holds {points.size:,} numbers, "
                         f"not {3 * count:,}")
    points = points.reshape(count, 3)
    arrays = {node.get("Name"): node for node in piece.findall("PointData/DataArray")}
    if "radius" not in arrays:
        raise ValueError("it has no point data array 'radius'")
    radii = _vtk_values(arrays["radius"], order, header)
    rounds = _vtk_values(arrays["round"], order, header) if "round" in arrays else None
    dim = points_dim(meta)
    return packing_from(meta, points[:, :dim], radii, rounds)


register(Format("vtp", (".vtp",), "1-3", "spheres, rounds, metadata (VTK points for ParaView glyphs)",
                {"encoding": "binary|ascii", "header_type": "UInt64|UInt32"}, _write_vtp, _read_vtp),
         default_for=(".vtp",))
