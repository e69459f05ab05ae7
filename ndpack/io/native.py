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
import re
import warnings
from pathlib import Path

import numpy as np

from ..packing import Packing, RoundStats
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
    data = np.load(path, allow_pickle=False)
    if not isinstance(data, np.lib.npyio.NpzFile):
        raise ValueError("it is a single NumPy array (.npy), not an archive of arrays")
    with data:
        meta = check_metadata(json.loads(str(data["metadata"])), path)
        return packing_from(
            meta,
            data["centers"],
            data["radii"],
            data["rounds"],
            stats=RoundStats(data["stats_time"], data["stats_count"], data["stats_fill"]),
            medial_axis=data["medial_axis"],
            medial_radii=data["medial_radii"],
        )


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
    meta = check_metadata(json.loads(first[2:]), path)
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

    document = json.loads(path.read_text())
    if isinstance(document, dict) and "collision_spheres" in document and "format" not in document:
        return curobo_packing(document)
    meta = check_metadata(document, path)
    dim = meta["dim"]
    stats = document["stats"]
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
