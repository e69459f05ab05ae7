"""What the formats share about packings: the JSON metadata of native files, its check on
reading, and the :class:`~ndpack.packing.Packing` rebuilt from a file's arrays.

Files that hold only spheres (PLY without metadata, meshes, ``.sph``, cuRobo, DEM files) load
as a Packing whose volume is unknown (NaN, so its fill is NaN), whose rounds are 0, and whose
params are empty.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ..errors import NdpackError
from ..packing import FORMAT_VERSION, Packing

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
    or ``"ndpack-medial"``) and not from a newer ndpack; raises otherwise."""
    if not isinstance(metadata, dict) or metadata.get("format") not in ("ndpack-packing", "ndpack-medial"):
        raise ValueError("it has no ndpack metadata")
    if metadata["format"] != kind:
        if kind == "ndpack-packing":
            raise NdpackError(
                f"{path} holds a medial-axis sample, not a packing: read it with ndpack.io.load_medial"
            )
        raise NdpackError(f"{path} holds a packing, not a medial-axis sample: read it with ndpack.Packing.load")
    newest = FORMAT_VERSION if kind == "ndpack-packing" else MEDIAL_VERSION
    if metadata.get("version", 0) > newest:
        raise NdpackError(f"{path} was written by a newer ndpack (format {metadata['version']}); upgrade ndpack")
    return metadata


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


def xyz(points: np.ndarray) -> np.ndarray:
    """``(n, d)`` points with ``d <= 3`` as ``(n, 3)`` float64, the missing coordinates 0 (for the
    formats that store 3 coordinates: PLY, VTP)."""
    out = np.zeros((len(points), 3))
    out[:, : points.shape[1]] = points
    return out

