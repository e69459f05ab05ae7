"""A file cannot loosen `verify`: what a check allows comes from the caller, or is named in the
verdict where it comes from the file, and ``--as packing`` / ``kind="packing"`` is strict (issue 45)."""

import subprocess
import sys

import numpy as np
import pytest

import ndpack as nd

SQUARE = nd.Box([0, 0], [1, 1])
#: Two discs apart, the second poking 0.08 out of the right side of the unit square.
CENTERS = np.array([[0.3, 0.5], [0.98, 0.5]])
RADII = np.array([0.2, 0.1])


def run(*args):
    return subprocess.run([sys.executable, "-m", "ndpack.cli", *args], capture_output=True, text=True, timeout=300)


def crafted(tmp_path, name: str, centers=CENTERS, radii=RADII, **params):
    """A packing file recording ``params`` (as a hand-edited file would) and the square as its shape."""
    packing = nd.Packing(centers=centers, radii=radii, rounds=np.arange(len(radii)), volume=1.0,
                         params={"source": "box:dim=2", **params})
    return packing, packing.save(tmp_path / name)


def test_centres_only_from_the_file_is_named_and_as_packing_is_strict(tmp_path):
    _, path = crafted(tmp_path, "poke.json", centers_only=True)
    loaded = nd.Packing.load(path)
    report = loaded.verify(SQUARE)
    assert report.ok and report.from_file == ("centers_only",)
    assert report.summary().startswith("valid as centres only (as the packing records)")
    assert report.kind == "centers_only"
    strict = nd.verify(loaded, SQUARE, kind="packing")
    assert not strict.ok and list(strict.outside) == [1] and strict.from_file == ()
    assert strict.worst_containment == pytest.approx(0.08)
    # The command line: the file's word is named in the verdict, --as packing overrules it.
    loose = run("verify", str(path))
    assert loose.returncode == 0, loose.stderr
    assert "verified: valid as centres only (as the packing records)" in loose.stdout
    assert "--as packing" in loose.stdout
    checked = run("verify", str(path), "--as", "packing")
    assert checked.returncode == 1 and "INVALID: 2 spheres, 1 outside" in checked.stdout, checked.stdout


def test_a_covering_flag_does_not_pass_overlapping_spheres_as_a_packing(tmp_path):
    centers = np.array([[0.5, 0.5], [0.55, 0.5]])  # overlapping by 0.35
    _, path = crafted(tmp_path, "covering.json", centers=centers, radii=np.array([0.2, 0.2]),
                      covering={"protrusion": 0.5})
    told = run("verify", str(path))
    # Checked as a covering, as the file says, and said so in the line with the verdict.
    assert "checked:  as a covering, as the file records" in told.stdout, told.stdout + told.stderr
    strict = run("verify", str(path), "--as", "packing")
    assert strict.returncode == 1 and "INVALID" in strict.stdout and "1 overlapping pairs" in strict.stdout


def test_a_recorded_period_is_named_and_as_packing_drops_it(tmp_path):
    # A disc across the right face: inside only if the square wraps along x.
    centers, radii = np.array([[0.98, 0.5], [0.5, 0.5]]), np.array([0.1, 0.1])
    _, path = crafted(tmp_path, "wrap.json", centers=centers, radii=radii, period=[1.0, None],
                      bounds=[[0.0, 0.0], [1.0, 1.0]])
    loose = run("verify", str(path))
    assert loose.returncode == 0, loose.stdout + loose.stderr
    assert "verified: valid as periodic (as the packing records)" in loose.stdout
    assert run("verify", str(path), "--as", "packing").returncode == 1
    # The caller's own period is not the file's word: no such mention.
    stated = run("verify", str(path), "--as", "packing", "--periodic", "0")
    assert stated.returncode == 0 and "verified: valid: 2 spheres" in stated.stdout, stated.stdout + stated.stderr


def test_kind_is_checked():
    with pytest.raises(nd.NdpackError, match="kind must be one of"):
        nd.verify(CENTERS, SQUARE, radii=RADII, kind="covering")
    with pytest.raises(nd.NdpackError, match="contradicts"):
        nd.verify(CENTERS, SQUARE, radii=RADII, kind="packing", centers_only=True)
    assert nd.verify(CENTERS, SQUARE, radii=RADII, kind="centers_only").ok
