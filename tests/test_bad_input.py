"""A catalogue of bad input: each gets one clear line (an ndpack error, or the command line's
``ndpack: error: ...`` with exit status 2), never a traceback or a silent wrong answer, and a
failed read or write loses nothing.

What other files already hold is not repeated here: impossible integer parameters and bad
shapes (test_protosphere.py), plug-in construction (shapes/test_plugin.py), garbage files of every format,
missing files and foreign PLY (io/test_formats.py), command-line sources, outputs and random bytes
(test_cli.py). Mesh files (NaN vertices, no faces) belong to shapes/test_mesh.py.
"""

import os
import pickle
from pathlib import Path

import numpy as np
import pytest

import ndpack as nd
from ndpack import cli

NAN, INF = float("nan"), float("inf")
SQUARE = nd.Box([0, 0], [1, 1])

#: protosphere._check_parameters and grid_counts (not this engineer's files, issue 21) pass these
#: on to NumPy or int(), which raise their own errors from deep inside pack().


def one_line(error) -> str:
    text = str(error)
    assert text and "\n" not in text and "Traceback" not in text, text
    return text


# ------------------------------------------------------------------------------ nd.pack parameters
@pytest.mark.parametrize("name, value, words", [
    ("n", NAN, "n (the number of spheres) must be a positive integer"),
    ("n", INF, "n (the number of spheres) must be a positive integer"),
    ("min_radius", NAN, "min_radius must be a non-negative number"),
    ("min_radius", INF, "min_radius must be a non-negative number"),
    ("fill", NAN, "fill (the target fill fraction) must lie in (0, 1)"),
    ("fill", INF, "fill (the target fill fraction) must lie in (0, 1)"),
    ("time_budget", NAN, "time_budget must be a positive number"),
    ("grid", [NAN, 4], "grid must be a positive integer or 2 of them"),
    ("iterations", NAN, "iterations must be a positive integer"),
    ("batch", INF, "batch must be a positive integer"),
    ("restarts", NAN, "restarts must be a non-negative integer"),
    ("seed", NAN, "seed must be None, an integer >= 0"),
    ("mode", None, "mode must be 'auto', 'faithful' or 'fast'"),
    ("time_budget", INF, "time_budget must be"),
    ("grid", NAN, "grid must be"),
    ("grid", INF, "grid must be"),
    ("grid", [INF, 4], "grid must be"),
    ("grid", True, "grid must be"),
    ("seed", "1", "seed must be"),
    ("fill", "0.5", "fill"),
    ("time_budget", "1", "time_budget"),
])
def test_impossible_numbers_for_pack_are_refused_in_one_line(name, value, words):
    with pytest.raises(nd.ParameterError) as info:
        nd.pack(SQUARE, **{name: value})
    assert words in one_line(info.value)


# ------------------------------------------------------------------------------ shapes
@pytest.mark.parametrize("make, words", [
    (lambda: nd.Ball([NAN, 0], 1), "center must be finite"),
    (lambda: nd.Ball([INF, 0], 1), "center must be finite"),
    (lambda: nd.Ball([0, 0], NAN), "radius must be a positive finite number"),
    (lambda: nd.Ball([0, 0], INF), "radius must be a positive finite number"),
    (lambda: nd.Box([NAN, 0], [1, 1]), "lower must be finite"),
    (lambda: nd.Box([0, 0], [1, INF]), "upper must be finite"),
    (lambda: nd.RoundedBox([0, 0], [1, 1], NAN), "radius must be a positive finite number"),
    (lambda: nd.Ellipsoid([0, 0], [1, NAN]), "radii must be finite"),
    (lambda: nd.Ellipsoid([0, 0], [1, INF]), "radii must be finite"),
    (lambda: nd.Capsule([0, 0], [1, NAN], 0.1), "b must be finite"),
    (lambda: nd.Cylinder([0, 0, 0], [1, 0, 0], NAN), "radius must be a positive finite number"),
    (lambda: nd.Torus([0, 0, 0], NAN, 0.1), "major_radius must be a positive finite number"),
    (lambda: nd.Simplex([[0, 0], [1, 0], [0, NAN]]), "vertices must be finite"),
    (lambda: nd.HalfSpace([NAN, 0], 0), "normal must be finite"),
    (lambda: nd.Slab([1, 0], NAN, 1), "lower must be finite"),
    (lambda: nd.Polygon([(0, 0), (1, NAN), (0, 1)]), "non-finite coordinates"),
    (lambda: SQUARE.translate([NAN, 0]), "offset must be finite"),
    (lambda: SQUARE.scale_by(NAN), "scale factor must be a positive number"),
    (lambda: SQUARE.scale_by(INF), "scale factor must be a positive"),
    (lambda: SQUARE.offset(INF), "offset amount must be finite"),
    (lambda: SQUARE.shell(NAN), "shell thickness must be positive"),
    (lambda: SQUARE.smooth_union(nd.Ball([0, 0], 1), NAN), "blend must be positive"),
    (lambda: SQUARE.rotate([[NAN, 0], [0, 1]]), "not orthogonal"),
])
def test_nan_and_infinite_sizes_of_shapes_are_refused(make, words):
    with pytest.raises(nd.ShapeError) as info:
        make()
    assert words in one_line(info.value)


@pytest.mark.parametrize("make, words", [
    (lambda: nd.Box([0, 0], [1, 0]), "lower must be < upper on every axis"),
    (lambda: nd.Simplex([[0, 0], [1, 0], [2, 0]]), "degenerate simplex"),
    (lambda: nd.Polygon([(0, 0), (1, 0), (2, 0)]), "zero area"),
    (lambda: nd.Ball([0, 0], 0.0), "radius must be a positive finite number"),
])
def test_degenerate_shapes_are_refused(make, words):
    with pytest.raises(nd.ShapeError) as info:
        make()
    assert words in one_line(info.value)


@pytest.mark.parametrize("shape, words", [
    (SQUARE - SQUARE, "found no interior point"),
    (SQUARE - nd.Box([-1, -1], [2, 2]), "found no interior point"),
    (nd.Ball([0, 0], 1) & nd.Ball([5, 0], 1), "there is nothing to pack"),
    (nd.Function(lambda p: np.full(len(p), 1.0), 2, [[0, 0], [1, 1]], name="nowhere"), "found no interior point"),
    # Rounding at 1e12 is far coarser than the ball: the safety margin (1e-10 of the scale, 100)
    # leaves no room. Before issue 21 this returned a packing of no spheres, "no room".
    (nd.Ball([1e12, 0], 1.0), "no sphere fits"),
])
def test_empty_shapes_are_refused_when_packed(shape, words):
    with pytest.raises(nd.ShapeError) as info:
        nd.pack(shape, n=5, grid=8)
    assert words in one_line(info.value)


def test_shapes_smaller_than_a_cell_pack_or_are_left_out_validly():
    # The grid follows the bounds: a shape of 1e-9 packs as a large one does.
    tiny = nd.pack(nd.Box([0, 0], [1e-9, 1e-9]), n=5, grid=8)
    assert len(tiny) == 5 and tiny.verify().ok and tiny.radii[0] == pytest.approx(5e-10, rel=1e-6)
    # A part far smaller than a cell of the whole may get no sphere (a known limit), but no
    # error and no invalid sphere.
    speck = nd.Ball([3.5, 3.5], 1e-3)
    packing = nd.pack(SQUARE | speck, n=20, grid=4)
    assert len(packing) == 20 and packing.verify().ok


def test_dimension_one_and_twelve():
    with pytest.raises(nd.DimensionError) as info:
        nd.Box([0], [1])
    assert "at least 2 coordinates" in one_line(info.value)
    with pytest.raises(nd.DimensionError):
        nd.Function(lambda p: p[:, 0], 0, np.zeros((2, 0)))
    segment = nd.Function(lambda p: np.abs(p[:, 0]) - 1.0, 1, [[-2], [2]], name="segment")
    packing = nd.pack(segment, n=3, grid=8)
    assert len(packing) == 1 and packing.stop_reason == "no_room" and packing.verify().ok
    assert packing.radii[0] == pytest.approx(1.0)
    cube = nd.pack(nd.Box(np.zeros(12), np.ones(12)), n=3, grid=2)
    assert len(cube) == 3 and cube.verify().ok and cube.radii[0] == pytest.approx(0.5)
    ball = nd.pack(nd.Ball(np.zeros(12), 1.0), n=3, grid=2)
    assert len(ball) == 1 and ball.stop_reason == "no_room" and ball.fill == pytest.approx(1.0)
    with pytest.raises(nd.DimensionError):
        nd.Ball(np.zeros(12), 1.0) | nd.Ball(np.zeros(11), 1.0)


# ------------------------------------------------------------------------------ files
@pytest.fixture(scope="module")
def saved(tmp_path_factory):
    """A small packing saved as .npz and .csv, and its arrays."""
    folder = tmp_path_factory.mktemp("bad-input")
    packing = nd.pack(SQUARE, n=10, grid=8)
    npz, csv = packing.save(folder / "good.npz"), packing.save(folder / "good.csv")
    with np.load(npz) as data:
        arrays = dict(data)
    return packing, npz, csv, arrays


def _npz(folder: Path, arrays: dict, **changes) -> Path:
    path = folder / "changed.npz"
    arrays = {**arrays, **changes}
    np.savez(path, **{name: value for name, value in arrays.items() if value is not None})
    return path


NPZ_DAMAGE = {
    "a NaN radius": (dict(radii=np.r_[NAN, np.ones(9)]), "1 of its radii are not positive finite numbers"),
    "negative radii": (dict(radii=-np.ones(10)), "10 of its radii are not positive finite numbers"),
    "an infinite centre": (dict(centers=np.r_[[[INF, 0.0]], np.zeros((9, 2))]), "1 of its centres are not finite"),
    "radii missing": (dict(radii=None), "it has no 'radii'"),
    "fewer radii": (dict(radii=np.ones(5)), "it has 10 centres, 5 radii and 10 rounds"),
    "text radii": (dict(radii=np.array(["a"] * 10)), "could not convert string to float"),
    "metadata not JSON": (dict(metadata=np.array("{not json")), "its JSON is not valid"),
    "a negative volume": (dict(metadata=np.array('{"format": "ndpack-packing", "version": 1, "dim": 2, "volume": -1}')),
                          "its volume -1 is not a non-negative number"),
    "a dimension of 0": (dict(metadata=np.array('{"format": "ndpack-packing", "version": 1, "dim": 0}')),
                         "its dimension 0 is not a positive integer"),
}


@pytest.mark.parametrize("damage", list(NPZ_DAMAGE))
def test_a_damaged_npz_is_refused_by_load_and_by_the_command_line(saved, tmp_path, capsys, damage):
    changes, words = NPZ_DAMAGE[damage]
    path = _npz(tmp_path, saved[3], **changes)
    before = path.read_bytes()
    with pytest.raises(nd.NdpackError) as info:
        nd.Packing.load(path)
    assert "is not a readable ndpack packing (npz format)" in one_line(info.value) and words in str(info.value)
    for command in (["verify", str(path), "--shape", "square"], ["info", str(path)]):
        assert words in cli_error(capsys, *command)
    assert path.read_bytes() == before  # nothing lost


CSV_DAMAGE = {
    "a NaN coordinate": ("nan,0.5,0.1,0", "1 of its centres are not finite"),
    "a negative radius": ("0.5,0.5,-0.1,0", "1 of its radii are not positive finite numbers"),
    "words": ("a,b,c,d", "could not convert string 'a'"),
    "a short row": ("0.5,0.5", "its rows differ in length"),
    "every row short": (None, "its rows have 3 columns, but a 2-D packing has 4"),
}


@pytest.mark.parametrize("damage", list(CSV_DAMAGE))
def test_a_damaged_csv_is_refused_by_load_and_by_the_command_line(saved, tmp_path, capsys, damage):
    row, words = CSV_DAMAGE[damage]
    lines = saved[2].read_text().splitlines()
    if row is None:
        lines = lines[:2] + [",".join(line.split(",")[:3]) for line in lines[2:]]
    else:
        lines = lines[:2] + [row] + lines[3:]
    path = tmp_path / "changed.csv"
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(nd.NdpackError) as info:
        nd.Packing.load(path)
    assert "is not a readable ndpack packing (csv format)" in one_line(info.value) and words in str(info.value)
    assert words in cli_error(capsys, "verify", str(path), "--shape", "square")


def test_a_csv_of_no_spheres_loads_without_a_warning(saved, tmp_path, recwarn):
    path = tmp_path / "none.csv"
    path.write_text("\n".join(saved[2].read_text().splitlines()[:2]) + "\n")
    assert len(nd.Packing.load(path)) == 0 and not recwarn.list


@pytest.mark.parametrize("kind", ["empty", "random", "pickled"])
@pytest.mark.parametrize("suffix", [".npz", ".csv", ".json"])
def test_empty_random_and_pickled_bytes_are_refused(tmp_path, capsys, kind, suffix):
    content = {"empty": b"", "random": np.random.default_rng(1).bytes(3000),
               "pickled": pickle.dumps({"centers": [0.0]})}[kind]
    words = {"empty": "it is empty (0 bytes)", "random": "is not a readable ndpack packing",
             "pickled": "which ndpack never loads" if suffix == ".npz" else "is not a readable ndpack packing"}[kind]
    path = tmp_path / f"bytes{suffix}"
    path.write_bytes(content)
    with pytest.raises(nd.NdpackError) as info:
        nd.Packing.load(path)
    assert words in one_line(info.value) and "allow_pickle" not in str(info.value)
    line = cli_error(capsys, "info", str(path))
    assert words in line and "allow_pickle" not in line


class _Payload:
    """Unpickling it leaves a marker file: proof that a loader ran code a file carried."""

    marker = None

    def __reduce__(self):
        return (Path.touch, (Path(self.marker),))


def test_loaders_never_unpickle(saved, tmp_path, capsys):
    _Payload.marker = str(tmp_path / "unpickled")
    payload = np.empty(10, dtype=object)
    payload[:] = [_Payload() for _ in range(10)]
    carrying = _npz(tmp_path, saved[3], radii=payload)
    plain = tmp_path / "plain.npz"
    plain.write_bytes(pickle.dumps(_Payload()))
    for path in (carrying, plain):
        with pytest.raises(nd.NdpackError, match="never loads"):
            nd.Packing.load(path)
        for command in ("info", "verify", "render"):
            cli_error(capsys, command, str(path), *(["-o", str(tmp_path / "x.svg")] if command == "render" else []))
    assert not (tmp_path / "unpickled").exists()
    pickle.loads(pickle.dumps(_Payload()))  # the marker works: unpickling does make it
    assert (tmp_path / "unpickled").exists()


def test_folders_unreadable_and_unwritable_paths(saved, tmp_path, capsys, monkeypatch):
    packing = saved[0]
    folder = tmp_path / "folder.npz"
    folder.mkdir()
    with pytest.raises(nd.NdpackError) as info:
        nd.Packing.load(folder)
    assert "is a folder, not a packing file" in one_line(info.value)
    with pytest.raises(nd.NdpackError) as info:
        packing.save(folder)
    assert "cannot write" in one_line(info.value) and folder.is_dir()
    assert "is a folder" in cli_error(capsys, "info", str(folder))
    # Unreadable: root reads anything, so the refusal is made by the operating system's error.
    unreadable = tmp_path / "unreadable.npz"
    unreadable.write_bytes(saved[1].read_bytes())

    def refused(*args, **kwargs):
        raise PermissionError(13, "Permission denied", str(unreadable))

    with monkeypatch.context() as patch:
        patch.setattr(np, "load", refused)
        with pytest.raises(nd.NdpackError) as info:
            nd.Packing.load(unreadable)
        assert "Permission denied" in one_line(info.value)
    if os.geteuid() != 0:
        unreadable.chmod(0)
        with pytest.raises(nd.NdpackError, match="Permission denied"):
            nd.Packing.load(unreadable)
    # Unwritable: a folder that does not exist, and one nobody may write (where there is one).
    with pytest.raises(nd.NdpackError) as info:
        packing.save(tmp_path / "no-such-folder" / "p.csv")
    assert "cannot write" in one_line(info.value)
    if os.path.isdir("/proc"):
        with pytest.raises(nd.NdpackError, match="cannot write"):
            packing.save("/proc/ndpack-test.npz")
    assert saved[1].exists() and len(nd.Packing.load(saved[1])) == 10  # nothing lost


def cli_error(capsys, *argv) -> str:
    """Run the command line in this process; it must exit 2 with one line, ``ndpack: error: ...``."""
    capsys.readouterr()
    assert cli.main(list(argv)) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("ndpack: error: ") and "\n" not in err and "Traceback" not in err, err
    return err
