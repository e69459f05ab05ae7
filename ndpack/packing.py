"""The result of a packing run, and its files (``.npz`` with metadata, ``.csv``).

Spheres are stored in insertion order: row ``i`` is the ``i``-th sphere the driver placed.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from .errors import NdpackError
from .oracle import ball_volume

#: Bumped when the file layout changes; load() refuses files from the future.
FORMAT_VERSION = 1


@dataclass
class RoundStats:
    """Per-round statistics of the driver, one entry per round.

    Attributes
    ----------
    time : (r,) float64
        Seconds since the start of the run (prototype placement included) at the end of the round.
    count : (r,) int64
        Spheres packed after the round.
    fill : (r,) float64
        Fill fraction after the round.
    """

    time: np.ndarray
    count: np.ndarray
    fill: np.ndarray

    @classmethod
    def empty(cls) -> RoundStats:
        return cls(np.zeros(0), np.zeros(0, dtype=np.int64), np.zeros(0))


@dataclass
class Packing:
    """Spheres packed into a shape.

    Attributes
    ----------
    centers : (n, d) float64
    radii : (n,) float64
    rounds : (n,) int64
        The round in which each sphere was inserted (rows are in insertion order).
    volume : float
        Volume of the shape used for the fill fraction.
    volume_error : float
        Its standard error (0 when exact).
    stats : RoundStats
        Time, count and fill after every round.
    medial_axis : (m, d) float64
        The first round's converged prototypes: a sample of the medial axis.
    medial_radii : (m,) float64
        Their clearances (the radii of the maximal balls there).
    params : dict
        The parameters of the run.
    stop_reason : str
        Why the run stopped: ``count``, ``fill``, ``time``, ``min_radius``, ``no_room`` or
        ``interrupted``.
    shape : Oracle or None
        The packed shape (not saved to files).
    """

    centers: np.ndarray
    radii: np.ndarray
    rounds: np.ndarray
    volume: float
    volume_error: float = 0.0
    stats: RoundStats = field(default_factory=RoundStats.empty)
    medial_axis: np.ndarray | None = None
    medial_radii: np.ndarray | None = None
    params: dict = field(default_factory=dict)
    stop_reason: str = ""
    shape: object = field(default=None, repr=False, compare=False)

    # ------------------------------------------------------------------ derived values
    @property
    def dim(self) -> int:
        return self.centers.shape[1]

    def __len__(self) -> int:
        return len(self.radii)

    @property
    def covered_volume(self) -> float:
        """Sum of the spheres' volumes (exact d-ball volume)."""
        return float(ball_volume(self.dim, self.radii).sum())

    @property
    def fill(self) -> float:
        """Fraction of the shape's volume covered by the spheres."""
        return self.covered_volume / self.volume

    @property
    def fill_error(self) -> float:
        """Standard error of :attr:`fill` from the volume estimate (0 when the volume is exact)."""
        return self.fill * self.volume_error / self.volume

    def verify(self, shape=None, tol: float | None = None):
        """Check validity in float64; see :func:`ndpack.verify`."""
        from .verify import verify

        return verify(self, shape, tol)

    def plot(self, shape=None, ax=None, axes=(0, 1), at=None):
        """Draw the packing (2-D) or a slice of it; see :func:`ndpack.plot.plot`."""
        from .plot import plot

        return plot(self, shape, ax=ax, axes=axes, at=at)

    def replace_spheres(self, centers, radii, rounds) -> Packing:
        """A copy with other spheres and everything else kept."""
        return replace(self, centers=centers, radii=radii, rounds=rounds)

    def summary(self) -> str:
        """One line: count, fill, time and why it stopped."""
        seconds = float(self.stats.time[-1]) if len(self.stats.time) else 0.0
        fill = f"{self.fill:.4f}" + (f" +- {self.fill_error:.4f}" if self.volume_error else "")
        smallest = f"{self.radii.min():.4g}" if len(self) else "-"
        return (
            f"{len(self)} spheres in {self.dim}-D, fill {fill}, smallest radius {smallest}, "
            f"{seconds:.2f} s, stopped by {self.stop_reason or '-'}"
        )

    def __repr__(self) -> str:
        return f"<Packing {self.summary()}>"

    # ------------------------------------------------------------------ files
    def _metadata(self) -> dict:
        return {
            "format": "ndpack-packing",
            "version": FORMAT_VERSION,
            "dim": self.dim,
            "volume": self.volume,
            "volume_error": self.volume_error,
            "params": self.params,
            "stop_reason": self.stop_reason,
            "shape": repr(self.shape) if self.shape is not None else None,
        }

    def save(self, path) -> Path:
        """Write to ``.npz`` (everything) or ``.csv`` (spheres and metadata); returns the path."""
        path = Path(path)
        suffix = path.suffix.lower()
        if suffix == ".npz":
            np.savez_compressed(
                path,
                centers=self.centers,
                radii=self.radii,
                rounds=self.rounds,
                stats_time=self.stats.time,
                stats_count=self.stats.count,
                stats_fill=self.stats.fill,
                medial_axis=self._or_empty(self.medial_axis),
                medial_radii=self._or_empty(self.medial_radii, 1),
                metadata=np.array(json.dumps(self._metadata())),
            )
        elif suffix == ".csv":
            header = ",".join([*(f"x{i}" for i in range(self.dim)), "radius", "round"])
            table = np.column_stack([self.centers, self.radii, self.rounds])
            formats = ["%.17g"] * (self.dim + 1) + ["%d"]
            comment = "# " + json.dumps(self._metadata())
            np.savetxt(path, table, delimiter=",", fmt=formats, header=f"{comment}\n{header}", comments="")
        else:
            raise NdpackError(f"cannot save to {path.name!r}: use a .npz or .csv file name")
        return path

    def _or_empty(self, array, ndim=2):
        if array is not None:
            return array
        return np.zeros((0, self.dim)) if ndim == 2 else np.zeros(0)

    @classmethod
    def load(cls, path) -> Packing:
        """Read a packing written by :meth:`save` (``.npz`` or ``.csv``)."""
        path = Path(path)
        if not path.exists():
            raise NdpackError(f"no such packing file: {path}")
        suffix = path.suffix.lower()
        try:
            if suffix == ".npz":
                with np.load(path, allow_pickle=False) as data:
                    metadata = _check_metadata(json.loads(str(data["metadata"])), path)
                    return cls(
                        centers=data["centers"],
                        radii=data["radii"],
                        rounds=data["rounds"],
                        volume=metadata["volume"],
                        volume_error=metadata["volume_error"],
                        stats=RoundStats(data["stats_time"], data["stats_count"], data["stats_fill"]),
                        medial_axis=data["medial_axis"],
                        medial_radii=data["medial_radii"],
                        params=metadata["params"],
                        stop_reason=metadata["stop_reason"],
                    )
            if suffix == ".csv":
                with open(path) as file:
                    first = file.readline()
                if not first.startswith("# {"):
                    raise ValueError("the first line is not ndpack's metadata comment")
                metadata = _check_metadata(json.loads(first[2:]), path)
                table = np.loadtxt(path, delimiter=",", skiprows=2, ndmin=2)
                dim = metadata["dim"]
                if table.size == 0:
                    table = np.zeros((0, dim + 2))
                return cls(
                    centers=table[:, :dim],
                    radii=table[:, dim],
                    rounds=table[:, dim + 1].astype(np.int64),
                    volume=metadata["volume"],
                    volume_error=metadata["volume_error"],
                    params=metadata["params"],
                    stop_reason=metadata["stop_reason"],
                )
        except (KeyError, ValueError, OSError) as error:
            raise NdpackError(f"{path} is not a readable ndpack packing: {error}") from error
        raise NdpackError(f"cannot load {path.name!r}: use a .npz or .csv file written by ndpack")


def _check_metadata(metadata: dict, path: Path) -> dict:
    if metadata.get("format") != "ndpack-packing":
        raise ValueError("it has no ndpack metadata")
    if metadata.get("version", 0) > FORMAT_VERSION:
        raise NdpackError(
            f"{path} was written by a newer ndpack (format {metadata['version']}); upgrade ndpack"
        )
    return metadata
