"""overlapping_pairs' grid (ndpack.geometry.overlaps) against the k-d tree path it stands in for:
the same pairs and the same worst overlap, bit for bit, in 1-D to 3-D."""

import numpy as np
import pytest
from scipy.spatial import cKDTree

import ndpack as nd
from ndpack.geometry import overlaps
from ndpack.verify import _overlapping_pairs_kdtree, overlapping_pairs


def both(centers, radii, tol=0.0):
    """The grid's answer and the k-d trees', after checking that the grid did answer."""
    grid = overlaps.overlapping_pairs(centers, radii, tol)
    assert grid is not None, "the grid fell back to the k-d trees"
    return grid, _overlapping_pairs_kdtree(centers, radii, tol)


def assert_same(centers, radii, tol=0.0):
    """The grid's pairs and worst overlap, after checking that they are the k-d trees' (and what
    ndpack.verify.overlapping_pairs returns)."""
    (pairs, worst), (expected_pairs, expected_worst) = both(centers, radii, tol)
    assert pairs.dtype == np.int64 and pairs.shape[1:] == (2,)
    np.testing.assert_array_equal(pairs, expected_pairs)
    assert worst == expected_worst  # the same float64, or both -inf
    np.testing.assert_array_equal(overlapping_pairs(centers, radii, tol)[0], pairs)
    return pairs, worst


def mixed_spheres(dim, seed, count=1500):
    """Radii log-uniform over five orders of magnitude, a few huge spheres, repeated centres and
    exactly touching pairs, in the unit box."""
    rng = np.random.default_rng(seed)
    centers = rng.random((count, dim))
    radii = 10 ** rng.uniform(-5.5, -0.5, count)
    radii[:3] = [0.7, 3.0, 40.0]  # huge: they overlap nearly everything
    centers[-30:] = centers[rng.choice(count - 30, 30)]  # the same centre twice
    # Exactly touching along the first axis: dyadic centres and radii, so that the distance is
    # computed exactly and the overlap is exactly 0.
    touching = np.arange(3, 23)
    centers[touching] = np.round(centers[touching] * 1024) / 1024
    radii[touching] = 2.0 ** -rng.integers(5, 12, len(touching))
    partner = touching + 20
    centers[partner] = centers[touching]
    radii[partner] = 2.0 ** -rng.integers(5, 12, len(touching))
    centers[partner, 0] += radii[touching] + radii[partner]
    return centers, radii


def cells(centers, radii, tol, octave, axes):
    """Each sphere's cell along ``axes`` in the grid of the spheres of ``octave``: cells of side
    ``2 * largest + tol`` from the corner of their centres (as ndpack.geometry.overlaps builds it)."""
    members = np.floor(np.log2(radii)) == octave
    side = 2 * radii[members].max() + tol
    return np.floor((centers[:, axes] - centers[members][:, axes].min(axis=0)) / side).astype(np.int64)


def hashed(centers, radii, tol=0.0):
    """Whether some octave has more rows than overlaps.DENSE per sphere (rows hashed)."""
    octaves = np.floor(np.log2(radii))
    for octave in np.unique(octaves):
        members = centers[octaves == octave]
        side = 2 * radii[octaves == octave].max() + tol
        rows = (np.floor(np.ptp(members[:, 1:], axis=0) / side) + 1).prod()
        if rows > overlaps.DENSE * len(members):
            return True
    return False


def assert_some_pair_crosses_cells(centers, radii, tol, pairs):
    """Some overlapping pair lies in different cells of both its spheres' grids (rows across the last
    axes in 2-D and 3-D; cells along the line in 1-D): a scan of only its own cell (or row) would
    miss it, whichever sphere examines the pair, so these tests would fail."""
    dim = centers.shape[1]
    axes = list(range(1, dim)) if dim > 1 else [0]
    octaves = np.floor(np.log2(radii))
    grids = {octave: cells(centers, radii, tol, octave, axes) for octave in np.unique(octaves[pairs])}
    crossing = sum(all((grids[octaves[k]][i] != grids[octaves[k]][j]).any() for k in (i, j)) for i, j in pairs)
    assert crossing > 0


@pytest.mark.parametrize("dim", [1, 2, 3])
@pytest.mark.parametrize("tol", [0.0, 1e-4])
def test_grid_finds_the_pairs_of_the_kdtrees(dim, tol):
    centers, radii = mixed_spheres(dim, seed=dim)
    assert np.ptp(np.floor(np.log2(radii))) >= 16  # octaves over 4 orders of magnitude and more
    pairs, _ = assert_same(centers, radii, tol)
    assert len(pairs) > 100
    touching = set(zip(range(3, 23), range(23, 43)))
    assert not touching & set(map(tuple, pairs.tolist()))  # an overlap of exactly 0 is no overlap
    assert_some_pair_crosses_cells(centers, radii, tol, pairs[:500])


@pytest.mark.parametrize("dim", [1, 2, 3])
def test_grid_gives_the_gap_of_the_kdtrees_where_nothing_overlaps(dim):
    # Each radius 30 to 45% of the distance to the nearest centre: no pair within r_i + r_j + tol,
    # and `worst` is the gap of the nearest pair examined, so both ways must examine the same pairs.
    rng = np.random.default_rng(10 + dim)
    centers = rng.random((2000, dim))
    nearest = cKDTree(centers).query(centers, k=2)[0][:, 1]
    radii = rng.uniform(0.3, 0.45, len(centers)) * nearest
    pairs, worst = assert_same(centers, radii)
    assert len(pairs) == 0 and -np.inf < worst < 0
    assert_same(centers, radii, tol=np.median(radii))


@pytest.mark.parametrize("dim", [1, 2, 3])
def test_grid_far_from_the_origin_with_tiny_spheres(dim):
    # Coordinates near 1e6 (rounded to 1e-10), radii near 1e-3, thin along the first axis (the one
    # rows are sorted along) and spread wide across it: from 2-D up, far more rows than spheres, so
    # the rows are hashed rather than indexed (overlaps.DENSE).
    rng = np.random.default_rng(20 + dim)
    count = 3000
    centers = 1e6 + rng.random((count, dim)) * {1: [1.0], 2: [0.003, 20.0], 3: [1e-5, 1.0, 1.0]}[dim]
    radii = 10 ** rng.uniform(-3.5, -2.5, count)
    assert dim == 1 or hashed(centers, radii)
    pairs, _ = assert_same(centers, radii)
    assert len(pairs) > 10
    assert_same(centers, radii, tol=1e-4)


@pytest.mark.parametrize("dim", [1, 2, 3])
def test_grid_in_one_octave(dim):
    rng = np.random.default_rng(30 + dim)
    centers = rng.random((1000, dim))
    radii = rng.uniform(0.008, 0.0155, 1000)  # all in octave -7
    assert len(np.unique(np.floor(np.log2(radii)))) == 1
    assert len(assert_same(centers, radii)[0]) > 0
    assert_same(centers, radii, tol=0.005)


def test_grid_with_few_spheres():
    empty = np.zeros((0, 3)), np.zeros(0)
    one = np.zeros((1, 3)), np.ones(1)
    for centers, radii in (empty, one):
        pairs, worst = overlaps.overlapping_pairs(centers, radii)
        assert pairs.shape == (0, 2) and worst == -np.inf
    two = np.array([[0.0, 0.0, 0.0], [1.5, 0.0, 0.0]])
    # Overlapping, touching, a gap within reach (one octave: 2 * 0.9 > 1.5), a gap out of reach
    # (2 * 0.7 < 1.5: no pair examined, -inf both ways), and apart.
    for radii, expected, worst in (([1.0, 1.0], [[0, 1]], 0.5), ([0.75, 0.75], [], 0.0), ([0.5, 0.9], [], -0.1),
                                   ([0.5, 0.7], [], -np.inf), ([0.01, 0.02], [], -np.inf)):
        pairs, found = assert_same(two, np.array(radii))
        assert pairs.tolist() == expected and found == pytest.approx(worst)


def test_a_packing_has_no_pairs_and_the_same_gap_both_ways():
    # 500 spheres over 5 octaves: 1.4 s on the NumPy reference backend the suite packs with.
    packing = nd.pack(nd.Box(np.zeros(3), np.ones(3)), 500, seed=0, progress=False)
    pairs, worst = assert_same(packing.centers, packing.radii, 1e-12)
    assert len(pairs) == 0 and worst < 0
    assert nd.verify(packing).worst_overlap == worst


def test_the_kdtrees_where_the_grid_does_not_apply():
    # Tiny spheres spread far: more than MAX_CELLS rows an axis; from 4-D up; tol < 0.
    centers = np.array([[0.0, 0.0, 0.0], [0.0, 1e6, 0.0], [1e-9, 1e6, 0.0]])
    radii = np.full(3, 1e-9)
    assert overlaps.overlapping_pairs(centers, radii) is None
    assert overlapping_pairs(centers, radii)[0].tolist() == [[1, 2]]
    rng = np.random.default_rng(4)
    centers, radii = rng.random((300, 4)), 10 ** rng.uniform(-3, -0.7, 300)
    assert overlaps.overlapping_pairs(centers, radii) is None
    pairs, worst = overlapping_pairs(centers, radii)
    expected = _overlapping_pairs_kdtree(centers, radii)
    np.testing.assert_array_equal(pairs, expected[0])
    assert len(pairs) > 0 and worst == expected[1]
    assert overlaps.overlapping_pairs(centers[:, :3], radii, tol=-1e-9) is None
