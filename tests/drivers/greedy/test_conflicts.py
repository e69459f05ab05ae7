"""The conflict check's grid path (:func:`~ndpack.drivers.greedy.conflicts._greedy_on_grid`, pairs
from :mod:`ndpack.geometry.close_pairs`) keeps exactly the spheres its k-d tree path keeps, and
falls back to that path where the grid does not apply or the candidates are crowded."""

import numpy as np
import pytest

from ndpack.drivers.greedy import conflicts
from ndpack.geometry import close_pairs


def tree_path(monkeypatch, centers, radii, margin):
    """:func:`disjoint_greedy` as before the grid: its k-d tree path, unchanged."""
    with monkeypatch.context() as patch:
        patch.setattr(conflicts, "_greedy_on_grid", lambda *args: None)
        return conflicts.disjoint_greedy(centers, radii, margin)


def same_as_tree(monkeypatch, centers, radii, margin, grid=True):
    """The grid path (taken, unless ``grid`` is False) keeps what the k-d tree path keeps."""
    taken = conflicts._greedy_on_grid(centers, radii, margin)
    assert (taken is not None) == grid
    kept = conflicts.disjoint_greedy(centers, radii, margin)
    np.testing.assert_array_equal(kept, tree_path(monkeypatch, centers, radii, margin))
    if grid:
        np.testing.assert_array_equal(kept, taken)
    return kept


def round_of(rng, count, dim, spread=1.25, large=0, larger=20.0):
    """Candidates as a fast-mode round gives them: radii within a factor ``spread``, in priority
    order (largest first), sparse enough to keep most, and ``large`` of them ``larger`` times
    larger, interleaved."""
    radii = np.sort(1 + (spread - 1) * rng.random(count))[::-1] * 0.3 * count ** (-1 / dim)
    radii[rng.choice(count, large, replace=False)] *= larger
    return rng.random((count, dim)), radii


@pytest.mark.parametrize("dim", [1, 2, 3])
@pytest.mark.parametrize("count,large", [(65, 0), (300, 0), (300, 5), (3000, 0), (3000, 12), (20000, 40)])
@pytest.mark.parametrize("margin", [0.0, 1e-9, 0.2], ids=["no margin", "1e-9", "a fifth of a radius"])
def test_random_rounds_keep_the_same_spheres(monkeypatch, dim, count, large, margin):
    rng = np.random.default_rng([dim, count, large, int(margin * 1e9)])
    centers, radii = round_of(rng, count, dim, spread=2.0 if large else 1.25, large=large)
    if margin == 0.2:
        margin *= radii.min()
    kept = same_as_tree(monkeypatch, centers, radii, margin)
    assert 0 < len(kept) < count  # something to decide


@pytest.mark.parametrize("dim", [1, 2, 3])
@pytest.mark.parametrize("along", [False, True], ids=["any way", "along an axis, the largest radii"])
def test_pairs_at_the_edge_of_meeting(monkeypatch, dim, along):
    """Pairs apart by ``r_i + r_j + margin`` to a few units in the last place either way: each
    meets or not as the rounding of ``_meet`` has it, alike on both paths. Along an axis, of the
    largest radius of the rest: a cell's side apart, at every place in the cells."""
    rng = np.random.default_rng(dim)
    centers, radii = round_of(rng, 4000, dim)
    margin = 1e-9
    if along:
        radii[:] = radii[0]
        direction = np.eye(dim)[rng.integers(0, dim, 2000)] * rng.choice([-1, 1], (2000, 1))
    else:
        direction = rng.standard_normal((2000, dim))
        direction /= np.linalg.norm(direction, axis=1)[:, None]
    first, second = np.arange(0, 4000, 2), np.arange(1, 4000, 2)
    distance = (radii[first] + radii[second] + margin) * (1 + rng.integers(-4, 5, 2000) * 2.0**-52)
    centers[second] = centers[first] + distance[:, None] * direction
    meet = conflicts._meet(centers, radii, first, second, margin)
    assert 0 < meet.sum() < len(meet)  # both ways, at the edge
    same_as_tree(monkeypatch, centers, radii, margin)
    same_as_tree(monkeypatch, centers, radii, 0.0)


def test_duplicate_centres_and_equal_radii(monkeypatch):
    rng = np.random.default_rng(3)
    centers, radii = round_of(rng, 3000, 3)
    centers[1::7] = centers[0::7][: len(centers[1::7])]  # duplicates, of larger and smaller ones
    radii[100:400] = radii[100]
    same_as_tree(monkeypatch, centers, radii, 1e-9)


def test_a_few_far_larger_spheres_early_and_late(monkeypatch):
    """The few largest (``few_largest``), huge beside the rest and anywhere in the order, meet
    many: found in the rows within their reach, or among every sphere where those are more."""
    rng = np.random.default_rng(4)
    centers, radii = round_of(rng, 5000, 3)
    radii[[0, 1, 2500, 4999]] = [0.3, 2.0, 0.05, 0.5]  # one covering the whole box
    radii[rng.choice(5000, 40, replace=False)] *= 5
    same_as_tree(monkeypatch, centers, radii, 1e-9)


def test_many_neighbours_each_but_not_crowded(monkeypatch):
    """A dozen neighbours each, under ``_crowded``'s rule: more pairs than the grid first makes
    room for (twice the spheres), listed again with room for all."""
    rng = np.random.default_rng(7)
    centers = rng.random((3000, 3))
    radii = np.full(3000, 0.045)
    spheres = close_pairs.grid(centers, radii, 1e-9, radii.max())
    assert len(spheres.pairs()[0]) > 2 * 3000 + 64
    same_as_tree(monkeypatch, centers, radii, 1e-9)


def test_crowded_candidates_take_the_tree_path(monkeypatch):
    """Thousands within reach of each other (``_crowded``'s rule): decided in blocks, as before."""
    rng = np.random.default_rng(5)
    centers = 0.05 * rng.random((3000, 3))
    radii = np.sort(0.02 + 0.01 * rng.random(3000))[::-1]
    kept = same_as_tree(monkeypatch, centers, radii, 1e-9, grid=False)
    assert len(kept) < 10


def test_inputs_the_grid_refuses_take_the_tree_path(monkeypatch):
    rng = np.random.default_rng(6)
    centers, radii = round_of(rng, 500, 3)
    # Tiny spheres spread far (more than 2**21 cells along an axis), or far from 0 (more than 2**30
    # cells, where a place in cells rounds by too much).
    far = centers.copy()
    far[0] = 1e6
    same_as_tree(monkeypatch, far, radii, 1e-9, grid=False)
    same_as_tree(monkeypatch, centers + 1e9, radii, 1e-9, grid=False)
    # Another dtype, a negative margin, no reach, a fourth dimension: the grid does not apply.
    assert close_pairs.grid(centers.astype(np.float32), radii, 1e-9, radii.max()) is None
    assert close_pairs.grid(centers, radii, -1e-9, radii.max()) is None
    assert close_pairs.grid(centers, np.zeros(500), 0.0, 0.0) is None
    assert close_pairs.grid(rng.random((500, 4)), radii, 1e-9, radii.max()) is None
    nan = centers.copy()
    nan[7, 1] = np.nan
    assert close_pairs.grid(nan, radii, 1e-9, radii.max()) is None
    same_as_tree(monkeypatch, centers, radii, -1e-3, grid=False)


@pytest.mark.parametrize("dim", [1, 2, 3])
def test_grid_lists_every_pair_that_meets(dim):
    """Against all pairs: the grid lists each pair of the spheres of radii at most ``cut`` that
    meets, once, and (with the few larger) every pair that meets."""
    rng = np.random.default_rng(dim + 10)
    centers, radii = round_of(rng, 1500, dim, spread=2.0)
    large, cut = conflicts.few_largest(radii)
    side, lower = (2 * cut + 1e-9) * close_pairs.SIDE, centers.min(axis=0)
    centers[::3] = lower + np.floor((centers[::3] - lower) / side) * side  # on the cells' faces
    centers[1::5] = centers[::5][: len(centers[1::5])]  # and duplicates
    spheres = close_pairs.grid(centers, radii, 1e-9, cut)
    first, second = np.triu_indices(len(radii), 1)
    meet = conflicts._meet(centers, radii, first, second, 1e-9)
    small = (radii[first] <= cut) & (radii[second] <= cut)
    expected = set(zip(first[meet & small].tolist(), second[meet & small].tolist()))
    listed = list(zip(*(column.tolist() for column in spheres.pairs())))
    assert len(listed) == len(set(listed)) and expected <= set(listed)
    assert all(i < j for i, j in listed)
    with_large = set(zip(*(column.tolist() for column in spheres.pairs_with(large))))
    expected = set(zip(first[meet & ~small].tolist(), second[meet & ~small].tolist()))
    assert expected <= with_large
