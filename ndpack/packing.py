"""The result of a packing run; its files are written and read by :mod:`ndpack.io`.

Spheres are stored in insertion order: row ``i`` is the ``i``-th sphere the driver placed.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from .oracle import Oracle, ball_volume
from .verify import Verification, verify

#: Bumped when the file layout changes; load() refuses files from the future.
FORMAT_VERSION = 1

#: What saves, loads and draws a packing: ``"save"``, ``"load"`` (:mod:`ndpack.io`) and ``"plot"``
#: (:mod:`ndpack.pictures`), registered by those packages when they are imported (``import
#: ndpack`` imports both). They build on this module, so it imports neither: a registry, as
#: trimesh's exchange registers its formats.
SERVICES: dict = {}


def service(name: str):
    """The function registered as ``name`` in :data:`SERVICES`."""
    try:
        return SERVICES[name]
    except KeyError:  # only where the package's __init__ did not run, which Python never skips
        raise RuntimeError(f"no {name}() is registered: import ndpack first") from None


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
        The parameters of the run; ``holes`` (``"cap"`` or ``"refuse"``) where the shape holds a
        mesh whose holes were capped or refused (:attr:`~ndpack.TriangleMesh.hole_option`), and
        ``source`` where ``ndpack pack`` made it.
    stop_reason : str
        Why the run stopped: ``count``, ``fill``, ``time``, ``min_radius``, ``no_room`` or
        ``interrupted``.
    repair : dict or None
        None for a packing that passed the driver's final float64 check as made. Otherwise
        what that check repaired (``pack(..., on_invalid="repair")``): the counts of spheres
        ``outside`` and ``overlapping_pairs`` it found, how many were ``shrunk`` and
        ``dropped``, the ``worst_poke_out`` and ``worst_overlap`` before the repair, and the
        likely ``cause``; where a plug-in's distance was steeper than a distance across some
        spheres (dropped), also their count ``steep`` and the ``worst_slope`` found.
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
    repair: dict | None = None
    shape: Oracle | None = field(default=None, repr=False, compare=False)

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

    def verify(self, shape=None, tol: float | None = None, independent: bool = False) -> Verification:
        """Check validity in float64; see :func:`ndpack.verify`."""
        return verify(self, shape, tol, independent=independent)

    def plot(self, shape=None, ax=None, axes=None, at=None, up="auto") -> Any:
        """Draw the packing (2-D) or a slice of it; see :func:`ndpack.pictures.plot`."""
        return service("plot")(self, shape, ax=ax, axes=axes, at=at, up=up)

    def replace_spheres(self, centers, radii, rounds) -> Packing:
        """A copy with other spheres and everything else kept."""
        return replace(self, centers=centers, radii=radii, rounds=rounds)

    def summary(self) -> str:
        """One line: count, fill, time and why it stopped."""
        seconds = float(self.stats.time[-1]) if len(self.stats.time) else 0.0
        fill = f"{self.fill:.4f}" + (f" +- {self.fill_error:.4f}" if self.volume_error else "")
        smallest = f"{self.radii.min():.4g}" if len(self) else "-"
        repaired = f", REPAIRED: {repair_summary(self.repair)}" if self.repair else ""
        return (
            f"{len(self)} spheres in {self.dim}-D, fill {fill}, smallest radius {smallest}, "
            f"{seconds:.2f} s, stopped by {self.stop_reason or '-'}{repaired}"
        )

    def __repr__(self) -> str:
        return f"<Packing {self.summary()}>"

    # ------------------------------------------------------------------ files
    def save(self, path, format: str | None = None, **options) -> Path:
        """Write to a file in the format of its suffix, or the one named; returns the path.

        ``.npz`` keeps everything, ``.csv`` the spheres and metadata, ``.json`` everything; the
        others (``.ply``, ``.vtp``, ``.obj``/``.stl``/``.glb``, ``.sph``, ``format="curobo"``,
        ``format="medial"``) and their ``options`` are listed by :func:`ndpack.io.table`.
        """
        return service("save")(self, path, format, **options)

    @classmethod
    def load(cls, path, format: str | None = None) -> Packing:
        """Read a packing written by :meth:`save` (any format but ``medial``)."""
        return service("load")(path, format)


def repair_summary(repair: dict) -> str:
    """One line on what the final check repaired (see :attr:`Packing.repair`)."""
    def worst(key):
        value = repair.get(key)
        return "-" if value is None else f"{value:.3g}"

    steep = (f", {repair['steep']} where the distance rose faster than a distance (slope at least "
             f"{worst('worst_slope')})" if repair.get("steep") else "")
    # .get: a record may hold only some counts (an obstacle repair), or come from a file.
    return (f"{repair.get('shrunk', 0)} sphere(s) shrunk and {repair.get('dropped', 0)} dropped after "
            f"{repair.get('outside', 0)} poked out (worst {worst('worst_poke_out')}), "
            f"{repair.get('overlapping_pairs', 0)} pair(s) overlapped (worst {worst('worst_overlap')}){steep}: "
            f"{repair.get('cause', 'cause not recorded')}")
