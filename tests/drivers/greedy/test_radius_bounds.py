"""Radius bounds: ``min_radius`` and ``max_radius`` as constraints of the greedy driver."""

import numpy as np
import pytest

import ndpack as nd
from ndpack import cli

PART = nd.Box([0.0, 0.0, 0.0], [1.0, 1.0, 1.0]) - nd.Ball([1.0, 1.0, 1.0], 0.5)


def gaps(packing, shape):
    """Each sphere's gap (k,) to its nearest obstacle: the shape's boundary or another sphere."""
    centers, radii = packing.centers, packing.radii
    between = np.linalg.norm(centers[:, None] - centers[None], axis=2) - radii[:, None] - radii[None]
    np.fill_diagonal(between, np.inf)
    return np.minimum(between.min(axis=1), -shape.distance(centers) - radii)


@pytest.mark.parametrize("mode", ["fast", "faithful"])
@pytest.mark.parametrize("backend", ["numpy", "numba"])
def test_radii_stay_within_the_bounds(mode, backend):
    low, high = 0.02, 0.06
    packing = nd.pack(PART, n=250 if mode == "fast" else 60, min_radius=low, max_radius=high, mode=mode,
                      backend=backend, seed=1, on_invalid="raise")
    assert packing.radii.min() >= low and packing.radii.max() <= high
    # The box takes many spheres larger than the cap: most are capped, and each capped one
    # was moved to touch its nearest obstacle (the margin, 1e-10, apart; a little more where
    # the move went along a crease of the shape's distance, in steps).
    capped = packing.radii == high
    assert capped.mean() > 0.5
    assert np.abs(gaps(packing, PART)[capped]).max() < 1e-4 * high
    assert packing.params["min_radius"] == low and packing.params["max_radius"] == high
    assert packing.verify(PART).ok


def test_without_a_cap_nothing_changes():
    shape = nd.Box([0.0, 0.0], [1.0, 1.0]) - nd.Ball([0.3, 0.4], 0.2)
    free = nd.pack(shape, n=80, mode="fast", backend="numba", seed=2)
    loose = nd.pack(shape, n=80, mode="fast", backend="numba", seed=2, max_radius=10.0)
    np.testing.assert_array_equal(free.centers, loose.centers)
    np.testing.assert_array_equal(free.radii, loose.radii)
    assert free.params["max_radius"] is None and loose.params["max_radius"] == 10.0


@pytest.mark.parametrize("backend", ["numpy", "numba"])
def test_equal_spheres_fill_more_than_random_sequential_addition(backend):
    """``min_radius == max_radius``: equal spheres until none fits. Random sequential addition
    saturates at 0.547 in the plane (without the walls, which only lower it): a driver that
    seeks the gaps must do better."""
    radius = 0.03
    square = nd.Box([0.0, 0.0], [1.0, 1.0])
    packing = nd.pack(square, n=10_000, min_radius=radius, max_radius=radius, mode="fast", backend=backend,
                      on_invalid="raise")
    assert packing.stop_reason == "min_radius"
    assert np.all(packing.radii == radius)
    assert packing.fill > 0.6, packing.fill
    # Saturated: no prototype found room for one more, and every sphere touches something.
    assert gaps(packing, square).max() < 1e-4 * radius
    assert packing.verify(square).ok


def test_equal_spheres_on_both_backends_fill_alike():
    box = nd.Box([0.0, 0.0, 0.0], [1.0, 1.0, 1.0])
    fills = [nd.pack(box, n=10_000, min_radius=0.06, max_radius=0.06, mode="fast", backend=name).fill
             for name in ("numpy", "numba")]
    # Equal spheres tie everywhere: the last bits of the clearances order them, so the two
    # packings part early, but they fill the box alike (beyond random addition's 0.38).
    assert abs(fills[0] / fills[1] - 1) < 0.05, fills
    assert min(fills) > 0.35, fills


@pytest.mark.parametrize(
    "kwargs, message",
    [
        (dict(max_radius=0.0), "max_radius must be a positive number"),
        (dict(max_radius=-1.0), "max_radius must be a positive number"),
        (dict(max_radius=True), "max_radius must be a positive number"),
        (dict(max_radius="big"), "max_radius must be a positive number"),
        (dict(max_radius=float("nan")), "max_radius must be a positive number"),
        (dict(min_radius=0.2, max_radius=0.1), r"max_radius \(0.1\) is below min_radius \(0.2\)"),
    ],
)
def test_impossible_bounds_are_refused(kwargs, message):
    with pytest.raises(nd.ParameterError, match=message):
        nd.pack(nd.Box([0, 0], [1, 1]), **kwargs)


def test_the_command_line_takes_the_bounds(tmp_path, capsys):
    out = tmp_path / "beads.npz"
    status = cli.main(["pack", "square", "-n", "5000", "--mode", "fast", "--min-radius", "0.05",
                       "--max-radius", "0.05", "--backend", "numba", "-q", "-o", str(out)])
    assert status == 0, capsys.readouterr().err
    packing = nd.Packing.load(out)
    assert np.all(packing.radii == 0.05) and packing.stop_reason == "min_radius"
