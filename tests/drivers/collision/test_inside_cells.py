"""The grid of inside / boundary / outside cells that coverings draw their samples in."""

import math

import numpy as np
import pytest

import ndpack as nd
from ndpack.drivers.collision.boundary import boundary_samples, sample_cells
from ndpack.drivers.collision.inside_cells import BOUNDARY, INSIDE, OUTSIDE, InsideCells


def cell_points(cells, state, per_cell, rng):
    """Random points in every cell of the given state, (k, d)."""
    index = np.argwhere(cells.state == state)
    index = np.repeat(index, per_cell, axis=0)
    return cells.lower + (index + rng.random(index.shape)) * cells.size


@pytest.mark.parametrize("shape", [
    nd.Box(np.zeros(3), [1.0, 2.0, 0.5]) - nd.Ball([1.0, 2.0, 0.5], 0.6),
    nd.Ball([0, 0, 0], 1.0) | nd.Ball([1.2, 0, 0], 0.7),  # a union: a lower bound inside
    nd.Box(np.zeros(4), np.ones(4)) - nd.Ball(np.ones(4), 0.6),
], ids=["box-minus-ball", "union", "4-d"])
def test_marked_cells_are_wholly_on_their_side(shape):
    cells = InsideCells(shape, cells=2**15)
    rng = np.random.default_rng(0)
    assert (cells.state == INSIDE).any() and (cells.state == BOUNDARY).any()
    inside = cell_points(cells, INSIDE, 4, rng)
    outside = cell_points(cells, OUTSIDE, 4, rng)
    assert np.all(shape._distance(inside) < 0)
    assert np.all(shape._distance(outside) > 0)
    # And the lookup agrees with the cells the points were drawn in.
    assert np.all(cells.classify(inside) == INSIDE) and np.all(cells.classify(outside) == OUTSIDE)
    assert np.all(cells.classify(np.full((1, shape.dim), 1e6)) == OUTSIDE)


def test_volume_is_bracketed_and_interior_points_are_uniform():
    ball = nd.Ball([0.3, -0.2, 0.1], 1.0)
    cells = InsideCells(ball)
    low, high = cells.volume_bounds
    assert low < 4 / 3 * math.pi < high
    points = cells.interior(40_000, np.random.default_rng(1))
    assert points.shape == (40_000, 3) and np.all(ball._distance(points) < 0)
    # Uniform in the ball: an eighth lie within half the radius (binomial sd 0.0017).
    share = np.mean(np.linalg.norm(points - [0.3, -0.2, 0.1], axis=1) < 0.5)
    assert abs(share - 1 / 8) < 0.01
    # Equal shares in the eight octants around the centre.
    octant = ((points - [0.3, -0.2, 0.1]) > 0) @ [1, 2, 4]
    assert np.all(np.abs(np.bincount(octant, minlength=8) / len(points) - 1 / 8) < 0.01)


def test_points_within_the_margin_lie_in_boundary_cells():
    shape = nd.Box(np.zeros(3), [1.0, 2.0, 0.5]) - nd.Ball([1.0, 2.0, 0.5], 0.6)
    margin = 0.04
    cells = InsideCells(shape, cells=2**15, margin=margin)
    rng = np.random.default_rng(2)
    points = shape.bounds[0] - margin + (np.ptp(shape.bounds, axis=0) + 2 * margin) * rng.random((200_000, 3))
    near = points[np.abs(shape._distance(points)) < margin]
    assert len(near) > 1000 and np.all(cells.classify(near) == BOUNDARY)


def test_projected_samples_drawn_in_cells_keep_the_band_distribution():
    # Without the grid, points of a band around the whole boundary are projected; with it, only
    # those of the boundary cells are drawn: the same band, so the same spread over the pieces.
    shape = nd.Box(np.zeros(3), np.ones(3)) - nd.Ball(np.ones(3), 0.6)
    rng = np.random.default_rng(3)
    plain, _ = boundary_samples(shape, 60_000, rng)
    drawn, normals = boundary_samples(shape, 60_000, rng, sample_cells(shape))
    assert np.all(np.abs(shape._distance(drawn)) <= 1e-9 * shape.scale)
    assert np.allclose(np.linalg.norm(normals, axis=1), 1.0)

    def shares(points):
        on_ball = np.abs(np.linalg.norm(points - 1.0, axis=1) - 0.6) < 1e-6
        on_edge = (np.isclose(points, 0) | np.isclose(points, 1)).sum(axis=1) >= 2
        return np.array([on_ball.mean(), on_edge.mean(), np.mean(points[:, 0] < 0.5)])

    assert np.allclose(shares(plain), shares(drawn), atol=0.01)


def test_a_shape_with_no_inside_is_refused():
    empty = nd.Ball([0, 0, 0], 1.0) & nd.Ball([5, 0, 0], 1.0)
    with pytest.raises(nd.NdpackError, match="inside"):
        InsideCells(empty, cells=2**12).interior(10, np.random.default_rng(0))
