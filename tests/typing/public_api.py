"""Typed use of the public API, checked by mypy in CI (``python -m mypy``, configured in
pyproject.toml): what a user's annotated code does with ``import ndpack as nd`` must type-check
against ndpack's own annotations. Not a test pytest runs: mypy reads it, nothing calls it."""

from __future__ import annotations

import numpy as np

import ndpack as nd


def pack_and_check() -> float:
    part: nd.Oracle = nd.Box([0, 0, 0], [1, 1, 1]) - nd.Ball([1, 1, 1], 0.6)
    moved: nd.Oracle = (part | nd.Capsule([0, 0, 0], [1, 1, 0], 0.2)).translate([1, 0, 0]).rotate(np.eye(3))
    packing: nd.Packing = nd.pack(moved, n=100, seed=0, mode="fast")
    report: nd.Verification = packing.verify()
    strict: nd.Verification = nd.verify(packing, moved, kind="packing")
    centers: np.ndarray = packing.centers
    radii: np.ndarray = packing.radii
    assert report.ok and strict.ok and len(centers) == len(radii)
    path = packing.save("part.npz")
    again: nd.Packing = nd.Packing.load(path)
    return again.fill


def sizes_and_covers() -> int:
    cell = nd.Periodic(nd.Box([0, 0, 0], [1, 1, 1]))
    bed: nd.Packing = nd.pack_sizes(cell, nd.SizeDistribution.discrete([0.05, 0.02], [0.5, 0.5]), n=50)
    report: nd.SizeReport = nd.SizeDistribution.lognormal(0.03, 0.25).report(bed)
    covering: nd.Covering = nd.cover(nd.Ball([0, 0, 0], 1.0), n=8)
    spheres: nd.Packing = covering.as_packing()
    return len(spheres) + len(report.classes)


def plug_in() -> nd.Function:
    @nd.plugin(dim=2, bounds=([-1, -1], [1, 1]))
    def disc(points: np.ndarray) -> np.ndarray:
        return np.linalg.norm(points, axis=1) - 1.0

    return disc
