"""Tests of ndpack.consistency: packings that verify() passes but that cannot be right."""

import numpy as np
import pytest

import ndpack as nd
from ndpack.consistency import steep_spheres, volume_problem
from ndpack.oracle import Volume
from ndpack.drivers.greedy.protosphere import _ensure_valid

HOLE_CENTER, HOLE_RADIUS, STEEP_BAND = np.array([0.3, 0.0]), 0.01, 0.01


def holed_disc():
    """The unit disc less a small hole whose distance is overstated 5 times within STEEP_BAND of
    it (and by 4 * STEEP_BAND beyond): steep only in a disc of radius 0.02, which the slope check's
    random pairs (before issue 21) did not meet; spheres beside the hole reach over it."""

    @nd.plugin(dim=2, bounds=[[-1.05, -1.05], [1.05, 1.05]])
    def holed(p):
        disc = np.linalg.norm(p, axis=1) - 1.0
        hole = HOLE_RADIUS - np.linalg.norm(p - HOLE_CENTER, axis=1)  # > 0 in the hole
        steep = np.where(hole >= -STEEP_BAND, 5.0 * hole, hole - 4.0 * STEEP_BAND)
        return np.maximum(disc, steep)

    return holed


#: What holed_disc pretends to be.
TRUE_SHAPE = nd.Ball([0, 0], 1.0) - nd.Ball(HOLE_CENTER, HOLE_RADIUS)


def test_the_slope_check_finds_a_steep_plugin_with_a_small_hole():
    # Random pairs miss the steep disc of radius 0.02; the rays from random points to where
    # their values put the boundary run into it.
    with pytest.raises(nd.OracleError, match="'holed' is not a conservative distance .*constant at least 5"):
        holed_disc().check_lipschitz()


def test_a_steep_plugin_the_slope_check_missed_fails_the_final_check():
    holed = holed_disc()
    holed._slope_checked = True  # as if check_lipschitz had missed it
    with pytest.raises(nd.InvalidPackingError, match="rises faster than a distance across 1 of the 20 spheres") as info:
        nd.pack(holed, n=20, mode="fast", grid=24)
    # It was right to: the first sphere reaches over the hole, and verify() with the plug-in
    # cannot see it. The error keeps the packing as made.
    made = info.value.packing
    assert len(made) == 20 and made.verify().ok
    assert not made.verify(TRUE_SHAPE).ok and list(made.verify(TRUE_SHAPE).outside) == [0]
    assert list(steep_spheres(made, holed)[0]) == [0]
    # Asked to repair, the driver drops the sphere, says so, and records it.
    with pytest.warns(nd.RepairWarning, match="rises faster than a distance"):
        repaired = nd.pack(holed, n=20, mode="fast", grid=24, on_invalid="repair")
    assert len(repaired) == 19 and repaired.verify(TRUE_SHAPE).ok
    assert repaired.repair["steep"] == repaired.repair["dropped"] == 1
    assert repaired.repair["worst_slope"] > 1.5
    assert "1 where the distance rose faster than a distance" in repaired.summary()


def test_a_lower_bound_plugin_passes_the_final_check():
    # The same disc with an honest hole (its true distance halved near the hole: a lower bound).
    @nd.plugin(dim=2, bounds=[[-1.05, -1.05], [1.05, 1.05]])
    def honest(p):
        hole = HOLE_RADIUS - np.linalg.norm(p - HOLE_CENTER, axis=1)
        return np.maximum(np.linalg.norm(p, axis=1) - 1.0, np.where(hole >= 0, hole, 0.5 * hole))

    packing = nd.pack(honest, n=20, mode="fast", grid=24)
    assert packing.repair is None and packing.verify(TRUE_SHAPE).ok
    assert len(steep_spheres(packing, honest)[0]) == 0


def square_packing(volume, volume_error=0.0):
    """Four disjoint circles in the unit square (total area 0.502), with the given volume."""
    centers = np.array([[0.25, 0.25], [0.75, 0.25], [0.25, 0.75], [0.75, 0.75]])
    return nd.Packing(centers, np.full(4, 0.1999), np.arange(4), volume=volume, volume_error=volume_error)


@pytest.mark.parametrize("on_invalid", ["raise", "repair"])
def test_spheres_beyond_the_shapes_volume_are_refused_in_either_mode(on_invalid):
    square = nd.Box([0, 0], [1, 1])
    assert _ensure_valid(square_packing(1.0), square, 1e-10, on_invalid=on_invalid).repair is None
    # Valid spheres, an impossible fill (a wrong volume): nothing can repair that.
    with pytest.raises(nd.InvalidPackingError,
                       match=r"exceeds the shape's volume 0.5 \(exact\): a fill of 1.004") as info:
        _ensure_valid(square_packing(0.5), square, 1e-10, on_invalid=on_invalid)
    assert len(info.value.packing) == 4 and "error.packing" in str(info.value)


def test_a_monte_carlo_volume_is_allowed_its_error():
    covered = square_packing(1.0).covered_volume
    assert volume_problem(square_packing(covered - 4e-3, 1e-3)) is None  # 4 sigma over
    assert "+- 0.001 (a Monte Carlo estimate)" in volume_problem(square_packing(covered - 6e-3, 1e-3))
    assert volume_problem(square_packing(np.inf)) is None  # no volume to hold it to


def test_a_wrong_volume_fails_a_real_run_and_keeps_its_spheres(monkeypatch):
    square = nd.Box([0, 0], [1, 1])
    monkeypatch.setattr(nd.Box, "volume", lambda self, *args, **kwargs: Volume(0.25, 0.0))
    with pytest.raises(nd.InvalidPackingError, match="a fill of 3.") as info:
        nd.pack(square, n=30, mode="fast", grid=16)
    assert len(info.value.packing) == 30 and info.value.packing.verify().ok


def test_the_command_line_keeps_an_invalid_packing_and_flags_an_impossible_file(tmp_path, monkeypatch, capsys):
    from ndpack import cli
    from ndpack.io import shape_sources

    holed = holed_disc()
    holed._slope_checked = True
    monkeypatch.setattr(shape_sources, "load_shape", lambda source, holes=None, sign=None, dim=None: holed)
    out = tmp_path / "holed.npz"
    assert cli.main(["pack", "holed.py", "-n", "20", "--mode", "fast", "--grid", "24", "-q", "-o", str(out)]) == 2
    line = capsys.readouterr().err.strip()
    assert line.startswith("ndpack: error: the packing failed its final check") and "\n" not in line, line
    assert "error.packing" not in line and f"kept in {out}.invalid.npz" in line, line
    assert len(nd.Packing.load(f"{out}.invalid.npz")) == 20 and not out.exists()
    # A file whose spheres exceed its volume: verify and info say so.
    impossible = tmp_path / "impossible.npz"
    square_packing(0.5).save(impossible)
    assert cli.main(["verify", str(impossible), "--shape", "square"]) == 1
    assert "IMPOSSIBLE: the spheres' volume 0.502" in capsys.readouterr().out
    assert cli.main(["info", str(impossible)]) == 0
    assert "IMPOSSIBLE: " in capsys.readouterr().out


def test_a_monte_carlo_volume_below_the_spheres_is_raised_to_theirs():
    # One sphere fills a ball plug-in; the Monte Carlo estimate of its volume came out 0.35%
    # (two standard errors) below the sphere's, and the fill printed as 1.0035.
    @nd.plugin(dim=3, bounds=[[-1.05] * 3, [1.05] * 3])
    def ball(p):
        return np.linalg.norm(p, axis=1) - 1.0

    packing = nd.pack(ball, n=3, grid=8)
    assert len(packing) == 1 and packing.params["volume_estimate"] < packing.covered_volume
    assert packing.volume == packing.covered_volume and packing.fill == packing.stats.fill[-1] == 1.0
    assert packing.volume_error > 0 and "fill 1.0000 +- 0.0017" in packing.summary()
