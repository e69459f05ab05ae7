"""What the formats share about packings: the JSON metadata of native files, its check on
reading, and the :class:`~ndpack.packing.Packing` rebuilt from a file's arrays.

Files that hold only spheres (PLY without metadata, meshes, ``.sph``, cuRobo, DEM files) load
as a Packing whose volume is unknown (NaN, so its fill is NaN), whose rounds are 0, and whose
params are empty (a LAMMPS file's periodic box aside). A file's metadata is checked for the types
ndpack writes (:func:`check_metadata`): a file may come from anyone.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ..errors import NdpackError
from ..packing import FORMAT_VERSION, Packing, RoundStats
from .limits import check_dim, check_nesting, shown

#: Version of the medial-axis sample's small metadata (its own layout, apart from packings').
MEDIAL_VERSION = 1


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


def check_metadata(metadata: dict, path: Path, kind: str = "ndpack-packing") -> dict:
    """``metadata`` read from ``path``, if it is ndpack's of this ``kind`` (``"ndpack-packing"``
    or ``"ndpack-medial"``), not from a newer ndpack, and of the types ndpack writes (a file may
    hold anything: a dimension of a billion, ``"params": "x"``); raises otherwise."""
    if not isinstance(metadata, dict) or metadata.get("format") not in ("ndpack-packing", "ndpack-medial"):
        raise ValueError("it has no ndpack metadata")
    if metadata["format"] != kind:
        if kind == "ndpack-packing":
            raise NdpackError(
                f"{path} holds a medial-axis sample, not a packing: read it with ndpack.io.load_medial"
            )
        raise NdpackError(f"{path} holds a packing, not a medial-axis sample: read it with ndpack.Packing.load")
    version = metadata.get("version", 0)
    if isinstance(version, bool) or not isinstance(version, int):
        raise ValueError(f"its format version {shown(version)} is not a whole number")
    newest = FORMAT_VERSION if kind == "ndpack-packing" else MEDIAL_VERSION
    if version > newest:
        raise NdpackError(f"{path} was written by a newer ndpack (format {version}); upgrade ndpack")
    check_nesting({key: value for key, value in metadata.items() if key not in ARRAY_KEYS}, "metadata")
    if "dim" in metadata:
        check_dim(metadata["dim"])
    for key, (types, what) in _FIELDS.items():
        value = metadata.get(key)
        if value is not None and (isinstance(value, bool) or not isinstance(value, types)):
            raise ValueError(f"its {key} {shown(value)} is not {what}")
    _check_params(metadata.get("params") or {}, metadata.get("dim", 3))
    _check_repair(metadata.get("repair"))
    return metadata


#: The keys of a native file that hold arrays: NumPy checks them as it converts them.
ARRAY_KEYS = ("centers", "radii", "rounds", "stats", "medial_axis", "medial_radii")

#: The metadata's other keys: the types they may hold (None aside) and those types in words.
_FIELDS = {
    "volume": ((int, float), "a number"),
    "volume_error": ((int, float), "a number"),
    "params": (dict, "a mapping of parameter names to values"),
    "stop_reason": (str, "a word"),
    "repair": (dict, "a mapping (what the final check repaired)"),
    "shape": (str, "text (the shape's repr)"),
}

#: Parameters that ndpack reads back (verify, render, info, the DEM writers): their types.
_PARAMS = {
    "source": (str, "text (a shape spec or a mesh file)"),
    "holes": (str, "text"),
    "sign": (str, "text"),
    "centers_only": (bool, "true or false"),
    "covering": (dict, "a mapping"),
}

#: A repair record's counts, worst values and cause (see ``Packing.repair``).
_REPAIR_COUNTS = ("outside", "overlapping_pairs", "shrunk", "dropped", "steep", "obstacle_overlaps")
_REPAIR_WORST = ("worst_poke_out", "worst_overlap", "worst_slope")


def _check_params(params: dict, dim) -> None:
    """The recorded parameters that ndpack reads back have the types it writes."""
    for key, (types, what) in _PARAMS.items():
        value = params.get(key)
        if value is not None and (not isinstance(value, types) or (types is not bool and isinstance(value, bool))):
            raise ValueError(f"its params.{key} {shown(value)} is not {what}")
    period = params.get("period")
    if period is not None:
        lengths = period if isinstance(period, list) else None
        if lengths is None or len(lengths) != dim or not all(
                length is None or (_is_number(length) and math.isfinite(length) and length > 0) for length in lengths):
            raise ValueError(f"its params.period {shown(period)} is not one period (a positive number) or null "
                             f"per axis of its {dim} axes")
    bounds = params.get("bounds")
    if bounds is not None and not (isinstance(bounds, list) and len(bounds) == 2 and all(
            isinstance(corner, list) and len(corner) == dim and all(map(_is_number, corner)) for corner in bounds)):
        raise ValueError(f"its params.bounds {shown(bounds)} is not two corners of {dim} numbers")


def _check_repair(repair: dict | None) -> None:
    if repair is None:
        return
    for key in _REPAIR_COUNTS:
        value = repair.get(key)
        if value is not None and (isinstance(value, bool) or not isinstance(value, int) or value < 0):
            raise ValueError(f"its repair.{key} {shown(value)} is not a count")
    for key in _REPAIR_WORST:
        if repair.get(key) is not None and not _is_number(repair[key]):
            raise ValueError(f"its repair.{key} {shown(repair[key])} is not a number")
    if not isinstance(repair.get("cause", ""), str):
        raise ValueError(f"its repair.cause {shown(repair['cause'])} is not text")


def _is_number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def packing_from(metadata: dict | None, centers, radii, rounds=None, **extra) -> Packing:
    """A Packing from a file's arrays and (native) metadata, checked.

    Parameters
    ----------
    metadata : dict or None
        None for a file of spheres only: NaN volume, rounds 0, empty params, 3-D unless
        ``{"dim": d}`` is given.
    centers : (n, d) array_like
    radii : (n,) array_like
    rounds : (n,) array_like of int, optional
    **extra
        More Packing fields (``stats``, ``medial_axis``, ``medial_radii``).

    Raises
    ------
    ValueError
        Starting "it ...", for arrays of different lengths, radii that are not positive finite
        numbers, centres that are not finite, a bad dimension or volume.
    """
    metadata = metadata or {}
    radii = np.asarray(radii, dtype=np.float64).reshape(-1)
    dim = check_dim(metadata.get("dim", 3))
    centers = np.asarray(centers, dtype=np.float64).reshape(-1, dim)
    rounds = np.zeros(len(radii), dtype=np.int64) if rounds is None else np.asarray(rounds, dtype=np.int64).reshape(-1)
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
            raise ValueError(f"its {name} {shown(value)} is not a non-negative number")
    if volume == 0:  # the fill would divide by it
        raise ValueError("its volume 0 is not a positive number")
    if extra.get("stats") is not None:
        extra["stats"] = _stats(extra["stats"])
    for name, shape in (("medial_axis", (-1, dim)), ("medial_radii", (-1,))):
        if extra.get(name) is not None:
            extra[name] = np.asarray(extra[name], dtype=np.float64).reshape(shape)
    return Packing(
        centers=centers,
        radii=radii,
        rounds=rounds,
        volume=float("nan") if volume is None else volume,
        volume_error=0.0 if volume_error is None else volume_error,
        params=metadata.get("params") or {},
        stop_reason=metadata.get("stop_reason") or "",
        repair=metadata.get("repair"),
        **extra,
    )


def _stats(stats: RoundStats) -> RoundStats:
    """Round statistics read from a file as float64, int64 and float64 arrays of one length."""
    checked = RoundStats(np.asarray(stats.time, dtype=np.float64).reshape(-1),
                         np.asarray(stats.count, dtype=np.int64).reshape(-1),
                         np.asarray(stats.fill, dtype=np.float64).reshape(-1))
    lengths = {len(checked.time), len(checked.count), len(checked.fill)}
    if len(lengths) > 1:
        raise ValueError(f"its round statistics have {len(checked.time)} times, {len(checked.count)} counts and "
                         f"{len(checked.fill)} fills")
    return checked


def xyz(points: np.ndarray) -> np.ndarray:
    """``(n, d)`` points with ``d <= 3`` as ``(n, 3)`` float64, the missing coordinates 0 (for the
    formats that store 3 coordinates: PLY, VTP)."""
    out = np.zeros((len(points), 3))
    out[:, : points.shape[1]] = points
    return out

