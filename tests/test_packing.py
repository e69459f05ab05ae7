"""Packing results: derived values and the .npz / .csv files."""

import json

import numpy as np
import pytest

import ndpack as nd


@pytest.fixture(scope="module")
def packing():
    return nd.pack(nd.Box([0, 0, 0], [1, 1, 1]) - nd.Ball([1, 1, 1], 0.6), n=40, seed=0)


def test_fields_have_documented_shapes(packing):
    n = len(packing)
    assert packing.centers.shape == (n, 3) and packing.radii.shape == (n,) and packing.rounds.shape == (n,)
    assert packing.dim == 3 and n == 40
    assert packing.medial_axis.shape[1] == 3 and len(packing.medial_radii) == len(packing.medial_axis)
    assert packing.params["n"] == 40 and packing.params["iterations"] == 50
    assert packing.volume_error > 0  # a CSG volume is a Monte Carlo estimate ...
    exact = 1 - nd.ball_volume(3, 0.6) / 8
    assert abs(packing.volume - exact) < 5 * packing.volume_error  # ... that is right
    assert packing.fill == pytest.approx(nd.ball_volume(3, packing.radii).sum() / packing.volume)
    assert "40 spheres in 3-D" in packing.summary()


@pytest.mark.parametrize("suffix", [".npz", ".csv"])
def test_save_and_load_round_trip(packing, tmp_path, suffix):
    path = packing.save(tmp_path / f"part{suffix}")
    loaded = nd.Packing.load(path)
    np.testing.assert_array_equal(loaded.centers, packing.centers)  # %.17g keeps every bit
    np.testing.assert_array_equal(loaded.radii, packing.radii)
    np.testing.assert_array_equal(loaded.rounds, packing.rounds)
    assert loaded.volume == packing.volume and loaded.params == packing.params
    assert loaded.stop_reason == packing.stop_reason and loaded.fill == packing.fill
    if suffix == ".npz":
        np.testing.assert_array_equal(loaded.stats.fill, packing.stats.fill)
        np.testing.assert_array_equal(loaded.medial_axis, packing.medial_axis)
    assert loaded.verify(packing.shape).ok
    with pytest.raises(nd.NdpackError, match="needs the shape"):
        loaded.verify()


def test_csv_is_readable_by_other_tools(packing, tmp_path):
    path = packing.save(tmp_path / "part.csv")
    lines = path.read_text().splitlines()
    assert json.loads(lines[0][2:])["format"] == "ndpack-packing"
    assert lines[1] == "x0,x1,x2,radius,round"
    assert len(lines) == 2 + len(packing)


def test_bad_files_get_clear_errors(packing, tmp_path):
    with pytest.raises(nd.NdpackError, match="no such packing file"):
        nd.Packing.load(tmp_path / "missing.npz")
    with pytest.raises(nd.NdpackError, match=r"\.npz or \.csv"):
        packing.save(tmp_path / "part.xyz")
    (tmp_path / "other.csv").write_text("a,b\n1,2\n")
    with pytest.raises(nd.NdpackError, match="not a readable ndpack packing"):
        nd.Packing.load(tmp_path / "other.csv")
