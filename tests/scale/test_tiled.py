"""One domain in tiles (issue 25): ``pack_tiled`` is valid as a whole and fills as ``pack`` does.

Every packing is checked here by an overlap test that shares nothing with ``ndpack.verify``: all
pairs' distances in NumPy (with the nearest periodic image where the box wraps),
and containment by the box's own coordinates. Counts are small (a few hundred to 2,000 spheres
in 2-D, on the NumPy backend that the test environment sets) to keep the file near a minute
on 2 cores.
"""

import numpy as np
import pytest

import ndpack as nd
from ndpack.scale import tiled
from ndpack.errors import ParameterError


def _assert_valid_by_hand(packing, lower, upper, periods=None):
    """No two spheres overlap (all pairs), and every sphere lies in the box ``lower``, ``upper``
    (along the axes that do not wrap)."""
    centers, radii = packing.centers, packing.radii
    delta = centers[:, None, :] - centers[None, :, :]
    if periods is not None:
        wraps = periods > 0
        delta[..., wraps] -= periods[wraps] * np.round(delta[..., wraps] / periods[wraps])
    distance = np.linalg.norm(delta, axis=2)
    np.fill_diagonal(distance, np.inf)
    gap = distance - radii[:, None] - radii[None, :]
    assert gap.min() >= -1e-12, f"spheres overlap by {-gap.min():.3g}"
    walls = np.ones(centers.shape[1], dtype=bool) if periods is None else periods == 0
    assert np.all(centers[:, walls] - radii[:, None] >= lower[walls] - 1e-12)
    assert np.all(centers[:, walls] + radii[:, None] <= upper[walls] + 1e-12)
    if periods is not None:  # wrapped into the cell
        assert np.all((centers >= lower) & (centers < upper))


@pytest.fixture(scope="module")
def square_runs():
    """A square of 2,000 spheres: alone, and in 8 slabs on a pool of 2 and in this process."""
    square = nd.Box([0, 0], [1, 1])
    alone = nd.pack(square, n=2000, seed=0, progress=False)
    pool = nd.pack_tiled(square, n=2000, tiles=8, workers=2, seed=0, progress=False)
    here = nd.pack_tiled(square, n=2000, tiles=8, workers=1, seed=0, progress=False)
    return square, alone, pool, here


def test_a_tiled_square_is_valid_as_a_whole_and_fills_within_one_percent_of_one_run(square_runs):
    square, alone, pool, _ = square_runs
    assert len(pool) == 2000 and pool.stop_reason == "count"
    _assert_valid_by_hand(pool, np.zeros(2), np.ones(2))
    assert nd.verify(pool, square).ok
    assert abs(pool.fill / alone.fill - 1) < 0.01, (pool.fill, alone.fill)
    info = pool.params["tiled"]
    assert info["tiles"] == [8, 8] and info["workers"] == 2 and info["halo"] == pytest.approx(1 / 32)
    assert len(info["bands"]) >= 2 and sum(band["spheres"] for band in info["bands"]) >= 2000 - info["global_spheres"]
    # The global phase placed every sphere above the halo, and no tile's sphere is larger than its box allows.
    assert np.all(pool.radii[: info["global_spheres"]] >= info["halo"])
    assert 0 < info["busy_share"] <= 1 and 0 < info["halo_share"] < 1
    # The fill curve: the global phase, then one point a phase, in time order.
    assert np.all(np.diff(pool.stats.time) >= 0) and np.all(np.diff(pool.stats.count) >= 0)
    assert pool.stats.count[0] == info["global_spheres"] and pool.stats.count[-1] == 2000


def test_a_tiled_packing_does_not_depend_on_where_the_tiles_ran(square_runs):
    _, _, pool, here = square_runs
    np.testing.assert_array_equal(pool.centers, here.centers)
    np.testing.assert_array_equal(pool.radii, here.radii)


def test_tiles_of_one_colour_never_meet_and_each_has_its_neighbours():
    tiling = tiled.make_tiling(np.array([[0.0, 0.0, 0.0], [1.0, 2.0, 1.0]]), [4, 2, 2], 1)
    boxes = [tiling.grown_box(tile) for tile in range(tiling.total)]
    for a in range(tiling.total):
        near = {other for other, _ in tiling.neighbours(a)}
        for b in range(tiling.total):
            meet = np.all(boxes[a][0] < boxes[b][1]) and np.all(boxes[b][0] < boxes[a][1])
            assert not (meet and a != b and tiling.colour(a) == tiling.colour(b))
            assert not meet or b in near  # every box that meets this one is a neighbour
    assert len({tiling.colour(tile) for tile in range(tiling.total)}) == 8


def test_a_tiled_periodic_box_wraps_and_is_valid_with_every_image():
    cell = nd.Periodic(nd.Box([0, 0], [1, 1]))
    alone = nd.pack(cell, n=800, seed=0, progress=False)
    packing = nd.pack_tiled(cell, n=800, tiles=[4, 2], workers=1, seed=0, progress=False)
    assert len(packing) == 800
    _assert_valid_by_hand(packing, np.zeros(2), np.ones(2), periods=np.ones(2))
    assert nd.verify(packing, cell).ok
    assert abs(packing.fill / alone.fill - 1) < 0.01, (packing.fill, alone.fill)


def test_periodic_slabs_wrap_along_the_axes_of_one_tile():
    cell = nd.Periodic(nd.Box([0, 0], [2, 1]))
    packing = nd.pack_tiled(cell, n=600, workers=1, seed=2, progress=False)  # 4 slabs across x, one tile in y
    assert packing.params["tiled"]["tiles"] == [4, 1] and len(packing) == 600
    _assert_valid_by_hand(packing, np.zeros(2), np.array([2.0, 1.0]), periods=np.array([2.0, 1.0]))
    assert nd.verify(packing, cell).ok


def test_a_tiled_shape_that_is_not_a_box_keeps_inside_it():
    ring = nd.Ball([0, 0], 1.0) - nd.Ball([0.2, 0], 0.4)
    packing = nd.pack_tiled(ring, n=800, tiles=[4, 4], workers=1, seed=1, progress=False)
    assert len(packing) == 800 and nd.verify(packing, ring).ok
    distance = np.linalg.norm(packing.centers, axis=1)
    assert np.all(distance + packing.radii <= 1 + 1e-12)
    assert np.all(np.linalg.norm(packing.centers - [0.2, 0], axis=1) - packing.radii >= 0.4 - 1e-12)
    _assert_valid_by_hand(packing, np.full(2, -1.0), np.full(2, 1.0))


def test_few_spheres_need_no_tiles():
    packing = nd.pack_tiled(nd.Box([0, 0], [1, 1]), n=5, tiles=4, workers=1, progress=False)
    assert len(packing) == 5 and "tiled" not in packing.params


def test_ctrl_c_keeps_the_phases_that_finished(monkeypatch):
    calls = []

    def interrupted_third(shape, task):
        calls.append(task.tile)
        if len(calls) == 3:
            raise KeyboardInterrupt
        return original(shape, task)

    original = tiled._pack_tile
    monkeypatch.setattr(tiled, "_pack_tile", interrupted_third)
    square = nd.Box([0, 0], [1, 1])
    packing = nd.pack_tiled(square, n=3000, tiles=4, workers=1, progress=False)
    assert packing.stop_reason == "interrupted" and 0 < len(packing) < 3000
    assert nd.verify(packing, square).ok


def test_ctrl_c_on_a_pool_stops_its_workers_and_keeps_the_phases_that_finished(monkeypatch):
    # Ctrl-C reaches this process, not the workers (they ignore it): here it comes as the third
    # tile's spheres arrive; the pool is stopped, not waited for.
    added = []
    original = tiled._Spheres.add

    def interrupted_third(self, tile, centers, radii, phase):
        added.append(tile)
        if len(added) == 3:
            raise KeyboardInterrupt
        original(self, tile, centers, radii, phase)

    monkeypatch.setattr(tiled._Spheres, "add", interrupted_third)
    stopped, original_stop = [], tiled.Workers.stop
    monkeypatch.setattr(tiled.Workers, "stop", lambda self: stopped.append(1) or original_stop(self))
    square = nd.Box([0, 0], [1, 1])
    packing = nd.pack_tiled(square, n=3000, tiles=8, workers=2, progress=False)
    assert packing.stop_reason == "interrupted" and stopped == [1]
    assert 0 < len(packing) < 3000 and nd.verify(packing, square).ok


@pytest.mark.parametrize("options, message", [
    (dict(band=1.5), "band must lie in"),
    (dict(tiles=[2, 0]), "tiles must be a positive integer"),
    (dict(tiles=2.5), "tiles must be a positive integer"),
    (dict(fill=0.5), "does not take fill="),
    (dict(obstacles=None), "does not take obstacles="),
    (dict(workers=0), "workers must be a positive integer"),
    (dict(n="many"), "n \\(the number of spheres\\) must be a positive integer"),
    (dict(min_radius=-1.0), "min_radius must be a non-negative number"),
])
def test_bad_options_are_named(options, message):
    with pytest.raises(ParameterError, match=message):
        nd.pack_tiled(nd.Box([0, 0], [1, 1]), **{"n": 100, **options})


def test_a_periodic_axis_needs_an_even_number_of_tiles():
    with pytest.raises(ParameterError, match="axis 0 has 3"):
        nd.pack_tiled(nd.Periodic(nd.Box([0, 0], [1, 1])), n=100, tiles=[3, 2], workers=1)
    with pytest.raises(ParameterError, match="periodic box"):
        nd.pack_tiled(nd.Periodic(nd.Ball([0, 0], 1.0)), n=100, workers=1)


def test_the_command_line_packs_one_shape_in_tiles(tmp_path, capsys):
    from ndpack.cli import main

    out = tmp_path / "square.npz"
    assert main(["pack", "box:dim=2", "-n", "400", "--tiles", "4", "--workers", "1", "-q", "-o", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "tiles:    4 x 4 on 1 workers;" in printed and "spheres:  400 (the count asked for)" in printed
    packing = nd.Packing.load(out)
    assert len(packing) == 400 and packing.params["tiled"]["tiles"] == [4, 4]
    assert main(["verify", str(out)]) == 0
    assert main(["pack", "box:dim=2", "-n", "400", "--tiles", "auto", "--fill", "0.5", "-q"]) == 2
    assert "it does not take --fill" in capsys.readouterr().err
    assert main(["pack", "box:dim=2", "box:dim=3", "--tiles", "auto", "-q"]) == 2
    assert "--tiles packs one shape in tiles" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        main(["pack", "box:dim=2", "--tiles", "0,2"])
    assert "give auto, a positive integer" in capsys.readouterr().err


def test_tiles_on_a_dask_cluster_give_the_packing_made_here():
    distributed = pytest.importorskip("distributed")
    square = nd.Box([0, 0], [1, 1])
    cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None)
    with cluster, distributed.Client(cluster) as client:
        remote = nd.pack_tiled(square, n=600, tiles=4, client=client, seed=4, progress=False)
    here = nd.pack_tiled(square, n=600, tiles=4, workers=1, seed=4, progress=False)
    assert remote.params["tiled"]["workers"] == 2 and len(remote) == 600
    np.testing.assert_array_equal(remote.centers, here.centers)
    np.testing.assert_array_equal(remote.radii, here.radii)
