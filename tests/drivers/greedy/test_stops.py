"""Honest stops (issue 45): a run stops for want of room only after a final search, finer than
the grid that ran out, found none (``RunState.search``), in both modes and on every backend, and
a shape is refused as too small only after the same search.

Each case stopped before with room left, on the NumPy reference and on numba alike.
"""

import time

import numpy as np
import pytest

import ndpack as nd
from ndpack.drivers.greedy import protosphere

BACKENDS = ["numpy", "numba"]


def _warp_on_cpu():
    try:
        nd.backends.get_backend("warp", device="cpu")
        return True
    except nd.BackendError:
        return False

#: A 6-D simplex drawn as the fuzzing draws one (tests/fuzz_shapes.py, ``leaf_simplex`` of seed
#: 36), rounded. On a grid of 3 the faithful mode stopped at 32 spheres, "no room", largest radius
#: 0.0247, while ``FREE`` had a clearance of 0.0557 (both backends).
SIMPLEX = [[-0.104, -0.0983, -0.1452, 0.0065, 0.6187, 0.0814], [-0.6482, -0.8345, 1.3687, -0.5691, -0.2937, -0.7764],
           [-0.1321, -0.0374, -0.0599, -0.2036, 0.2997, -0.2291], [-0.9341, -0.2748, 0.5215, -0.6838, -0.1695, 0.3648],
           [0.3112, 0.3617, 0.5569, 0.5917, -0.0741, -0.0511], [-0.4499, 0.4134, -0.0626, -0.3748, 1.1307, -0.2741],
           [-1.408, 0.3371, 0.9666, -0.6383, -0.3596, -0.3562]]
FREE, FREE_CLEARANCE = np.array([-0.4477, 0.0107, 0.2567, -0.2518, 0.2809, -0.0854]), 0.0556

#: The issue's box less a ball: refused on a grid of 4 ("no sphere fits ... scale it up") though
#: ``ROOM`` has a clearance of 0.0179 (packed on the default grid).
BOX = ([-0.7064, 0.0971, -0.2882, -0.0922, -0.1066, -0.4943], [0.2796, 0.3446, 0.2374, 0.1248, 0.1062, -0.0493])
BALL = ([-0.2916, 0.1558, 0.1149, 0.0954, -0.0735, -0.2075], 0.7615)
ROOM = np.array([0.2616, 0.3259, -0.269, -0.0708, 0.0864, -0.4758])


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_square_on_a_grid_of_two_reaches_its_count(backend):
    """``ndpack pack square --grid 2 --mode faithful`` stopped at 169 circles (numpy) and 201
    (numba), "no room left", with free discs 80 times the last radius; now the cells refine."""
    packing = nd.pack(nd.Box([0, 0], [1, 1]), n=210, grid=2, mode="faithful", backend=backend)
    assert len(packing) == 210 and packing.stop_reason == "count" and packing.verify().ok
    assert "final_search" not in packing.params  # recorded only where a run stopped for room


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_6d_simplex_places_a_sphere_where_room_was_left(backend):
    shape = nd.Simplex(SIMPLEX)
    assert -shape._distance(FREE[None])[0] > FREE_CLEARANCE  # the boundary was all that bounded it
    with pytest.warns(nd.GridWarning, match="thinner than the grid's cells"):  # no cell centre lies inside
        packing = nd.pack(shape, n=40, grid=3, mode="faithful", backend=backend)
    assert len(packing) == 40 and packing.stop_reason == "count" and packing.verify().ok
    # The search after the 32nd sphere found the largest gap, so the 33rd sphere is there, at
    # least as large as the clearance found at FREE, and the order is largest first again.
    assert packing.radii[32] >= FREE_CLEARANCE and packing.radii[32] == packing.radii.max()
    assert np.linalg.norm(packing.centers[32] - FREE) < packing.radii[32]
    assert np.all(np.diff(packing.radii[32:]) <= 1e-6)


@pytest.mark.parametrize("mode", ["faithful", "fast"])
@pytest.mark.parametrize("backend", BACKENDS)
def test_a_box_less_a_ball_is_packed_on_a_coarse_grid(backend, mode):
    """Refused before as too small on a grid of 4: its one cell with a start inside held no
    room, and the cells whose starts all lay outside were dropped; they join the search."""
    shape = nd.Box(*BOX) - nd.Ball(*BALL)
    room = -shape._distance(ROOM[None])[0]
    assert room == pytest.approx(0.0179, abs=1e-4)
    with pytest.warns(nd.GridWarning, match="thinner than the grid's cells"):
        packing = nd.pack(shape, n=20, grid=4, mode=mode, backend=backend)
    assert len(packing) == 20 and packing.stop_reason == "count" and packing.verify().ok
    assert packing.radii[0] >= 0.99 * room  # the first sphere is about the largest that fits


@pytest.mark.parametrize("backend", [*BACKENDS, pytest.param("warp", marks=pytest.mark.skipif(
    not _warp_on_cpu(), reason="warp is not installed"))])
def test_slivers_whose_cells_had_no_start_inside_are_searched(backend):
    """A square less a disc leaves four corner slivers. On a grid of 2 the faithful mode made 4
    circles of 3e-9 and below and stopped ("no room"); the cells set aside join the search (on a
    device store too), which finds each corner's largest circle: the one tangent to both sides
    and to the disc, of radius t with (1/2 - t) sqrt(2) - 0.7 = t. (The specks come first still:
    the coarse grid's prototypes had that little room, and the search starts only once none has
    any.)"""
    options = {"device": "cpu"} if backend == "warp" else {}
    shape = nd.Box([0, 0], [1, 1]) - nd.Ball([0.5, 0.5], 0.7)
    with pytest.warns(nd.GridWarning, match="thinner than the grid's cells"):
        packing = nd.pack(shape, n=8, grid=2, mode="faithful", backend=backend, **options)
    assert len(packing) == 8 and packing.stop_reason == "count" and packing.verify().ok
    corner = (0.5 * np.sqrt(2) - 0.7) / (1 + np.sqrt(2))
    largest = np.argsort(-packing.radii)[:4]
    np.testing.assert_allclose(packing.radii[largest], corner, rtol=1e-3)
    assert len(np.unique(np.round(packing.centers[largest]), axis=0)) == 4  # one in each corner


def test_a_stop_for_room_records_the_search_that_found_none():
    """Where the search finds nothing, the packing says how far it looked: here every cell that
    could still hold a circle of min_radius was split until none could."""
    packing = nd.pack(nd.Box([0, 0], [1, 1]), n=10_000, min_radius=0.05, mode="faithful", grid=8)
    assert packing.stop_reason == "min_radius" and packing.radii.min() >= 0.05 and packing.verify().ok
    searched = packing.params["final_search"]
    assert searched["ended"] == "no cell may hold room" and searched["halvings"] == protosphere.SEARCH_HALVINGS


def test_the_search_is_bounded_where_no_room_is_left():
    """A 12-D ball on a grid of 2 is full after one sphere, but no bound proves the shell it
    leaves empty: the search stops at its cell budget, in about what placing the grid cost, and
    says so."""
    started = time.perf_counter()
    packing = nd.pack(nd.Ball(np.zeros(12), 1.0), n=3, grid=2)
    assert len(packing) == 1 and packing.stop_reason == "no_room"
    searched = packing.params["final_search"]
    assert searched["cells"] <= max(protosphere.SEARCH_CELLS, 2**12) and "new cells" in searched["ended"]
    assert time.perf_counter() - started < 30


def test_a_shape_with_no_room_above_the_margin_is_still_refused():
    """The refusal comes after the search: a ball at 1e12, where rounding leaves no room."""
    with pytest.raises(nd.ShapeError, match="no sphere fits"):
        nd.pack(nd.Ball([1e12, 0], 1.0), n=5, grid=8)
