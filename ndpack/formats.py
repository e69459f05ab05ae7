"""Packing files: every format ndpack writes, and reads back, chosen by suffix or by name.

========  ================  ====  ====================================================================
name      suffixes          dims  what is kept
========  ================  ====  ====================================================================
npz       .npz              any   everything: metadata, spheres, rounds, round stats, medial axis
csv       .csv              any   metadata (first line), spheres and rounds
json      .json             any   everything, as plain JSON
ply       .ply              1-3   spheres and rounds (one point per sphere), metadata as a comment
vtp       .vtp              1-3   spheres as VTK points with radius, diameter and round (ParaView)
mesh      .obj .stl .glb    3     an icosphere per sphere: centres and radii (STL, GLB: float32, radii
                                  shrunk by its rounding, so that the spheres read back verify)
sph       .sph              3     spheres as a 2-level sphere tree (sphere-tree toolkit)
curobo    .json .yml .yaml  3     spheres as cuRobo ``collision_spheres`` of one link (JSON or YAML)
lammps    .data             2-3   spheres, a density and a box: LAMMPS ``read_data``, atom_style sphere
liggghts  .data             2-3   the same rows, for LIGGGHTS ``read_data`` (atom_style granular)
yade      .txt              3     spheres as ``x y z r`` lines: Yade's ``ymport.text``
medial    .ply .csv         any   the medial-axis sample (points and radii); .ply up to 3-D
========  ================  ====  ====================================================================

:func:`save` picks the format from the suffix (the first name listed for it) unless ``format=``
names one: ``liggghts`` and ``medial`` are only chosen by name, and so is ``curobo`` for a
``.json`` file (``.yml`` and ``.yaml`` are always cuRobo YAML). Named, ``lammps`` and
``liggghts`` take any file name (LAMMPS users often write ``data.bed``). :func:`load` reads
every format but ``medial`` (read with :func:`load_medial`); a ``.json`` file is told apart by
its content. cuRobo YAML is written and read with PyYAML. The DEM
formats (lammps, liggghts, yade) are written by :mod:`ndpack.dem_formats`.
Files that hold only spheres load as a :class:`~ndpack.packing.Packing` whose volume is unknown
(NaN, so its fill is NaN), whose rounds are 0, and whose params are empty.

Every problem (unknown suffix or name, wrong dimension, missing or unreadable file) raises an
:class:`~ndpack.errors.NdpackError` with a one-line message.
"""

from __future__ import annotations

import base64
import io
import json
import math
import re
import warnings
import xml.etree.ElementTree as ET
import zipfile
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np

from . import dem_formats
from .errors import DimensionError, NdpackError
from .packing import FORMAT_VERSION, Packing, RoundStats

#: Version of the medial-axis sample's small metadata (its own layout, apart from packings').
MEDIAL_VERSION = 1


@dataclass(frozen=True)
class Format:
    """One file format: its name, suffixes, the dimensions it holds, what it keeps, its options."""

    name: str
    suffixes: tuple[str, ...]
    dims: str
    keeps: str
    options: dict[str, str]
    write: Callable
    read: Callable | None


# ---------------------------------------------------------------------------------- public API
def save(packing: Packing, path, format: str | None = None, **options) -> Path:
    """Write ``packing`` to ``path`` in the format of its suffix, or the one named; returns the path.

    Parameters
    ----------
    packing : Packing
    path : str or Path
    format : str, optional
        A name from :func:`names`; needed for ``liggghts``, ``medial`` and ``curobo`` in
        ``.json``, whose suffixes (``.json``, ``.data``, ``.ply``, ``.csv``) default to other
        formats.
    **options
        Format options (see :func:`table`): ``encoding`` ("binary" or "ascii") for ply, vtp
        and medial .ply; ``header_type`` ("UInt64" or "UInt32") for vtp; ``subdivisions`` for
        mesh; ``link`` for curobo; ``density`` (a positive number, default 1) for lammps and
        liggghts.
    """
    path = Path(path)
    fmt = check(path, format, packing.dim, **options)
    try:
        fmt.write(packing, path, **options)
    except OSError as error:
        raise NdpackError(f"cannot write {path}: {error.strerror or error}") from error
    return path


def check(path, format: str | None = None, dim: int | None = None, **options) -> Format:
    """The format :func:`save` would write ``path`` in; raises if it would refuse.

    Checks the suffix (or ``format``), the options' names and, given ``dim``, that the format
    holds packings of that dimension, so that a long packing can be refused before it starts
    rather than after it ends.

    Returns
    -------
    Format
    """
    path = Path(path)
    fmt = _resolve(path, format, "save to")
    unknown = sorted(set(options) - set(fmt.options))
    if unknown:
        accepted = ", ".join(fmt.options) or "none"
        raise NdpackError(f"the {fmt.name} format has no option {', '.join(unknown)} (its options: {accepted})")
    if dim is not None:
        allowed = _dims(fmt, path.suffix.lower())
        if fmt.name == "medial" and dim not in allowed:
            raise DimensionError(f"PLY holds points in up to 3-D, not a {dim}-D medial axis: write it to a .csv file")
        if dim not in allowed:
            _require_dim(dim, allowed, f"the {fmt.name} format ({path.suffix.lower()})")
    return fmt


def _dims(fmt: Format, suffix: str) -> range:
    """The dimensions ``fmt`` holds, from its table entry (``"any"``, ``"3"``, ``"1-3"``)."""
    if fmt.name == "medial" and suffix == ".ply":
        return range(1, 4)
    if fmt.dims == "any":
        return range(1, 1 << 30)
    low, _, high = fmt.dims.partition("-")
    return range(int(low), int(high or low) + 1)


def load(path, format: str | None = None) -> Packing:
    """Read a packing from any format but ``medial`` (see :func:`load_medial`).

    Native files (npz, csv, json) come back as they were saved (every bit of the spheres);
    the others as described in the module's table.
    """
    path = _existing(path)
    fmt = _resolve(path, format, "load")
    if fmt.name == "medial":
        raise NdpackError(f"the medial format is read with ndpack.formats.load_medial({str(path)!r}), not load()")
    return _reading(fmt, path, fmt.read)


def load_medial(path) -> tuple[np.ndarray, np.ndarray]:
    """Read a medial-axis sample written with ``save(..., format="medial")``.

    Returns
    -------
    points : (m, d) float64
    radii : (m,) float64
        The clearance at each point (the radius of the maximal ball there).
    """
    path = _existing(path)
    fmt = _resolve(path, "medial", "load")
    return _reading(fmt, path, _read_medial)


def names() -> list[str]:
    """The format names, in the order of :func:`table`."""
    return list(FORMATS)


def table() -> str:
    """The formats as a plain-text table (name, suffixes, dimensions, what is kept, save options)."""
    rows = [("name", "suffixes", "dims", "keeps", "options")]
    for fmt in FORMATS.values():
        options = ", ".join(f"{key}={value}" for key, value in fmt.options.items()) or "-"
        rows.append((fmt.name, " ".join(fmt.suffixes), fmt.dims, fmt.keeps, options))
    widths = [max(len(row[i]) for row in rows) for i in range(4)]
    return "\n".join("  ".join(cell.ljust(width) for cell, width in zip(row, widths)) + "  " + row[4] for row in rows)


def sphere_mesh(centers, radii, subdivisions: int = 1):
    """One icosphere per sphere, all in one triangle mesh (built without a loop over spheres).

    Parameters
    ----------
    centers : (n, 3) float64
    radii : (n,) float64
    subdivisions : int
        Of the unit icosphere: 0 gives 12 vertices and 20 triangles a sphere, 1 gives 42 and 80,
        and each one more multiplies the triangles by 4.

    Returns
    -------
    trimesh.Trimesh
        ``n * (10 * 4**s + 2)`` vertices and ``n * 20 * 4**s`` faces; sphere ``i`` owns the
        ``i``-th block of each. Every vertex lies on its sphere (to float64 rounding).
    """
    import trimesh

    centers = np.asarray(centers, dtype=np.float64)
    radii = np.asarray(radii, dtype=np.float64)
    if centers.ndim != 2 or centers.shape[1] != 3:
        raise DimensionError(f"a sphere mesh needs 3-D centres of shape (n, 3), got {centers.shape}")
    if not (isinstance(subdivisions, (int, np.integer)) and 0 <= subdivisions <= 6):
        raise NdpackError(f"subdivisions must be an integer from 0 to 6, got {subdivisions!r}")
    unit = trimesh.creation.icosphere(subdivisions=int(subdivisions))
    vertices = (centers[:, None, :] + radii[:, None, None] * unit.vertices[None]).reshape(-1, 3)
    offsets = np.arange(len(radii), dtype=np.int64) * len(unit.vertices)
    faces = (unit.faces[None].astype(np.int64) + offsets[:, None, None]).reshape(-1, 3)
    # process=False: no vertex merging, so that the per-sphere blocks stay as built.
    return trimesh.Trimesh(vertices, faces, process=False)


def spheres_from_mesh(vertices, faces) -> tuple[np.ndarray, np.ndarray]:
    """Recover the spheres of a mesh made by :func:`sphere_mesh` (its faces in the same order).

    The faces per sphere, ``20 * 4**s``, are the smallest block size that cuts the faces into
    closed surfaces of ``10 * 4**s + 2`` vertices each (vertices matched by exact coordinates).
    This needs no vertex merging with a tolerance (STL stores every triangle's corners apart)
    and checks that every block is an icosphere; spheres that touch at a shared vertex stay apart.

    Parameters
    ----------
    vertices : (v, 3) float
    faces : (f, 3) int
        As read, unmerged: trimesh's ``process=False``.

    Returns
    -------
    centers : (n, 3) float64
        The mean of each icosphere's vertices (the icosphere is centrally symmetric).
    radii : (n,) float64
        The mean distance of its vertices from that centre (they lie on the sphere).
    """
    corners = np.asarray(vertices, dtype=np.float64)[np.asarray(faces, dtype=np.int64)]  # (f, 3, 3)
    count = len(corners)
    if count == 0:
        return np.zeros((0, 3)), np.zeros(0)
    table, ids = np.unique(corners.reshape(-1, 3), axis=0, return_inverse=True)
    ids = ids.reshape(count, 3)
    s = 0
    while 20 * 4**s <= count:
        per_sphere = 20 * 4**s
        if count % per_sphere == 0:
            found = _icosphere_blocks(table, ids, per_sphere, 10 * 4**s + 2)
            if found is not None:
                return found
        s += 1
    raise ValueError(f"its {count} triangles are not icospheres of one size written by ndpack")


# ---------------------------------------------------------------------------------- resolution
def _existing(path) -> Path:
    path = Path(path)
    if not path.exists():
        raise NdpackError(f"no such packing file: {path}")
    if path.is_dir():
        raise NdpackError(f"{path} is a folder, not a packing file")
    return path


def _resolve(path: Path, format: str | None, verb: str) -> Format:
    suffix = path.suffix.lower()
    if format is not None:
        fmt = FORMATS.get(str(format).lower())
        if fmt is None:
            raise NdpackError(f"unknown format {format!r}: use one of {', '.join(FORMATS)}")
        if suffix not in fmt.suffixes and fmt.name not in ANY_NAME:
            raise NdpackError(
                f"cannot {verb} {path.name!r} as {fmt.name}: its file name must end in {' or '.join(fmt.suffixes)}"
            )
        return fmt
    if suffix not in SUFFIXES:
        others = ", ".join(s for s in SUFFIXES if s not in (".npz", ".csv"))
        what = f"unknown suffix {suffix!r}" if suffix else "no suffix"
        raise NdpackError(
            f"cannot {verb} {path.name!r}: {what}; use a .npz or .csv file name (ndpack's own), or {others} "
            f"(format= picks one of {', '.join(FORMATS)})"
        )
    return FORMATS[SUFFIXES[suffix]]


def _reading(fmt: Format, path: Path, read: Callable):
    """Run a reader; anything a bad file makes it raise becomes one line naming file and reason."""
    try:
        return read(path)
    except NdpackError:
        raise
    except (KeyError, IndexError, TypeError, ValueError, OSError, EOFError, SyntaxError, zipfile.BadZipFile) as error:
        # SyntaxError covers xml.etree's ParseError; ValueError covers JSON and base64 errors.
        reason = str(error).strip().splitlines()[0] if str(error).strip() else type(error).__name__
        if path.is_file() and path.stat().st_size == 0:
            reason = "it is empty (0 bytes)"
        elif isinstance(error, json.JSONDecodeError):
            reason = f"its JSON is not valid ({error.msg}, at character {error.pos})"
        elif isinstance(error, UnicodeDecodeError):
            reason = "it is binary, not text"
        elif isinstance(error, KeyError):
            key = str(error.args[0]) if error.args else reason
            reason = f"it has no {key.removesuffix(' is not a file in the archive')!r}"
        elif "Object arrays" in reason:  # numpy's advice to allow pickles: ndpack never loads them
            reason = "it holds arrays of Python objects (pickled), which ndpack never loads"
        elif "pickle" in reason:
            reason = "it is not an archive of arrays (NumPy would read it as pickled objects, which ndpack never loads)"
        raise NdpackError(f"{path} is not a readable ndpack packing ({fmt.name} format): {reason}") from error


def _require_dim(dim: int, allowed: range, what: str) -> None:
    if dim not in allowed:
        if allowed.stop - allowed.start == 1:
            need = f"{allowed.start}-D spheres"
        else:
            need = f"spheres in {allowed.start} to {allowed.stop - 1} dimensions"
        raise DimensionError(
            f"{what} holds {need}, not a {dim}-D packing: use .npz, .csv or .json, which keep any dimension"
        )


def _xyz(points: np.ndarray) -> np.ndarray:
    """``(n, d)`` points with ``d <= 3`` as ``(n, 3)``, the missing coordinates 0."""
    out = np.zeros((len(points), 3))
    out[:, : points.shape[1]] = points
    return out


def _encoding(encoding: str | None) -> bool:
    """True for binary (the default), False for ASCII."""
    if encoding is None or str(encoding).lower() == "binary":
        return True
    if str(encoding).lower() == "ascii":
        return False
    raise NdpackError(f"encoding must be 'binary' or 'ascii', got {encoding!r}")


# ---------------------------------------------------------------------------------- metadata
def metadata(packing: Packing) -> dict:
    """The JSON metadata that every native file carries (npz, csv, json; ply and vtp too)."""
    return {
        "format": "ndpack-packing",
        "version": FORMAT_VERSION,
        "dim": packing.dim,
        # None, not NaN, keeps the JSON standard (a NaN volume: a packing read from spheres only).
        "volume": _finite_or_none(packing.volume),
        "volume_error": _finite_or_none(packing.volume_error),
        "params": packing.params,
        "stop_reason": packing.stop_reason,
        "repair": _json_repair(packing.repair),
        "shape": repr(packing.shape) if packing.shape is not None else None,
    }


def _json_repair(repair: dict | None) -> dict | None:
    """The repair record with infinite worst values as None (standard JSON)."""
    if repair is None:
        return None
    return {key: _finite_or_none(value) if isinstance(value, float) else value for key, value in repair.items()}


def _finite_or_none(value):
    return float(value) if math.isfinite(value) else None


def _check_metadata(metadata: dict, path: Path, kind: str = "ndpack-packing") -> dict:
    if not isinstance(metadata, dict) or metadata.get("format") not in ("ndpack-packing", "ndpack-medial"):
        raise ValueError("it has no ndpack metadata")
    if metadata["format"] != kind:
        if kind == "ndpack-packing":
            raise NdpackError(
                f"{path} holds a medial-axis sample, not a packing: read it with ndpack.formats.load_medial"
            )
        raise NdpackError(f"{path} holds a packing, not a medial-axis sample: read it with ndpack.Packing.load")
    newest = FORMAT_VERSION if kind == "ndpack-packing" else MEDIAL_VERSION
    if metadata.get("version", 0) > newest:
        raise NdpackError(f"{path} was written by a newer ndpack (format {metadata['version']}); upgrade ndpack")
    return metadata


def _packing(metadata: dict | None, centers, radii, rounds=None, **extra) -> Packing:
    """A Packing from arrays and (native) metadata; spheres-only files get NaN volume, rounds 0."""
    metadata = metadata or {}
    radii = np.asarray(radii, dtype=np.float64).reshape(-1)
    dim = metadata.get("dim", 3)
    if isinstance(dim, bool) or not isinstance(dim, int) or dim < 1:
        raise ValueError(f"its dimension {dim!r} is not a positive integer")
    centers = np.asarray(centers, dtype=np.float64).reshape(-1, dim)
    rounds = np.zeros(len(radii), dtype=np.int64) if rounds is None else np.asarray(rounds, dtype=np.int64)
    if not len(centers) == len(radii) == len(rounds):
        raise ValueError(f"it has {len(centers)} centres, {len(radii)} radii and {len(rounds)} rounds")
    # A corrupted or hand-edited file must not load as spheres that verify() or a picture would trip over.
    for what, bad in (("radii", ~(np.isfinite(radii) & (radii > 0))), ("centres", ~np.isfinite(centers).all(axis=1))):
        if bad.any():
            first = int(np.flatnonzero(bad)[0])
            raise ValueError(f"{int(bad.sum())} of its {what} are not {'positive ' if what == 'radii' else ''}finite "
                             f"numbers, first of sphere {first}")
    volume, volume_error = metadata.get("volume"), metadata.get("volume_error")
    for name, value in (("volume", volume), ("volume_error", volume_error)):
        if value is not None and (isinstance(value, bool) or not isinstance(value, (int, float)) or value < 0):
            raise ValueError(f"its {name} {value!r} is not a non-negative number")
    return Packing(
        centers=centers,
        radii=radii,
        rounds=rounds,
        volume=float("nan") if volume is None else volume,
        volume_error=0.0 if volume_error is None else volume_error,
        params=metadata.get("params", {}),
        stop_reason=metadata.get("stop_reason", ""),
        repair=metadata.get("repair"),
        **extra,
    )


def _or_empty(array, shape):
    return np.zeros(shape) if array is None else array


# ---------------------------------------------------------------------------------- npz, csv, json
def _write_npz(packing: Packing, path: Path) -> None:
    np.savez_compressed(
        path,
        centers=packing.centers,
        radii=packing.radii,
        rounds=packing.rounds,
        stats_time=packing.stats.time,
        stats_count=packing.stats.count,
        stats_fill=packing.stats.fill,
        medial_axis=_or_empty(packing.medial_axis, (0, packing.dim)),
        medial_radii=_or_empty(packing.medial_radii, 0),
        metadata=np.array(json.dumps(metadata(packing))),
    )


def _read_npz(path: Path) -> Packing:
    data = np.load(path, allow_pickle=False)
    if not isinstance(data, np.lib.npyio.NpzFile):
        raise ValueError("it is a single NumPy array (.npy), not an archive of arrays")
    with data:
        meta = _check_metadata(json.loads(str(data["metadata"])), path)
        return _packing(
            meta,
            data["centers"],
            data["radii"],
            data["rounds"],
            stats=RoundStats(data["stats_time"], data["stats_count"], data["stats_fill"]),
            medial_axis=data["medial_axis"],
            medial_radii=data["medial_radii"],
        )


def _write_csv(packing: Packing, path: Path) -> None:
    header = ",".join([*(f"x{i}" for i in range(packing.dim)), "radius", "round"])
    table = np.column_stack([packing.centers, packing.radii, packing.rounds])
    formats = ["%.17g"] * (packing.dim + 1) + ["%d"]  # %.17g keeps every bit of a float64
    comment = "# " + json.dumps(metadata(packing))
    np.savetxt(path, table, delimiter=",", fmt=formats, header=f"{comment}\n{header}", comments="")


def _read_csv(path: Path) -> Packing:
    with open(path) as file:
        first = file.readline()
    if not first.startswith("# {"):
        raise ValueError("the first line is not ndpack's metadata comment")
    meta = _check_metadata(json.loads(first[2:]), path)
    dim = meta["dim"]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # "input contained no data": a packing of no spheres
        try:
            table = np.loadtxt(path, delimiter=",", skiprows=2, ndmin=2)
        except ValueError as error:
            changed = re.search(r"number of columns changed from \d+ to \d+ at row \d+", str(error))
            raise ValueError(f"its rows differ in length (the {changed.group()})" if changed else str(error)) from None
    if table.size == 0:
        table = np.zeros((0, dim + 2))
    if table.shape[1] != dim + 2:
        raise ValueError(f"its rows have {table.shape[1]} columns, but a {dim}-D packing has {dim + 2} "
                         f"(x0 to x{dim - 1}, radius, round)")
    return _packing(meta, table[:, :dim], table[:, dim], table[:, dim + 1].astype(np.int64))


def _write_json(packing: Packing, path: Path) -> None:
    # Python writes floats with repr, the shortest text that reads back to the same float64.
    document = {
        **metadata(packing),
        "centers": packing.centers.tolist(),
        "radii": packing.radii.tolist(),
        "rounds": packing.rounds.tolist(),
        "stats": {key: getattr(packing.stats, key).tolist() for key in ("time", "count", "fill")},
        "medial_axis": _or_empty(packing.medial_axis, (0, packing.dim)).tolist(),
        "medial_radii": _or_empty(packing.medial_radii, 0).tolist(),
    }
    path.write_text(json.dumps(document) + "\n")


def _read_json(path: Path) -> Packing:
    document = json.loads(path.read_text())
    if isinstance(document, dict) and "collision_spheres" in document and "format" not in document:
        return _curobo_packing(document)
    meta = _check_metadata(document, path)
    dim = meta["dim"]
    stats = document["stats"]
    return _packing(
        meta,
        document["centers"],
        document["radii"],
        document["rounds"],
        stats=RoundStats(
            np.asarray(stats["time"], dtype=np.float64),
            np.asarray(stats["count"], dtype=np.int64),
            np.asarray(stats["fill"], dtype=np.float64),
        ),
        medial_axis=np.asarray(document["medial_axis"], dtype=np.float64).reshape(-1, dim),
        medial_radii=np.asarray(document["medial_radii"], dtype=np.float64),
    )


# ---------------------------------------------------------------------------------- PLY
# PLY's scalar types and their NumPy codes (both the old and the sized names).
_PLY_TYPES = {
    "char": "i1", "int8": "i1", "uchar": "u1", "uint8": "u1", "short": "i2", "int16": "i2",
    "ushort": "u2", "uint16": "u2", "int": "i4", "int32": "i4", "uint": "u4", "uint32": "u4",
    "float": "f4", "float32": "f4", "double": "f8", "float64": "f8",
}
_PLY_ORDERS = {"binary_little_endian": "<", "binary_big_endian": ">", "ascii": "<"}


def _write_ply_points(path: Path, comments: list[str], columns: list[tuple], binary: bool) -> None:
    """One ``vertex`` element: ``columns`` are ``(name, ply type, (n,) values)``."""
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


def _read_ply_points(path: Path) -> tuple[dict | None, np.ndarray]:
    """The ndpack metadata (or None) and the vertex table of a points-only PLY file.

    Reads binary (either byte order) and ASCII files whose only element is ``vertex`` with
    scalar properties; a mesh (faces, list properties) is refused, not misread.
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
                meta = json.loads(text[len("ndpack-metadata ") :])
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
        found = ", ".join(name for name, _, _ in elements) or "none"
        raise ValueError(f"it has the elements {found}; ndpack reads PLY files of one 'vertex' element (points)")
    _, count, properties = elements[0]
    dtype = np.dtype([(name, _PLY_ORDERS[layout] + code) for name, code in properties])
    if layout == "ascii":
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
    missing = [name for name in ("x", "y", "z", "radius") if name not in dtype.names]
    if missing:
        raise ValueError(f"its vertices have no {', '.join(missing)} (ndpack writes x, y, z, radius)")
    return meta, table


def _dimension_comment(dim: int) -> list[str]:
    if dim == 3:
        return []
    return [f"ndpack-dimension {dim}: the coordinates past x{dim - 1} are 0"]


def _write_ply(packing: Packing, path: Path, encoding: str | None = None) -> None:
    _require_dim(packing.dim, range(1, 4), "PLY (.ply)")
    if len(packing) and packing.rounds.max() > np.iinfo(np.int32).max:
        raise NdpackError("a round number exceeds PLY's 32-bit int: use .npz, .csv or .json")
    points = _xyz(packing.centers)
    columns = [
        ("x", "double", points[:, 0]),
        ("y", "double", points[:, 1]),
        ("z", "double", points[:, 2]),
        ("radius", "double", packing.radii),
        ("round", "int", packing.rounds),
    ]
    comments = ["ndpack packing: one vertex per sphere", *_dimension_comment(packing.dim)]
    comments.append("ndpack-metadata " + json.dumps(metadata(packing)))
    _write_ply_points(path, comments, columns, _encoding(encoding))


def _read_ply(path: Path) -> Packing:
    meta, table = _read_ply_points(path)
    if meta is not None:
        _check_metadata(meta, path)
    dim = meta["dim"] if meta else 3
    points = np.column_stack([table["x"], table["y"], table["z"]])[:, :dim]
    rounds = table["round"] if "round" in table.dtype.names else None
    return _packing(meta, points, table["radius"], rounds)


# ---------------------------------------------------------------------------------- VTK PolyData
# Written by hand: one small XML file does not justify VTK or pyvista as dependencies.
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
    _require_dim(packing.dim, range(1, 4), "VTK PolyData (.vtp)")
    if header_type not in ("UInt64", "UInt32"):
        raise NdpackError(f"header_type must be 'UInt64' or 'UInt32', got {header_type!r}")
    binary = _encoding(encoding)
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
        "        " + array("Points", _xyz(packing.centers), "Float64", 3),
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
    """The values of one ``DataArray`` (ascii or inline binary, uncompressed)."""
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
            meta = _check_metadata(json.loads(text[len("ndpack-metadata ") :]), path)
    pieces = root.findall("PolyData/Piece")
    if len(pieces) != 1:
        raise ValueError(f"it has {len(pieces)} pieces; ndpack writes one")
    piece = pieces[0]
    count = int(piece.get("NumberOfPoints", "0"))
    points = _vtk_values(piece.find("Points/DataArray"), order, header).reshape(count, 3)
    arrays = {node.get("Name"): node for node in piece.findall("PointData/DataArray")}
    if "radius" not in arrays:
        raise ValueError("it has no point data array 'radius'")
    radii = _vtk_values(arrays["radius"], order, header)
    rounds = _vtk_values(arrays["round"], order, header) if "round" in arrays else None
    dim = meta["dim"] if meta else 3
    return _packing(meta, points[:, :dim], radii, rounds)


# ---------------------------------------------------------------------------------- sphere meshes
def _write_mesh(packing: Packing, path: Path, subdivisions: int = 1) -> None:
    _require_dim(packing.dim, range(3, 4), "a sphere mesh (.obj, .stl, .glb)")
    if not len(packing):
        raise NdpackError("an empty packing makes no sphere mesh (a mesh file with no triangles)")
    float32 = path.suffix.lower() != ".obj"
    radii = _float32_safe_radii(packing.centers, packing.radii, subdivisions) if float32 else packing.radii
    mesh = sphere_mesh(packing.centers, radii, subdivisions)
    if not float32:
        # 17 decimals: OBJ keeps float64 to about 1e-17; STL and GLB store float32.
        header = f"ndpack: {len(packing)} icospheres of {20 * 4**subdivisions} triangles"
        mesh.export(path, file_type="obj", include_normals=False, digits=17, header=header)
    else:
        mesh.export(path, file_type=path.suffix.lower()[1:])


def _float32_safe_radii(centers, radii, subdivisions: int) -> np.ndarray:
    """Radii to write in a float32 mesh (STL, GLB) so that the spheres read back from its rounded
    vertices (as :func:`spheres_from_mesh` recovers them) lie inside the given ones: a packing's
    file then verifies as the packing does. Each radius shrinks by about the float32 rounding of
    its coordinates (1e-7 of them), found by rounding the vertices as the writer will."""
    centers = np.asarray(centers, dtype=np.float64)
    radii = np.asarray(radii, dtype=np.float64)
    # float32's spacing at each sphere's largest coordinate: the step its vertices round to.
    step = np.spacing(np.float32(np.abs(centers).max(axis=1) + radii)).astype(np.float64)
    written = radii.copy()
    for _ in range(8):
        vertices = sphere_mesh(centers, written, subdivisions).vertices
        stored = vertices.astype(np.float32).astype(np.float64).reshape(len(radii), -1, 3)
        read_centers = stored.mean(axis=1)
        read_radii = np.linalg.norm(stored - read_centers[:, None, :], axis=2).mean(axis=1)
        excess = np.linalg.norm(read_centers - centers, axis=1) + read_radii - radii
        beyond = excess > -step  # within a rounding step of reaching out: shrink it
        if not beyond.any():
            break
        written[beyond] -= excess[beyond] + 2 * step[beyond]
    else:
        raise NdpackError("float32 cannot hold these spheres inside their own radii; save as .obj or .npz")
    if np.any(written <= 0):
        raise NdpackError(f"{int(np.count_nonzero(written <= 0))} spheres are smaller than float32 can place at "
                          "their coordinates (STL and GLB store float32): save as .obj or .npz, which keep float64")
    return written


def _read_mesh(path: Path) -> Packing:
    import trimesh

    try:
        # process=False: no merging or reordering, so that each sphere stays one block of faces.
        mesh = trimesh.load(path, force="mesh", process=False)
    except Exception as error:  # trimesh raises many kinds for unreadable files
        raise ValueError(f"trimesh cannot read it ({type(error).__name__}: {error})") from error
    if not isinstance(mesh, trimesh.Trimesh):
        raise ValueError(f"it holds a {type(mesh).__name__}, not a triangle mesh")
    if len(mesh.faces) == 0:
        raise ValueError("it has no triangles")
    centers, radii = spheres_from_mesh(mesh.vertices, mesh.faces)
    return _packing(None, centers, radii)


def _icosphere_blocks(table: np.ndarray, ids: np.ndarray, per_sphere: int, vertex_count: int):
    """Centres and radii if every block of ``per_sphere`` faces is a closed icosphere, else None."""
    count = len(ids) // per_sphere
    block = np.repeat(np.arange(count), per_sphere * 3)
    # Closed: every edge of a block is shared by exactly two of its faces.
    edges = np.sort(np.stack([ids, np.roll(ids, -1, axis=1)], axis=2).reshape(-1, 2), axis=1)
    _, uses = np.unique(np.column_stack([block, edges]), axis=0, return_counts=True)
    if not np.all(uses == 2):
        return None
    corners = np.sort(ids.reshape(count, per_sphere * 3), axis=1)
    first = np.ones(corners.shape, dtype=bool)
    first[:, 1:] = corners[:, 1:] != corners[:, :-1]
    if not np.all(first.sum(axis=1) == vertex_count):
        return None
    points = table[corners[first]].reshape(count, vertex_count, 3)
    centers = points.mean(axis=1)
    radii = np.linalg.norm(points - centers[:, None, :], axis=2).mean(axis=1)
    return centers, radii


# ---------------------------------------------------------------------------------- .sph sphere trees
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
    toolkit marks unused slots by a radius <= 0). The root is :func:`enclosing_sphere` of the
    spheres: it encloses every sphere, within about 1% of the smallest that does. Numbers are
    written with 17 significant digits, so a read-back is exact.
    """
    _require_dim(packing.dim, range(3, 4), "the sphere-tree format (.sph)")
    if len(packing):
        center, radius = enclosing_sphere(packing.centers, packing.radii)
        rows = np.vstack([np.append(center, radius), np.column_stack([packing.centers, packing.radii])])
        degree = len(packing)
    else:
        rows, degree = np.zeros((2, 4)), 1
    table = np.column_stack([rows, np.ones(len(rows))])
    np.savetxt(path, table, fmt=["%.17g"] * 4 + ["%d"], header=f"2 {degree}", comments="")


def enclosing_sphere(centers, radii, steps: int = 100) -> tuple[np.ndarray, float]:
    """A sphere that encloses every given sphere, close to the smallest one.

    Badoiu and Clarkson's iteration: from the bounding box's middle, step ``1 / (k + 1)`` of
    the way towards the farthest sphere surface; the result, or the box's middle where that is
    better. The radius is measured from the centre chosen, so the sphere always encloses every
    one given; it is within 0.2% of the smallest in the tests' cases.

    Parameters
    ----------
    centers : (n, d) float64
    radii : (n,) float64

    Returns
    -------
    center : (d,) float64
    radius : float
    """
    centers = np.asarray(centers, dtype=float)
    radii = np.asarray(radii, dtype=float)
    center = ((centers - radii[:, None]).min(axis=0) + (centers + radii[:, None]).max(axis=0)) / 2
    box_center = center
    for k in range(1, steps + 1):
        offsets = centers - center
        lengths = np.linalg.norm(offsets, axis=1)
        far = int(np.argmax(lengths + radii))
        if lengths[far] > 0:
            surface = centers[far] + radii[far] * offsets[far] / lengths[far]
            center = center + (surface - center) / (k + 1)
    # The box's middle is sometimes better (a few extreme spheres): keep the smaller sphere.
    return min(((c, float((np.linalg.norm(centers - c, axis=1) + radii).max())) for c in (center, box_center)),
               key=lambda pair: pair[1])


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
    path = _existing(path)
    return _reading(FORMATS["sph"], path, lambda path: _read_sph_level(path, level))


def _read_sph_level(path: Path, level: int) -> tuple[np.ndarray, np.ndarray]:
    lines = [line.split() for line in path.read_text().splitlines()]
    lines = [words for words in lines if words]
    if not lines or len(lines[0]) != 2:
        raise ValueError("its first line is not 'levels branching'")
    levels, degree = int(lines[0][0]), int(lines[0][1])
    if levels < 1 or degree < 1:
        raise ValueError(f"its header '{levels} {degree}' has no spheres")
    sizes = [degree**i for i in range(levels)]
    if len(lines) - 1 < sum(sizes):
        raise ValueError(f"a {levels}-level tree of branching {degree} has {sum(sizes)} nodes; found {len(lines) - 1}")
    if not -levels <= level < levels:
        raise NdpackError(f"{path} has {levels} levels; there is no level {level}")
    level = level % levels
    start = 1 + sum(sizes[:level])
    rows = np.array([[float(word) for word in words[:4]] for words in lines[start : start + sizes[level]]])
    rows = rows[rows[:, 3] > 0]
    return rows[:, :3].reshape(-1, 3), rows[:, 3]


def _read_sph(path: Path) -> Packing:
    centers, radii = _read_sph_level(path, -1)
    return _packing(None, centers, radii)


# ---------------------------------------------------------------------------------- cuRobo spheres
#: Suffixes of cuRobo YAML files (the rest of the curobo format's suffixes are JSON).
YAML_SUFFIXES = (".yml", ".yaml")


def _write_curobo(packing: Packing, path: Path, link: str = "body") -> None:
    """``{"collision_spheres": {link: [{"center": [x, y, z], "radius": r}, ...]}}``, a sphere a line,
    as JSON, or as YAML for a ``.yml`` or ``.yaml`` file (:func:`curobo_yaml`)."""
    _require_dim(packing.dim, range(3, 4), "cuRobo's collision_spheres")
    if path.suffix.lower() in YAML_SUFFIXES:
        path.write_text(curobo_yaml({str(link): (packing.centers, packing.radii)}))
        return
    spheres = [
        json.dumps({"center": center, "radius": radius})
        for center, radius in zip(packing.centers.tolist(), packing.radii.tolist())
    ]
    body = ",\n".join(f"      {sphere}" for sphere in spheres)
    text = f'{{\n  "collision_spheres": {{\n    {json.dumps(str(link))}: [\n{body}\n    ]\n  }}\n}}\n'
    path.write_text(text if spheres else text.replace("[\n\n    ]", "[]"))


def curobo_yaml(links: dict, comment: str | None = None) -> str:
    """cuRobo's collision spheres file as YAML text (PyYAML's ``safe_dump``; every number reads
    back as the same float64)::

        collision_spheres:
          base_link:
          - center: [0.1, 0.0, 0.25]
            radius: 0.05

    Parameters
    ----------
    links : dict
        Link name -> ``(centers, radii)``: ``(n, 3)`` and ``(n,)`` arrays, in the link's frame.
    comment : str, optional
        Written first, as ``#`` comment lines.

    Returns
    -------
    str
    """
    import yaml

    document = {}
    for link, (centers, radii) in links.items():
        centers = np.asarray(centers, dtype=np.float64).reshape(-1, 3)
        radii = np.asarray(radii, dtype=np.float64).reshape(-1)
        if len(centers) != len(radii):
            raise NdpackError(f"link {link!r} has {len(centers)} centres but {len(radii)} radii")
        if not (np.isfinite(centers).all() and np.isfinite(radii).all()):
            raise NdpackError(f"cannot write link {link!r} in cuRobo's collision spheres: every number must be finite")
        document[str(link)] = [{"center": center, "radius": radius}
                               for center, radius in zip(centers.tolist(), radii.tolist())]
    lines = [f"# {line}".rstrip() for line in (comment.splitlines() if comment else [])]
    body = yaml.safe_dump({"collision_spheres": document}, sort_keys=False, default_flow_style=None)
    return "\n".join(lines + [body])


def _curobo_packing(document: dict) -> Packing:
    links = document["collision_spheres"]
    if isinstance(links, str):
        raise ValueError(f"its collision_spheres names another file ({links!r}): load that file")
    if links is None:
        links = {}
    if not isinstance(links, dict):
        raise ValueError("its collision_spheres is not a mapping of link names to sphere lists")
    spheres = [sphere for link in links.values() for sphere in (link or [])]
    centers = np.array([sphere["center"] for sphere in spheres], dtype=np.float64).reshape(-1, 3)
    radii = np.array([sphere["radius"] for sphere in spheres], dtype=np.float64)
    keep = radii > 0  # cuRobo marks disabled spheres by a negative radius
    return _packing(None, centers[keep], radii[keep])


def _read_curobo(path: Path) -> Packing:
    text = path.read_text()
    if path.suffix.lower() in YAML_SUFFIXES:
        document = _find_collision_spheres(_load_yaml(text))
        if document is None:
            raise ValueError("it has no 'collision_spheres' mapping")
        return _curobo_packing(document)
    document = json.loads(text)
    if not isinstance(document, dict) or "collision_spheres" not in document:
        raise ValueError("it has no top-level 'collision_spheres'")
    return _curobo_packing(document)


def _find_collision_spheres(document, depth: int = 0):
    """The mapping that holds ``collision_spheres``: the document, or one nested in it (a whole
    cuRobo robot configuration keeps it under ``robot_cfg: kinematics:``); None if none does."""
    if not isinstance(document, dict) or depth > 8:
        return None
    if "collision_spheres" in document:
        return document
    for value in document.values():
        found = _find_collision_spheres(value, depth + 1)
        if found is not None:
            return found
    return None


def _load_yaml(text: str):
    """A YAML document, read with PyYAML's ``safe_load``."""
    import yaml

    try:
        return yaml.safe_load(text)
    except yaml.YAMLError as error:
        raise ValueError(f"its YAML is not valid ({' '.join(str(error).split())})") from None


# ---------------------------------------------------------------------------------- DEM codes
def _dem_box(packing: Packing) -> tuple[np.ndarray, np.ndarray, str]:
    """The data file's box, its periodic axes, and a comment on where the box came from.

    ``params["bounds"]`` and ``params["period"]`` (a periodic domain's cell and per-axis periods)
    where the packing records them; else the shape's bounds; else the spheres' extent.
    """
    bounds, periods = packing.params.get("bounds"), packing.params.get("period")
    where = "the packing's recorded bounds"
    if bounds is None and packing.shape is not None:
        bounds = np.asarray(packing.shape.bounds, dtype=np.float64)
        where = "the shape's bounds"
        if bounds.shape != (2, packing.dim) or not np.isfinite(bounds).all():
            bounds = None
    if bounds is None:
        where = "the spheres' extent (centre -+ radius)"
    box, periodic = dem_formats.data_box(packing.centers, packing.radii, bounds, periods)
    return box, periodic, f"box: {where}"


def _write_data(packing: Packing, path: Path, program: str, density) -> None:
    _require_dim(packing.dim, range(2, 4), f"a {program} data file")
    density = dem_formats.density_value(density)
    box, periodic, note = _dem_box(packing)
    dem_formats.write_data(path, packing.centers, packing.radii, box, periodic, density, program, [note])


def _write_lammps(packing: Packing, path: Path, density=1.0) -> None:
    """A LAMMPS data file for ``atom_style sphere`` (see :func:`ndpack.dem_formats.write_data`)."""
    _write_data(packing, path, "LAMMPS", density)


def _write_liggghts(packing: Packing, path: Path, density=1.0) -> None:
    """The same rows for LIGGGHTS's ``read_data`` (see :func:`ndpack.dem_formats.write_data`)."""
    _write_data(packing, path, "LIGGGHTS", density)


def _read_lammps(path: Path) -> Packing:
    centers, radii, _ = dem_formats.read_data(path)
    return _packing({"dim": centers.shape[1]}, centers, radii)


def _write_yade(packing: Packing, path: Path) -> None:
    _require_dim(packing.dim, range(3, 4), "Yade's text format (.txt)")
    dem_formats.write_yade(path, packing.centers, packing.radii)


def _read_yade(path: Path) -> Packing:
    centers, radii = dem_formats.read_yade(path)
    return _packing(None, centers, radii)


# ---------------------------------------------------------------------------------- medial axis
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
    xyz = _xyz(points)
    columns = [("x", "double", xyz[:, 0]), ("y", "double", xyz[:, 1]), ("z", "double", xyz[:, 2]),
               ("radius", "double", radii)]
    comments = ["ndpack medial-axis sample: points and their clearance", *_dimension_comment(dim)]
    comments.append("ndpack-metadata " + json.dumps(_medial_metadata(dim)))
    _write_ply_points(path, comments, columns, _encoding(encoding))


def _read_medial(path: Path) -> tuple[np.ndarray, np.ndarray]:
    if path.suffix.lower() == ".ply":
        meta, table = _read_ply_points(path)
        if meta is not None:
            _check_metadata(meta, path, "ndpack-medial")
        dim = meta["dim"] if meta else 3
        points = np.column_stack([table["x"], table["y"], table["z"]])[:, :dim]
        return points.astype(np.float64), table["radius"].astype(np.float64)
    with open(path) as file:
        first = file.readline()
        header = file.readline() if first.startswith("#") else first
    if first.startswith("#"):
        _check_metadata(json.loads(first[1:]), path, "ndpack-medial")
    columns = header.strip().split(",")
    dim = len(columns) - 1
    if dim < 1 or columns != [*(f"x{i}" for i in range(dim)), "radius"]:
        raise ValueError(f"its header is {header.strip()!r}, not x0,...,radius")
    table = np.loadtxt(path, delimiter=",", skiprows=2 if first.startswith("#") else 1, ndmin=2)
    table = table.reshape(-1, dim + 1)
    return table[:, :dim], table[:, dim]


# ---------------------------------------------------------------------------------- the table
FORMATS: dict[str, Format] = {
    fmt.name: fmt
    for fmt in (
        Format("npz", (".npz",), "any", "everything (metadata, spheres, rounds, stats, medial axis)", {},
               _write_npz, _read_npz),
        Format("csv", (".csv",), "any", "metadata, spheres, rounds", {}, _write_csv, _read_csv),
        Format("json", (".json",), "any", "everything, as plain JSON", {}, _write_json, _read_json),
        Format("ply", (".ply",), "1-3", "spheres, rounds, metadata (points with radius)",
               {"encoding": "binary|ascii"}, _write_ply, _read_ply),
        Format("vtp", (".vtp",), "1-3", "spheres, rounds, metadata (VTK points for ParaView glyphs)",
               {"encoding": "binary|ascii", "header_type": "UInt64|UInt32"}, _write_vtp, _read_vtp),
        Format("mesh", (".obj", ".stl", ".glb"), "3", "an icosphere per sphere (STL, GLB: float32)",
               {"subdivisions": "1"}, _write_mesh, _read_mesh),
        Format("sph", (".sph",), "3", "spheres, as a 2-level sphere tree", {}, _write_sph, _read_sph),
        Format("curobo", (".json", ".yml", ".yaml"), "3", "spheres, as cuRobo collision_spheres (JSON or YAML)",
               {"link": "body"}, _write_curobo, _read_curobo),
        Format("lammps", (".data",), "2-3", "spheres, density, box (LAMMPS read_data, atom_style sphere)",
               {"density": "1.0"}, _write_lammps, _read_lammps),
        Format("liggghts", (".data",), "2-3", "the lammps rows, for LIGGGHTS read_data", {"density": "1.0"},
               _write_liggghts, _read_lammps),
        Format("yade", (".txt",), "3", "spheres, as x y z r lines (Yade ymport.text)", {}, _write_yade, _read_yade),
        Format("medial", (".ply", ".csv"), "any", "the medial-axis sample (.ply: up to 3-D)",
               {"encoding": "binary|ascii"}, _write_medial, None),
    )
}

#: The format each suffix means when ``format=`` is not given.
SUFFIXES: dict[str, str] = {
    ".npz": "npz", ".csv": "csv", ".json": "json", ".ply": "ply", ".vtp": "vtp",
    ".obj": "mesh", ".stl": "mesh", ".glb": "mesh", ".sph": "sph", ".data": "lammps", ".txt": "yade",
    ".yml": "curobo", ".yaml": "curobo",
}

#: Formats that take any file name when ``format=`` names them (LAMMPS data files are often
#: named ``data.NAME``).
ANY_NAME = frozenset({"lammps", "liggghts"})
