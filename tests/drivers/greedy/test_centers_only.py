"""Centres only: spheres whose centres lie inside, reaching past the walls by at most their radius."""

import numpy as np
import pytest

import ndpack as nd
from ndpack.drivers.sizes import SizeDistribution

CYLINDER = nd.Cylinder([0.0, 0.0, 0.0], [0.0, 0.0, 1.0], 0.5) & nd.Slab([0.0, 0.0, 1.0], 0.0, 1.0)


def disjoint(packing):
    centers, radii = packing.centers, packing.radii
    gaps = np.linalg.norm(centers[:, None] - centers[None], axis=2) - radii[:, None] - radii[None]
    np.fill_diagonal(gaps, np.inf)
    return gaps.min() > 0


@pytest.mark.parametrize("backend", ["numpy", "numba"])
def test_centers_inside_and_spheres_through_the_walls(backend):
    radius = 0.06
    packing = nd.pack(CYLINDER, n=150, mode="fast", min_radius=radius, max_radius=radius, centers_only=True,
                      backend=backend, on_invalid="raise")
    depth = CYLINDER.distance(packing.centers)
    assert len(packing) == 150 and packing.stop_reason == "count"
    assert np.all(depth < 0) and disjoint(packing)
    assert np.any(depth + packing.radii > 1e-3)  # some reach through the walls, as the option allows
    assert packing.params["centers_only"] is True
    report = packing.verify()
    assert report.ok and report.centers_only and "centres only" in report.summary()
    # Checked as whole spheres, the same packing pokes out.
    assert not nd.verify(packing, centers_only=False).ok


def test_centers_only_packs_more_equal_spheres_than_walls():
    options = dict(n=100_000, mode="fast", min_radius=0.04, max_radius=0.04, backend="numba")
    walls = nd.pack(CYLINDER, **options)
    centers = nd.pack(CYLINDER, centers_only=True, **options)
    assert walls.stop_reason == centers.stop_reason == "min_radius"
    assert len(centers) > 1.1 * len(walls)


def test_a_distribution_by_centre_keeps_its_shares():
    bimodal = SizeDistribution.discrete([0.04, 0.015], [0.6, 0.4], by="mass")
    packing = nd.pack_sizes(CYLINDER, bimodal, n=3000, centers_only=True, backend="numba")
    report = bimodal.report(packing)
    assert len(packing) == 3000 and packing.params["unplaced"] == 0
    assert np.all(CYLINDER.distance(packing.centers) < 0) and packing.verify().ok
    assert report.ks <= 0.05
    for size in report.classes:
        assert abs(size.volume_share - size.target) <= 0.05 * size.target, report


def test_centers_only_needs_a_largest_radius():
    with pytest.raises(nd.ParameterError, match="needs max_radius"):
        nd.pack(CYLINDER, n=10, centers_only=True)
    with pytest.raises(nd.ParameterError, match="periodic"):
        nd.pack(nd.Periodic(nd.Box([0, 0], [1, 1])), n=10, max_radius=0.1, centers_only=True)
