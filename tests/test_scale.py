"""Packing at scale: the sphere index, the cells' walls, and the fast mode against the faithful one."""

import numpy as np
import pytest

import ndpack as nd
from ndpack.backends.numba_backend import INDEX_NEW_SPHERES, NumbaBackend
from ndpack.backends.numpy_backend import NumpyBackend
from ndpack.drivers.greedy.conflicts import disjoint_greedy, greedy_over_pairs
from ndpack.drivers.greedy.protosphere import cooling_schedule

REFERENCE = NumpyBackend()


def spheres_over_octaves(rng, count, dim, size=3.0):
    """Spheres whose radii span five orders of magnitude, as a greedy packing's do."""
    radii = 0.4 * rng.random(count) ** 8 + 1e-6
    return size * rng.random((count, dim)), radii


@pytest.mark.parametrize("dim", [2, 3, 5])
def test_index_finds_the_spheres_the_reference_finds(dim):
    rng = np.random.default_rng(dim)
    centers, radii = spheres_over_octaves(rng, 2000, dim)
    lower = 3.0 * rng.random((300, dim))
    upper = lower + rng.random((300, 1)) * np.array([0.001, 0.03, 0.3])[rng.integers(0, 3, 300)][:, None]
    reach = rng.random(300) * 0.5
    backend = NumbaBackend()
    widths = []
    for count in (1, 700, 2000):  # grows: the index adds only the new spheres
        expected, expected_bound = REFERENCE.near_spheres(lower, upper, reach, centers[:count], radii[:count],
                                                          return_bound=True)
        got, bound = backend.near_spheres(lower, upper, reach, centers[:count], radii[:count], return_bound=True)
        np.testing.assert_array_equal(got, expected)
        np.testing.assert_allclose(bound, expected_bound, rtol=0, atol=1e-12)
        # The bound alone (a split level's halves) is the same walk's, to the bit.
        tightened = backend.tightened_reach(lower, upper, reach, centers[:count], radii[:count])
        np.testing.assert_array_equal(tightened, bound)
        assert np.all(tightened <= reach) and (count < 2000 or np.any(tightened < reach))
        widths.append(got.shape[1])
    # The table is filled as wide as the last call's widest rows: the rows beyond that walk again.
    assert widths[0] < 8 < widths[2], widths
    # Other spheres (not an extension of the indexed ones) start a fresh index.
    moved = centers[:500] + 0.01
    np.testing.assert_array_equal(backend.near_spheres(lower, upper, reach, moved, radii[:500]),
                                  REFERENCE.near_spheres(lower, upper, reach, moved, radii[:500]))


def spheres_on_cell_faces(rng, count, dim):
    """Spheres and boxes on a 1/64 lattice, in binary exactly: the index's cells (side 1/2**l with
    the largest radius 1/4) have many centres on their faces, and many spheres come exactly as near
    a box as its reach. Returns centres, radii, box corners and reaches."""
    centers = rng.integers(0, 129, (count, dim)) / 64.0
    radii = rng.choice([1 / 4, 1 / 16, 1 / 64, 1 / 128], count, p=[0.02, 0.18, 0.4, 0.4])
    lower = rng.integers(0, 120, (300, dim)) / 64.0
    upper = lower + rng.integers(1, 9, (300, 1)) / 64.0
    reach = rng.integers(1, 24, 300) / 64.0
    # And a sphere exactly at each box's reach, beyond its upper face on a random axis.
    axis = rng.integers(0, dim, 300)
    planted = upper.copy()
    planted[np.arange(300), axis] += reach + 1 / 64
    return np.vstack([centers, planted]), np.append(radii, np.full(300, 1 / 64)), lower, upper, reach


@pytest.mark.parametrize("dim", [3, 4, 5])
def test_index_skips_only_cells_out_of_reach(dim):
    """A query skips the cells of its window farther than its reach (its corners, most of it from
    4-D up) before hashing them: spheres on those cells' faces, and exactly at the reach, are
    still found, as the reference finds them."""
    rng = np.random.default_rng(20 + dim)
    centers, radii, lower, upper, reach = spheres_on_cell_faces(rng, 3000, dim)
    expected, expected_bound = REFERENCE.near_spheres(lower, upper, reach, centers, radii, return_bound=True)
    got, bound = NumbaBackend().near_spheres(lower, upper, reach, centers, radii, return_bound=True)
    np.testing.assert_array_equal(got, expected)
    np.testing.assert_array_equal(bound, expected_bound)
    # The lattice puts spheres at a box's tightened reach (to the bit where it was not tightened):
    # the edge case is exercised, and most boxes find some spheres.
    outside = np.maximum(np.maximum(lower[:, None] - centers, centers - upper[:, None]), 0.0)
    box_gap = np.sqrt((outside**2).sum(axis=2)) - radii
    assert np.any(np.abs(box_gap - bound[:, None]) <= 1e-12), "no sphere at a reach"
    assert np.mean(np.any(expected < len(radii), axis=1)) > 0.5


@pytest.mark.parametrize("dim", [3, 5])
def test_index_finds_tiny_spheres_far_from_the_origin(dim):
    """Cells of a billionth at coordinates of a thousand (a scanned part in millimetres, packed
    down to tiny gaps), where a unit in the last place is a hundred times the millionth of a cell
    that widens a skipped cell: the spheres sit on their level's cells' faces, a unit in the last
    place either side, each box has one at its reach, and the tables are the reference's."""
    rng = np.random.default_rng(40 + dim)
    side = 4 * 0.3 * 0.5**31  # the level of radius 1e-9 under a largest radius of 0.3
    cells = np.round(1000.0 / side) + rng.integers(-50, 50, (2000, dim))
    centers = cells * side + rng.choice([-1, 0, 1], (2000, dim)) * np.spacing(1000.0)
    radii = np.append(np.full(1999, 1e-9), 0.3)
    centers[-1] = 990.0  # the largest sphere, far away: it sets the levels
    lower = centers[:300] + rng.uniform(2e-9, 3e-8, (300, dim))
    upper = lower + 1e-8
    reach = rng.uniform(1e-9, 2e-8, 300)
    planted = upper.copy()
    planted[:, 0] += reach + 1e-9
    centers, radii = np.vstack([centers, planted]), np.append(radii, np.full(300, 1e-9))
    expected = REFERENCE.near_spheres(lower, upper, reach, centers, radii)
    np.testing.assert_array_equal(NumbaBackend().near_spheres(lower, upper, reach, centers, radii), expected)
    assert np.mean(np.any(expected < len(radii), axis=1)) > 0.5


@pytest.mark.parametrize("dim", [2, 3, 6])
def test_touched_through_the_index_matches_the_reference(dim):
    rng = np.random.default_rng(10 + dim)
    points = rng.random((4000, dim))
    clearance = rng.random(4000) * 0.1 * dim - 0.02  # some prototypes already inside a sphere
    new_centers = rng.random((4 * INDEX_NEW_SPHERES, dim))
    new_radii = rng.random(4 * INDEX_NEW_SPHERES) * 0.05
    expected = REFERENCE.touched(points, clearance, new_centers, new_radii)
    assert 0 < (expected >= 0).sum() < len(points)
    # Which ones are touched, and the nearest new sphere of each (a brute-force argmin).
    gaps = np.linalg.norm(points[:, None] - new_centers, axis=2) - new_radii
    nearest = np.argmin(gaps, axis=1)
    touched = gaps[np.arange(len(points)), nearest] < clearance
    np.testing.assert_array_equal(expected, np.where(touched, nearest, -1))
    np.testing.assert_array_equal(NumbaBackend().touched(points, clearance, new_centers, new_radii), expected)


@pytest.mark.parametrize("shape", [nd.Ball(np.zeros(3), 1.0),
                                   nd.Box(-np.ones(2), np.ones(2)) - nd.Ball(np.zeros(2), 0.3)])
def test_walls_spare_evaluations_without_changing_results(shape):
    """A wall lets the kernel skip the shape where a sphere is surely nearer: same numbers."""
    rng = np.random.default_rng(4)
    dim = shape.dim
    lower = shape.bounds[0] + (shape.bounds[1] - shape.bounds[0]) * rng.random((500, dim)) * 0.9
    upper = lower + 0.1
    points = lower + 0.1 * rng.random((500, dim))
    centers = shape.bounds[0] + (shape.bounds[1] - shape.bounds[0]) * rng.random((60, dim))
    radii = np.full(60, 0.05)
    wall = -shape._distance(0.5 * (lower + upper)) - 1e-9
    neighbours = REFERENCE.near_spheres(lower, upper, np.full(500, 10.0), centers, radii)
    steps = cooling_schedule(30)
    starts = lower + 0.1 * rng.random((3, 500, dim))
    backend = NumbaBackend()
    plain = backend.converge(shape, points, lower, upper, centers, radii, neighbours, steps, starts=starts)
    walled = backend.converge(shape, points, lower, upper, centers, radii, neighbours, steps, wall, starts)
    np.testing.assert_array_equal(walled[0], plain[0])
    np.testing.assert_array_equal(walled[1], plain[1])
    # The walls are read: walls that wrongly claim the boundary far away change the results.
    fooled = backend.converge(shape, points, lower, upper, centers, radii, neighbours, steps, np.full(500, 1e9), starts)
    assert not np.array_equal(fooled[1], plain[1])
    reference = REFERENCE.converge(shape, points, lower, upper, centers, radii, neighbours, steps, starts=starts)
    np.testing.assert_allclose(walled[1], reference[1], atol=1e-8)


@pytest.mark.parametrize("large", [0, 40], ids=["even radii", "a few large"])
def test_greedy_conflict_check_matches_brute_force(large):
    rng = np.random.default_rng(5)
    centers = rng.random((600, 3))
    # A fast-mode round may hold a few spheres far larger than the rest (gaps found late).
    radii = np.sort(np.concatenate([rng.random(600 - large) * 0.05, 0.1 + 0.2 * rng.random(large)]))[::-1]
    np.testing.assert_array_equal(disjoint_greedy(centers, radii, 1e-9), sequential_greedy(centers, radii, 1e-9))


def sequential_greedy(centers, radii, margin):
    kept = []
    for i in range(len(radii)):
        if all(np.linalg.norm(centers[i] - centers[j]) >= radii[i] + radii[j] + margin for j in kept):
            kept.append(i)
    return kept


def sequential_greedy_among(centers, radii, margin, period=None):
    """The sequential rule, each candidate against all kept so far at once (in a periodic domain
    between nearest images): for thousands of candidates."""
    kept = np.empty(0, dtype=np.int64)
    for i in range(len(radii)):
        delta = centers[i] - centers[kept] if period is None else period.difference(centers[i], centers[kept])
        if np.all(np.linalg.norm(delta, axis=1) >= radii[i] + radii[kept] + margin):
            kept = np.append(kept, i)
    return kept


def counting_pairs(monkeypatch):
    """The pairs the conflict check decides over, call by call."""
    import ndpack.drivers.greedy.conflicts as conflicts

    compared = []
    greedy = conflicts.greedy_over_pairs
    monkeypatch.setattr(conflicts, "greedy_over_pairs", lambda count, first, second: compared.append(len(first)) or
                        greedy(count, first, second))
    return compared


@pytest.mark.parametrize("axes", [[True, True], [True, True, False]], ids=["2-D", "3-D, one axis free"])
def test_dense_candidates_in_a_periodic_box_are_decided_without_listing_their_pairs(monkeypatch, axes):
    """A fast-mode round in a small periodic box: thousands of prototypes, nearly all capped at
    the largest radius, nearly all within twice it of each other (32,761 in the unit square with
    radii up to 0.2 had listed hundreds of millions of pairs, a minute for 5 spheres). The kept
    ones exclude the rest: the work follows them, and the subset is the sequential rule's."""
    from ndpack.geometry.period import Period

    compared = counting_pairs(monkeypatch)
    rng = np.random.default_rng(7)
    dim = len(axes)
    period = Period(np.zeros(dim), np.ones(dim), axes)
    # The prototypes of a grid, cell after cell (the first few all near one corner).
    side = [40, 128] if dim == 2 else [18, 18, 16]
    cells = np.stack(np.meshgrid(*[np.arange(n) for n in side], indexing="ij"), axis=-1).reshape(-1, dim)
    centers = (cells + 0.5 + 0.1 * rng.standard_normal(cells.shape)) / side
    centers[:, ~np.asarray(axes)] *= 0.3  # a slab along the free axis
    count = len(centers)
    radii = np.minimum(0.2, 0.15 + 0.1 * rng.random(count))  # most capped
    kept = disjoint_greedy(centers, radii, 1e-10, period)
    np.testing.assert_array_equal(kept, sequential_greedy_among(centers, radii, 1e-10, period))
    assert 2 <= len(kept) < 20 and sum(compared) < 4 * count
    # Between nearest images: the kept ones are apart across the box's faces too.
    delta = period.difference(centers[kept][:, None], centers[kept][None])
    gaps = np.linalg.norm(delta, axis=2) - radii[kept][:, None] - radii[kept][None]
    assert np.all(gaps[~np.eye(len(kept), dtype=bool)] >= 1e-10)


@pytest.mark.parametrize("small", [0.004, 0.03], ids=["sparse", "crowded"])
def test_a_few_huge_spheres_among_many_small_ones(monkeypatch, small):
    """Candidates far larger than the rest, early and late in the order, among sparse small
    ones (decided over their pairs) or crowded ones (decided block by block, each huge one that
    survives to its block looking for the kept spheres before it): the sequential rule's subset,
    in a plain box and a periodic one, over a bounded number of pairs."""
    compared = counting_pairs(monkeypatch)
    rng = np.random.default_rng(11)
    count = 4000
    centers = rng.random((count, 2))
    radii = small * (0.5 + 0.5 * rng.random(count))
    huge = np.array([0, 3, 100, 700, 2500, 3999])  # in priority order: first, early, late, last
    radii[huge] = [0.3, 0.05, 0.2, 0.25, 0.15, 0.4]
    kept = disjoint_greedy(centers, radii, 1e-9)
    np.testing.assert_array_equal(kept, sequential_greedy_among(centers, radii, 1e-9))
    assert 0 in kept and 3999 not in kept
    assert sum(compared) < 20 * count
    # In a periodic box, the huge ones reaching across its faces.
    from ndpack.geometry.period import Period

    period = Period(np.zeros(2), np.ones(2), [True, True])
    centers[huge] = [[0.02, 0.5], [0.99, 0.98], [0.5, 0.01], [0.97, 0.3], [0.3, 0.97], [0.6, 0.6]]
    compared.clear()
    kept = disjoint_greedy(centers, radii, 1e-9, period)
    np.testing.assert_array_equal(kept, sequential_greedy_among(centers, radii, 1e-9, period))
    assert sum(compared) < 20 * count


def test_candidates_in_one_gap_are_decided_without_listing_their_pairs(monkeypatch):
    """A 12-D ball on a grid of 2: every one of its 4,096 cells' prototypes finds the centre, and
    the conflict check listed all 8.4 million pairs among them (5.5 s, 1.6 GB) for one sphere.
    The work is bounded here by the pairs of spheres that meet it decides over, not by the time."""
    import ndpack.drivers.greedy.conflicts as conflicts

    compared = []
    greedy = conflicts.greedy_over_pairs
    monkeypatch.setattr(conflicts, "greedy_over_pairs", lambda count, first, second: compared.append(len(first)) or
                        greedy(count, first, second))
    rng = np.random.default_rng(0)
    centers = 1e-3 * rng.standard_normal((4096, 12))
    radii = np.sort(0.99 + 0.01 * rng.random(4096))[::-1]
    assert disjoint_greedy(centers, radii, 1e-10).tolist() == [0]
    assert sum(compared) < 4 * 4096
    # Three gaps apart, candidates interleaved by size: the same subset as one after another.
    gaps = 10 * np.eye(12)[rng.integers(0, 3, 600)]
    centers, radii = gaps + 0.3 * rng.standard_normal((600, 12)), np.sort(0.5 + rng.random(600))[::-1]
    compared.clear()
    np.testing.assert_array_equal(disjoint_greedy(centers, radii, 1e-9), sequential_greedy(centers, radii, 1e-9))
    assert sum(compared) < 600 * 64
    # The fast mode's first sphere in that ball, through the driver.
    compared.clear()
    packing = nd.pack(nd.Ball(np.zeros(12), 1.0), n=3, grid=2, mode="fast", backend="numpy", progress=False)
    assert len(packing) == 1 and packing.radii[0] > 0.999 and 0 < sum(compared) < 4 * 4096


def test_the_reference_backend_bounds_its_temporaries(monkeypatch):
    """In high dimensions every sphere is near every cell: the reference backend's (points,
    neighbours, d) arrays go in chunks of CHUNK_FLOATS (a 12-D fast run of 2,000 spheres had
    needed 24 GB), with the same results to the bit."""
    import ndpack.backends.numpy_backend as numpy_backend

    rng = np.random.default_rng(2)
    dim, count = 12, 3000
    shape = nd.Ball(np.zeros(dim), 1.0) - nd.Ball(np.zeros(dim), 0.5)
    centers, radii = 0.7 * rng.standard_normal((400, dim)) / np.sqrt(dim), 0.05 + 0.05 * rng.random(400)
    points = rng.uniform(-0.6, 0.6, (count, dim))
    lower, upper = points - 0.2, points + 0.2
    neighbours = np.tile(np.arange(400), (count, 1))
    steps = np.linspace(0.2, 0.01, 8)
    starts = rng.uniform(-0.6, 0.6, (3, count, dim))
    whole = REFERENCE.converge(shape, points, lower, upper, centers, radii, neighbours, steps, starts=starts)
    largest = []
    among = NumpyBackend._free_space_among
    monkeypatch.setattr(NumpyBackend, "_free_space_among", lambda self, shape, p, c, r: largest.append(c.size) or among(
        self, shape, p, c, r))
    monkeypatch.setattr(numpy_backend, "CHUNK_FLOATS", 200_000)
    chunked = REFERENCE.converge(shape, points, lower, upper, centers, radii, neighbours, steps, starts=starts)
    assert max(largest) <= 200_000
    np.testing.assert_array_equal(chunked[0], whole[0])
    np.testing.assert_array_equal(chunked[1], whole[1])


def test_parallel_greedy_decides_as_one_item_after_another():
    """Long chains of rivals (each blocks the next) and random conflict graphs: the passes keep
    exactly what the sequential rule keeps."""
    def sequential(count, first, second):
        kept, blocked = [], np.zeros(count, dtype=bool)
        for i in range(count):
            if not blocked[i]:
                kept.append(i)
                blocked[second[first == i]] = True
        return kept

    chain = np.arange(199)
    np.testing.assert_array_equal(greedy_over_pairs(200, chain, chain + 1), np.arange(0, 200, 2))
    rng = np.random.default_rng(3)
    for count, pairs in ((50, 0), (300, 900), (300, 5000)):
        a, b = rng.integers(0, count, (2, pairs))
        first, second = np.minimum(a, b)[a != b], np.maximum(a, b)[a != b]
        np.testing.assert_array_equal(greedy_over_pairs(count, first, second), sequential(count, first, second))


def fill_at(packing, count):
    return nd.ball_volume(packing.dim, packing.radii[:count]).sum() / packing.volume


@pytest.mark.parametrize("dim, count", [(2, 3000), (3, 3000)])
def test_fast_mode_fills_like_the_faithful_mode(dim, count):
    shape = nd.Box(np.zeros(dim), np.ones(dim))
    faithful = nd.pack(shape, count, backend="numba", grid=24 if dim == 3 else 100)
    fast = nd.pack(shape, count, backend="numba", mode="fast", grid=24 if dim == 3 else 100)
    assert len(fast) == count and fast.verify().ok
    assert fast.params["mode"] == "fast"
    for at in (count // 10, count // 2, count):
        assert abs(fill_at(fast, at) / fill_at(faithful, at) - 1) < 0.01
    # Far fewer rounds: many spheres each.
    assert len(fast.stats.time) < count / 20


@pytest.mark.parametrize("dim", [2, 3, 4])
def test_fast_mode_finds_the_exact_cube_radii(dim):
    packing = nd.pack(nd.Box(np.zeros(dim), np.ones(dim)), n=1 + 2**dim, mode="fast", backend="numba")
    assert abs(packing.radii[0] - 0.5) < 1e-4
    radius = 0.5 * (np.sqrt(dim) - 1) / (np.sqrt(dim) + 1)
    assert np.abs(packing.radii[1:] / radius - 1).max() < 1e-4
    assert len(np.unique(np.round(packing.centers[1:]), axis=0)) == 2**dim


def test_fast_mode_polishes_only_the_candidates_it_keeps(monkeypatch):
    # A candidate that a larger one blocks is touched by that sphere and converges again, so
    # polishing it is lost: the polish goes to the chosen ones (a few passes may add some).
    from ndpack.drivers.greedy.protosphere import RunState

    polished = []
    original = RunState.polish
    monkeypatch.setattr(RunState, "polish", lambda state, ids: polished.append(len(ids)) or original(state, ids))
    packing = nd.pack(nd.Box(np.zeros(3), np.ones(3)), 3000, mode="fast", backend="numba")
    assert packing.verify().ok
    assert len(packing) <= sum(polished) <= 1.1 * len(packing)  # 4.7 times before the change


def test_fast_mode_splits_cells_and_the_cells_still_tile_the_grid():
    shape = nd.Box(np.zeros(2), np.ones(2))
    states = []
    packing = nd.pack(shape, 4000, mode="fast", backend="numba", grid=16,
                      on_round=lambda round: states.append(round.state))
    store = states[0].prototypes
    assert len(store) > 16 * 16  # cells split where the gaps became small
    sizes = store.cell_upper - store.cell_lower
    assert np.isclose(np.prod(sizes, axis=1).sum(), 1.0)  # halves tile the grid, no cell lost
    points, _ = store.all()
    assert np.all((points >= store.cell_lower) & (points <= store.cell_upper))
    assert packing.verify().ok


def test_fast_mode_on_a_mesh_and_the_reference_backend_agree():
    mesh = nd.TriangleMesh.load(__import__("pathlib").Path(__file__).parent / "data/meshes/fandisk.ply")
    fast = nd.pack(mesh, 400, mode="fast", backend="numba", grid=12)
    reference = nd.pack(mesh, 400, mode="fast", backend="numpy", grid=12)
    assert fast.verify().ok and reference.verify().ok
    # The compiled gradient is a central difference, the reference's comes from the nearest
    # point: at the model's creases prototypes stop in slightly different places (faithful
    # mode too: radii differ by up to 0.2% here), and a round's choice among near-equal
    # candidates can follow. The largest sphere and the fill agree.
    assert abs(fast.radii[0] / reference.radii[0] - 1) < 1e-4
    assert abs(fast.fill / reference.fill - 1) < 0.01


def test_mode_is_checked():
    with pytest.raises(nd.ParameterError, match="mode must be"):
        nd.pack(nd.Ball(np.zeros(2), 1.0), 3, mode="quick")
    with pytest.raises(nd.ParameterError, match="faithful mode only"):
        nd.pack(nd.Ball(np.zeros(2), 1.0), 3, mode="fast", batch=8)


def _device_backends():
    import os

    names = []
    if os.environ.get("NUMBA_ENABLE_CUDASIM") != "1":
        names += [("warp", "float64"), ("warp", "float32")]
    try:
        nd.backends.get_backend("numba-cuda")
        names.append(("numba-cuda", "float64"))
    except nd.BackendError:
        pass
    return names


@pytest.mark.parametrize("name, precision", [case for case in _device_backends() if case[1] == "float64"])
def test_device_index_skips_only_cells_out_of_reach(name, precision):
    """The device kernels skip the cells out of reach as the CPU's do: on the 1/64 lattice (spheres
    on cell faces and at the reach), the tables are the reference's."""
    if name == "warp":
        pytest.importorskip("warp")
        from ndpack.backends.warp_backend import WarpBackend

        backend = WarpBackend(precision=precision)
    else:
        backend = nd.backends.get_backend(name)
    dim = 3  # the module the other device test compiles
    centers, radii, lower, upper, reach = spheres_on_cell_faces(np.random.default_rng(30), 3000, dim)
    points = 0.5 * (lower + upper)
    store = backend.prototypes(nd.Box(np.zeros(dim), 3 * np.ones(dim)), lower, upper, reach, points,
                               np.zeros(len(reach)))
    ids = np.arange(len(reach))
    _, d_radii, table = store._neighbours(ids, store.device.upload(ids, "index"), centers, radii)
    got = np.sort(table.numpy() if hasattr(table, "numpy") else table.copy_to_host(), axis=1).astype(np.int64)
    got[got >= d_radii.shape[0]] = len(radii)
    expected = REFERENCE.near_spheres(lower, upper, reach, centers, radii)
    np.testing.assert_array_equal(got[:, : expected.shape[1]], expected)
    assert np.all(got[:, expected.shape[1]:] == len(radii))


@pytest.mark.parametrize("name, precision", _device_backends())
def test_device_index_finds_what_the_reference_finds(name, precision):
    """The device store's sphere index (built on the host, mirrored and queried on the device):
    neighbour tables as the reference's while the spheres grow, past a rebuild, and the prototypes
    that new spheres touch. float32 may list more spheres (its cell ranges are widened), never fewer."""
    if name == "warp":
        pytest.importorskip("warp")
        from ndpack.backends.warp_backend import WarpBackend

        backend = WarpBackend(precision=precision)
    else:
        backend = nd.backends.get_backend(name)
    rng = np.random.default_rng(7)
    dim, cells = 3, 400
    centers, radii = spheres_over_octaves(rng, 1500, dim)
    lower = 3.0 * rng.random((cells, dim))
    upper = lower + rng.random((cells, 1)) * np.array([0.001, 0.03, 0.3])[rng.integers(0, 3, cells)][:, None]
    reach = rng.random(cells) * 0.5
    points = lower + (upper - lower) * rng.random((cells, dim))
    clearance = rng.random(cells) * 0.2 - 0.02
    store = backend.prototypes(nd.Box(np.zeros(dim), 3 * np.ones(dim)), lower, upper, reach, points, clearance)
    ids = np.arange(cells)
    for count in (1, 20, 40, 700, 900, 1500):  # mirrored incrementally, rebuilt past its capacity
        store.device.write(store.d_reach, 0, reach, "float")  # the store tightens its reach: start again
        _, d_radii, table = store._neighbours(ids, store.device.upload(ids, "index"), centers[:count],
                                              radii[:count])
        got = np.sort(table.numpy() if hasattr(table, "numpy") else table.copy_to_host(), axis=1).astype(np.int64)
        got[got >= d_radii.shape[0]] = count
        expected = REFERENCE.near_spheres(lower, upper, reach, centers[:count], radii[:count])
        if precision == "float64":
            np.testing.assert_array_equal(got[:, : expected.shape[1]], expected)
            assert np.all(got[:, expected.shape[1]:] == count)
        else:  # rounding may add a sphere at the edge of the reach; every expected one is there
            assert all(set(want) <= set(row) for want, row in zip(expected, got))
    new_centers, new_radii = centers[:300], radii[:300] * 3
    nearest = REFERENCE.touched(points, clearance, new_centers, new_radii)
    expected = np.flatnonzero(nearest >= 0)
    assert 0 < len(expected) < cells
    touched, _, found = store.touched(new_centers, new_radii)
    if precision == "float64":
        np.testing.assert_array_equal(touched, expected)
        np.testing.assert_array_equal(found, nearest[expected])
    else:  # float32 decides ties at the last bit differently: a handful may differ
        assert len(np.setxor1d(touched, expected)) <= 0.01 * cells
        both = np.intersect1d(touched, expected)
        assert np.mean(found[np.searchsorted(touched, both)] == nearest[both]) >= 0.99
