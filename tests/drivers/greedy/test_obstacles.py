"""``pack(..., obstacles=)``: spheres already in place, which the new ones keep clear of.

Overlaps with the obstacles are checked by hand (all pairs, NumPy), not by ``ndpack.verify``.
"""

import numpy as np
import pytest

import ndpack as nd
from ndpack.errors import ParameterError

CUBE = nd.Box([0, 0, 0], [1, 1, 1])


def _clear_of(packing, centers, radii, periods=None):
    """The least gap between a new sphere and an obstacle (negative: they overlap)."""
    delta = packing.centers[:, None, :] - np.asarray(centers)[None, :, :]
    if periods is not None:
        delta -= periods * np.round(delta / periods)
    return (np.linalg.norm(delta, axis=2) - packing.radii[:, None] - np.asarray(radii)[None, :]).min()


def test_going_on_from_a_packing_fills_as_one_run_does():
    first = nd.pack(CUBE, n=200, seed=0, progress=False)
    more = nd.pack(CUBE, n=200, obstacles=first, seed=1, progress=False)
    assert len(more) == 200 and more.params["obstacles"] == 200
    assert _clear_of(more, first.centers, first.radii) >= 0
    assert nd.verify(more, CUBE).ok
    # The new spheres are the next ones of the greedy packing: none larger than the gaps left.
    assert more.radii.max() <= first.radii.min() * 1.2
    whole = nd.pack(CUBE, n=400, seed=0, progress=False)
    assert abs((first.fill + more.fill) / whole.fill - 1) < 0.01


def test_obstacles_may_reach_outside_the_shape_and_a_tuple_is_a_packing():
    centers, radii = np.array([[0.0, 0.5, 0.5], [1.0, 1.0, 1.0]]), np.array([0.3, 0.4])  # on a face, at a corner
    packing = nd.pack(CUBE, n=60, obstacles=(centers, radii), seed=2, progress=False)
    assert _clear_of(packing, centers, radii) >= 0 and nd.verify(packing, CUBE).ok
    given = nd.Packing(centers=centers, radii=radii, rounds=np.zeros(2, int), volume=1.0)
    same = nd.pack(CUBE, n=60, obstacles=given, seed=2, progress=False)
    np.testing.assert_array_equal(packing.centers, same.centers)


def test_a_periodic_domain_keeps_clear_of_the_obstacles_images():
    cell = nd.Periodic(nd.Box([0, 0], [1, 1]))
    centers, radii = np.array([[0.02, 0.5]]), np.array([0.15])  # its image pokes in across x = 1
    packing = nd.pack(cell, n=150, obstacles=(centers, radii), seed=0, progress=False)
    assert _clear_of(packing, centers, radii, periods=np.ones(2)) >= 0


def test_small_obstacles_in_a_periodic_domain_do_not_cap_the_new_spheres():
    # The images of a round's spheres are kept within twice its largest radius, since the greedy
    # radii only shrink; obstacles say nothing of the radii to come.
    cell = nd.Periodic(nd.Box([0, 0], [1, 1]))
    packing = nd.pack(cell, n=5, obstacles=([[0.5, 0.5]], [0.01]), seed=0, progress=False)
    assert packing.radii.max() > 0.2
    assert _clear_of(packing, [[0.5, 0.5]], [0.01], periods=np.ones(2)) >= 0


def test_the_numba_backend_agrees_with_numpy_around_obstacles():
    first = nd.pack(CUBE, n=40, seed=0, progress=False, grid=8)
    runs = [nd.pack(CUBE, n=40, obstacles=first, seed=1, progress=False, grid=8, backend=name)
            for name in ("numpy", "numba")]
    # The two converge to the same Voronoi nodes; their zig-zags end apart by about 1e-8 of a radius.
    np.testing.assert_allclose(runs[1].radii, runs[0].radii, rtol=1e-6)
    assert _clear_of(runs[1], first.centers, first.radii) >= 0


@pytest.mark.parametrize("obstacles, message", [
    ("spheres", "obstacles must be a Packing or"),
    ((np.zeros((2, 3)), np.ones(3)), "2 centres but radii of shape"),
    ((np.zeros((1, 3)), np.array([-1.0])), "radius positive"),
    ((np.array([[np.nan, 0, 0]]), np.ones(1)), "finite"),
    ((np.zeros((2, 2)), np.ones(2)), r"centres of shape \(2, 2\), but the shape is 3-D"),
    ((np.zeros((3, 2)), np.ones(2)), r"centres of shape \(3, 2\)"),
])
def test_bad_obstacles_are_named(obstacles, message):
    with pytest.raises(ParameterError, match=message):
        nd.pack(CUBE, n=10, obstacles=obstacles)
