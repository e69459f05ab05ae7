"""verify(): finds every poke-out and overlap, misses none, flags nothing valid."""

import numpy as np
import pytest

import ndpack as nd
from ndpack.verify import overlapping_pairs


def brute_force_overlaps(centers, radii, tol=0.0):
    gaps = np.linalg.norm(centers[:, None] - centers[None], axis=2)
    overlap = radii[:, None] + radii[None] - gaps
    i, j = np.nonzero(np.triu(overlap > tol, k=1))
    return set(zip(i.tolist(), j.tolist()))


@pytest.mark.parametrize("dim", [2, 3, 6])
def test_overlaps_match_brute_force_with_radii_over_orders_of_magnitude(dim):
    rng = np.random.default_rng(dim)
    centers = rng.random((600, dim))
    radii = 10 ** rng.uniform(-4, -0.5, 600)  # 0.0001 .. 0.3
    pairs, worst = overlapping_pairs(centers, radii)
    assert set(map(tuple, pairs.tolist())) == brute_force_overlaps(centers, radii)
    gaps = np.linalg.norm(centers[:, None] - centers[None], axis=2)
    overlap = radii[:, None] + radii[None] - gaps
    np.fill_diagonal(overlap, -np.inf)
    assert worst == pytest.approx(overlap.max())


def test_verify_reports_the_worst_violations():
    box = nd.Box([0, 0], [1, 1])
    centers = np.array([[0.5, 0.5], [0.2, 0.2], [0.95, 0.5], [0.7, 0.7]])
    radii = np.array([0.2, 0.1, 0.1, 0.1])  # #2 pokes out by 0.05; #0 and #3 overlap by ~0.017
    report = nd.verify(centers, box, radii=radii)
    assert not report.ok and not bool(report)
    np.testing.assert_array_equal(report.outside, [2])
    np.testing.assert_array_equal(report.overlapping, [[0, 3]])
    assert report.worst_containment == pytest.approx(0.05)
    assert report.worst_overlap == pytest.approx(0.3 - np.sqrt(0.08))
    assert "INVALID" in report.summary()
    with pytest.raises(nd.NdpackError, match="invalid"):
        report.raise_if_invalid()


def test_touching_spheres_pass_within_tolerance_only():
    box = nd.Box([0, 0], [2, 1])
    centers, radii = np.array([[0.5, 0.5], [1.5, 0.5]]), np.array([0.5, 0.5])
    assert nd.verify(centers, box, radii=radii).ok  # touching exactly, and touching the walls
    assert not nd.verify(centers, box, radii=radii + 1e-9).ok
    assert nd.verify(centers, box, radii=radii + 1e-9, tol=1e-8).ok


def test_verify_rejects_malformed_input():
    box = nd.Box([0, 0], [1, 1])
    with pytest.raises(nd.DimensionError):
        nd.verify(np.zeros((2, 3)), box, radii=[0.1, 0.1])
    with pytest.raises(nd.DimensionError, match="expected 2 radii"):
        nd.verify(np.full((2, 2), 0.5), box, radii=[0.1])
    with pytest.raises(nd.NdpackError, match="not positive"):
        nd.verify(np.full((1, 2), 0.5), box, radii=[np.nan])
