"""ndpack's own formats, which keep any dimension and read back every bit of the spheres.

========  ========  ===============================================================
name      suffix    what is kept
========  ========  ===============================================================
npz       .npz      everything: metadata, spheres, rounds, round stats, medial axis
csv       .csv      metadata (a first ``# {...}`` comment line), spheres and rounds
json      .json     everything, as plain JSON (a cuRobo ``collision_spheres`` document
                    in a ``.json`` file is told apart by its content)
========  ========  ===============================================================
"""

from __future__ import annotations

import json
import math
import re
import warnings
import zipfile
from pathlib import Path

import numpy as np

from ..packing import Packing, RoundStats
from . import limits
from .limits import parse_json, shown
from .metadata import check_metadata, metadata, packing_from
from .registry import Format, register


def _or_empty(array, shape):
    return np.zeros(shape) if array is None else array


# ---------------------------------------------------------------------------------- npz
def _write_npz(packing: Packing, path: Path) -> None:
    """Arrays ``centers`` (n, d), ``radii`` (n,), ``rounds`` (n,), ``stats_time``, ``stats_count``,
    ``stats_fill`` (rounds,), ``medial_axis`` (m, d), ``medial_radii`` (m,) and ``metadata`` (JSON
    text), compressed."""
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
    """A packing from a ``.npz`` archive, read member by member: every header and size is checked
    (:func:`_npz_arrays`) before an array is allocated or a byte of it inflated."""
    with open(path, "rb") as file:
        if file.read(6) == b"\x93NUMPY":  # np.load would read a .npy whole, whatever its header says
            raise ValueError("it is a single NumPy array (.npy), not an archive of arrays")
    data = np.load(path, allow_pickle=False)  # an archive opens lazily: its directory only
    if not isinstance(data, np.lib.npyio.NpzFile):
        raise ValueError("it is a single NumPy array (.npy), not an archive of arrays")
    with data:
        arrays, meta = _npz_arrays(data.zip, path)
    return packing_from(
        meta,
        arrays["centers"],
        arrays["radii"],
        arrays["rounds"],
        stats=RoundStats(arrays["stats_time"], arrays["stats_count"], arrays["stats_fill"]),
        medial_axis=arrays["medial_axis"],
        medial_radii=arrays["medial_radii"],
    )


#: The arrays of an ndpack archive, metadata first.
NPZ_ARRAYS = ("metadata", "centers", "radii", "rounds", "stats_time", "stats_count", "stats_fill", "medial_axis",
              "medial_radii")


def _npz_arrays(archive: zipfile.ZipFile, path: Path) -> tuple[dict, dict]:
    """The archive's arrays and checked metadata.

    Checked before anything is inflated: that the members together unpack to no more than
    :data:`~ndpack.io.limits.NPZ_MAX_RATIO` times the file (or
    :data:`~ndpack.io.limits.NPZ_FREE_BYTES`). Then, from the headers alone (a few hundred bytes
    each): that each member's size is its header's shape and type, the types are numbers or text
    (never pickled objects), and the shapes agree with each other and the metadata's dimension.
    Each array is then read into an array of its declared size from a stream that the member's
    declared size caps.
    """
    members = {name: archive.getinfo(f"{name}.npy") for name in NPZ_ARRAYS if f"{name}.npy" in archive.namelist()}
    missing = [name for name in NPZ_ARRAYS if name not in members]
    if missing:
        raise KeyError(missing[0])
    size = path.stat().st_size
    total = sum(member.file_size for member in members.values())
    if total > max(limits.NPZ_FREE_BYTES, limits.NPZ_MAX_RATIO * size):
        raise ValueError(
            f"it would unpack to {total:,} bytes, {total / max(size, 1):,.0f} times its {size:,} on disk: ndpack "
            f"refuses archives that unpack to more than {limits.NPZ_MAX_RATIO} times their size beyond "
            f"{limits.NPZ_FREE_BYTES >> 20} MiB, as zip bombs do (ndpack.io.limits.NPZ_MAX_RATIO)"
        )
    with archive.open(members["metadata"]) as stream:
        text = _npy_read(stream, _npy_header(stream, "metadata", members["metadata"]))
    meta = check_metadata(parse_json(str(text)), path)
    dim = meta["dim"]
    headers = {}
    for name in NPZ_ARRAYS[1:]:
        with archive.open(members[name]) as stream:
            headers[name] = _npy_header(stream, name, members[name])
    counts = {name: math.prod(header[0]) for name, header in headers.items()}
    for name in ("centers", "medial_axis"):
        if counts[name] % dim:
            raise ValueError(f"its {name} hold {counts[name]:,} numbers, not rows of {dim} (its dimension)")
    spheres = (counts["centers"] // dim, counts["radii"], counts["rounds"])
    if len(set(spheres)) > 1:
        raise ValueError("it has {:,} centres, {:,} radii and {:,} rounds".format(*spheres))
    if counts["medial_axis"] // dim != counts["medial_radii"]:
        raise ValueError(f"it has {counts['medial_axis'] // dim:,} medial-axis points and "
                         f"{counts['medial_radii']:,} medial radii")
    arrays = {}
    for name, header in headers.items():
        with archive.open(members[name]) as stream:
            _npy_header(stream, name, members[name])
            arrays[name] = _npy_read(stream, header)
    return arrays, meta


def _npy_header(stream, name: str, member: zipfile.ZipInfo) -> tuple:
    """``(shape, fortran_order, dtype)`` of a ``.npy`` member, checked against the member's size
    (which caps the stream) before its data is read."""
    version = np.lib.format.read_magic(stream)
    if version == (1, 0):
        shape, fortran_order, dtype = np.lib.format.read_array_header_1_0(stream)
    elif version == (2, 0):
        shape, fortran_order, dtype = np.lib.format.read_array_header_2_0(stream)
    else:
        raise ValueError(f"its {name}.npy is of .npy version {version}, which ndpack does not read")
    if dtype.hasobject:  # numpy's advice would be to allow pickles: ndpack never loads them
        raise ValueError("it holds arrays of Python objects (pickled), which ndpack never loads")
    if dtype.kind not in "biufU" or dtype.itemsize == 0:
        raise ValueError(f"its {name}.npy holds {dtype}, not numbers")
    data = member.file_size - stream.tell()
    declared = math.prod(shape) * dtype.itemsize
    if declared != data:
        raise ValueError(f"its {name}.npy declares {'x'.join(map(str, shape)) or 'one'} {dtype} ({declared:,} "
                         f"bytes), but holds {data:,} bytes")
    return shape, fortran_order, dtype


def _npy_read(stream, header: tuple) -> np.ndarray:
    """The data after a checked header: exactly the declared bytes, read into the array in pieces."""
    shape, fortran_order, dtype = header
    raw = np.empty(math.prod(shape) * dtype.itemsize, dtype=np.uint8)
    view, done = memoryview(raw), 0
    while done < len(view):
        read = stream.readinto(view[done : done + (16 << 20)])
        if not read:
            raise ValueError(f"it is truncated: an array ends after {done:,} of its {len(view):,} bytes")
        done += read
    array = raw.view(dtype)
    return array.reshape(shape[::-1]).T if fortran_order else array.reshape(shape)


# ---------------------------------------------------------------------------------- csv
def _write_csv(packing: Packing, path: Path) -> None:
    """``# {metadata}``, then ``x0,...,x{d-1},radius,round``, then a sphere a line (``%.17g``)."""
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
    meta = check_metadata(parse_json(first[2:]), path)
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
    return packing_from(meta, table[:, :dim], table[:, dim], table[:, dim + 1].astype(np.int64))


# ---------------------------------------------------------------------------------- json
def _write_json(packing: Packing, path: Path) -> None:
    """The metadata's keys, and ``centers``, ``radii``, ``rounds``, ``stats``, ``medial_axis`` and
    ``medial_radii`` as lists."""
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
    """A packing written in this format, or the spheres of a cuRobo JSON document."""
    from .curobo import curobo_packing  # here: importing it registers curobo, which comes after json

    document = parse_json(path.read_text())
    if isinstance(document, dict) and "collision_spheres" in document and "format" not in document:
        return curobo_packing(document)
    meta = check_metadata(document, path)
    dim = meta["dim"]
    stats = document["stats"]
    if not isinstance(stats, dict):
        raise ValueError(f"its stats {shown(stats)} is not a mapping of time, count and fill")
    return packing_from(
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


register(Format("npz", (".npz",), "any", "everything (metadata, spheres, rounds, stats, medial axis)", {},
                _write_npz, _read_npz), default_for=(".npz",))
register(Format("csv", (".csv",), "any", "metadata, spheres, rounds", {}, _write_csv, _read_csv),
         default_for=(".csv",))
register(Format("json", (".json",), "any", "everything, as plain JSON", {}, _write_json, _read_json),
         default_for=(".json",))
