"""Files for DEM codes (LAMMPS and LIGGGHTS data files, Yade text): written, read back exactly,
laid out as those programs read them, hand-written files read, bad input refused clearly."""

import dataclasses
import subprocess
import sys

import numpy as np
import pytest

import ndpack as nd
from ndpack import io as ndio
from ndpack.errors import DimensionError, NdpackError


@pytest.fixture(scope="module")
def cube():
    return nd.pack(nd.Box([0, 0, 0], [1, 1, 1]), n=50, mode="fast", backend="numpy")


@pytest.fixture(scope="module")
def square():
    return nd.pack(nd.Box([0, 0], [1, 1]), n=40, mode="fast", backend="numpy")


def spheres_only(centers, radii) -> nd.Packing:
    centers = np.asarray(centers, dtype=np.float64)
    return nd.Packing(centers=centers, radii=np.asarray(radii, dtype=np.float64),
                      rounds=np.zeros(len(centers), dtype=np.int64), volume=1.0)


def assert_same_spheres(loaded, packing):
    assert loaded.centers.shape == packing.centers.shape and loaded.centers.dtype == np.float64
    np.testing.assert_array_equal(loaded.centers, packing.centers)
    np.testing.assert_array_equal(loaded.radii, packing.radii)


def atoms_rows(text: str) -> list[list[str]]:
    """The rows of the Atoms section, as LAMMPS reads them: after the section line and one more."""
    lines = text.splitlines()
    start = next(i for i, line in enumerate(lines) if line.split("#")[0].strip() == "Atoms")
    assert lines[start + 1] == ""
    count = int(next(line.split()[0] for line in lines if line.split("#")[0].split()[1:] == ["atoms"]))
    return [line.split() for line in lines[start + 2 : start + 2 + count]]


def header_values(text: str, keyword: str) -> list[float]:
    for line in text.splitlines()[1:]:
        words = line.split("#")[0].split()
        if words and " ".join(words[-len(keyword.split()):]) == keyword:
            return [float(word) for word in words[: -len(keyword.split())]]
    raise AssertionError(f"no {keyword!r} line")


# ---------------------------------------------------------------------------------- round trips
@pytest.mark.parametrize("name, format", [("bed.data", None), ("bed.data", "lammps"), ("bed_l.data", "liggghts"),
                                          ("bed.txt", None), ("bed.txt", "yade")])
def test_round_trip_3d(cube, tmp_path, name, format):
    path = cube.save(tmp_path / name, format=format)
    assert_same_spheres(nd.Packing.load(path), cube)
    assert_same_spheres(nd.Packing.load(path, format=format), cube)


@pytest.mark.parametrize("format", ["lammps", "liggghts"])
def test_round_trip_2d(square, tmp_path, format):
    path = square.save(tmp_path / "disks.data", format=format)
    loaded = nd.Packing.load(path)
    assert loaded.dim == 2
    assert_same_spheres(loaded, square)


def test_named_lammps_formats_take_any_file_name(cube, tmp_path):
    path = cube.save(tmp_path / "data.bed", format="lammps", density=2500)
    assert_same_spheres(nd.Packing.load(path, format="lammps"), cube)
    path = cube.save(tmp_path / "bed.lig", format="liggghts")
    assert_same_spheres(nd.Packing.load(path, format="liggghts"), cube)
    with pytest.raises(NdpackError, match="unknown suffix '.bed'"):
        nd.Packing.load(tmp_path / "data.bed")


def test_empty_packings_round_trip(tmp_path):
    empty = spheres_only(np.zeros((0, 3)), np.zeros(0))
    for name in ("empty.data", "empty.txt"):
        loaded = nd.Packing.load(empty.save(tmp_path / name))
        assert len(loaded) == 0 and loaded.dim == 3
    assert "Atoms" not in (tmp_path / "empty.data").read_text()  # LAMMPS wants none for 0 atoms


# ---------------------------------------------------------------------------------- layout
def test_lammps_file_is_laid_out_as_read_data_expects(cube, tmp_path):
    text = cube.save(tmp_path / "bed.data", density="2500").read_text()
    lines = text.splitlines()
    assert lines[0].startswith("LAMMPS data file") and not lines[0].startswith("#")
    assert f"{len(cube)} atoms" in lines and "1 atom types" in lines
    assert "Atoms # sphere" in lines
    rows = atoms_rows(text)
    assert len(rows) == len(cube)
    assert all(len(row) == 7 for row in rows)
    table = np.array([[float(word) for word in row] for row in rows])
    np.testing.assert_array_equal(table[:, 0], np.arange(1, len(cube) + 1))  # IDs, in packing order
    np.testing.assert_array_equal(table[:, 1], 1)  # one atom type
    np.testing.assert_array_equal(table[:, 2], 2 * cube.radii)  # diameters
    np.testing.assert_array_equal(table[:, 3], 2500)  # density
    np.testing.assert_array_equal(table[:, 4:], cube.centers)
    assert lines[-1] == " ".join(rows[-1]) and text.endswith("\n")  # nothing after the rows
    assert max(len(line) for line in lines) < 254  # LAMMPS reads lines up to 254 characters


def test_box_lines_hold_the_shape_bounds(cube, square, tmp_path):
    text = cube.save(tmp_path / "bed.data").read_text()
    bounds = cube.shape.bounds
    for axis, keyword in enumerate(("xlo xhi", "ylo yhi", "zlo zhi")):
        assert header_values(text, keyword) == [bounds[0][axis], bounds[1][axis]]
    assert "box: the shape's bounds" in text and "boundary f f f" in text
    text = square.save(tmp_path / "disks.data").read_text()
    assert header_values(text, "xlo xhi") == [0, 1] and header_values(text, "ylo yhi") == [0, 1]
    zlo, zhi = header_values(text, "zlo zhi")
    assert zlo < 0 < zhi  # a 2-D box straddles z = 0
    assert "dimension 2" in text and "boundary f f p" in text
    assert all(float(row[6]) == 0 for row in atoms_rows(text))


def test_box_without_a_shape_is_the_spheres_extent(tmp_path):
    packing = spheres_only([[0, 0, 0], [3, 1, 0.5]], [0.5, 0.25])
    text = packing.save(tmp_path / "two.data").read_text()
    assert header_values(text, "xlo xhi") == [-0.5, 3.25]
    assert header_values(text, "ylo yhi") == [-0.5, 1.25]
    assert header_values(text, "zlo zhi") == [-0.5, 0.75]
    assert "spheres' extent" in text


def test_periodic_domain_params_set_the_box(cube, tmp_path):
    params = {**cube.params, "bounds": [[0, 0, 0], [1, 1, 1]], "period": [1.0, None, 2.0]}
    periodic = dataclasses.replace(cube, params=params)
    text = periodic.save(tmp_path / "cell.data").read_text()
    assert header_values(text, "xlo xhi") == [0, 1] and header_values(text, "zlo zhi") == [0, 2]
    assert "periodic in x z" in text and "boundary p f p" in text
    periodic.params["period"] = [1.0, None]
    with pytest.raises(NdpackError, match="periods must be a list of 3"):
        periodic.save(tmp_path / "bad.data")


def test_a_periodic_bed_keeps_its_period_through_a_data_file(tmp_path):
    """Written with ``boundary p p p``, it loads with the cell and periods, verifies as periodic
    (spheres cross the faces), and is written again the same; a file without the line has none."""
    bed = nd.pack(nd.Periodic(nd.Box([0, 0, 0], [1, 1, 1])), n=30, grid=6, backend="numpy")
    assert ((bed.centers - bed.radii[:, None] < 0) | (bed.centers + bed.radii[:, None] > 1)).any()
    for program in ("lammps", "liggghts"):
        path = bed.save(tmp_path / f"pbox-{program}.data", format=program)
        loaded = nd.Packing.load(path, format="lammps")
        assert loaded.params == {"bounds": [[0, 0, 0], [1, 1, 1]], "period": [1.0, 1.0, 1.0]}
        assert_same_spheres(loaded, bed)
        assert loaded.save(tmp_path / "again.data", format=program).read_text() == path.read_text()
    result = subprocess.run([sys.executable, "-m", "ndpack.cli", "verify", str(tmp_path / "pbox-lammps.data"),
                             "--shape", "box:dim=3"], capture_output=True, text=True, timeout=300)
    assert result.returncode == 0 and "against Periodic(Box(" in result.stdout, result.stdout + result.stderr
    # One open axis, in 2-D (z is written periodic for LAMMPS's `dimension 2`, and not kept).
    slab = nd.pack(nd.Periodic(nd.Box([0, 0], [2, 1]), axes=[0]), n=10, grid=8, backend="numpy")
    assert nd.Packing.load(slab.save(tmp_path / "slab.data")).params == {"bounds": [[0, 0], [2, 1]],
                                                                         "period": [2.0, None]}
    # A shape whose cell is not the recorded one is refused, not checked against other images.
    with pytest.raises(NdpackError, match="records a period of 2 along axis 0, but the shape"):
        from ndpack.cli import _recorded_shape

        _recorded_shape(nd.Packing.load(tmp_path / "slab.data"), "box:dim=2", required=True)
    text = (tmp_path / "pbox-lammps.data").read_text().replace("boundary p p p", "boundary f f f")
    (tmp_path / "closed.data").write_text(text)
    assert nd.Packing.load(tmp_path / "closed.data").params == {}


def test_liggghts_file(cube, square, tmp_path):
    text = cube.save(tmp_path / "bed.data", format="liggghts", density=2500).read_text()
    lines = text.splitlines()
    assert lines[0].startswith("LIGGGHTS data file") and "Atoms" in lines  # no style comment on it
    rows = atoms_rows(text)
    assert len(rows) == len(cube) and all(len(row) == 7 and row[1] == "1" for row in rows)
    assert "mass per volume" in text
    text = square.save(tmp_path / "disks.data", format="liggghts").read_text()
    assert "mass per area" in text and "dimension 2" in text  # LIGGGHTS: density * pi r^2 in 2-D


def test_yade_file_is_laid_out_as_ymport_text_expects(cube, tmp_path):
    text = cube.save(tmp_path / "bed.txt").read_text()
    lines = text.splitlines()
    assert lines[0] == "#format x_y_z_r"
    # Yade's reader looks at the first word of every line: no blank lines, comments start with '#'.
    assert all(line.split() for line in lines)
    rows = [line.split() for line in lines if not line.startswith("#")]
    assert len(rows) == len(cube) and all(len(row) == 4 for row in rows)
    np.testing.assert_array_equal(np.array(rows, dtype=float), np.column_stack([cube.centers, cube.radii]))


# ---------------------------------------------------------------------------------- hand-written files
HAND_DATA = """LAMMPS data file via write_data, version 22 Jul 2025, timestep = 1000, units = si

3 atoms
1 atom types

0 10 xlo xhi
0 10 ylo yhi   # a comment
-1 10 zlo zhi
0 0 0 xy xz yz

Atoms # sphere

3 1 1.5 2500 7 7 7 0 0 1
1 1 1 2500 1 2 3 0 0 0
2 1 2 2600 4 5 6 -1 0 0  # tagged

Velocities

1 0 0 0 0 0 0
3 0.1 0 0 0 0 0
2 0 0 0 0 0 0
"""


def test_read_a_hand_written_lammps_file(tmp_path):
    path = tmp_path / "hand.data"
    path.write_text(HAND_DATA)
    loaded = nd.Packing.load(path)
    assert loaded.dim == 3
    np.testing.assert_array_equal(loaded.centers, [[1, 2, 3], [4, 5, 6], [7, 7, 7]])  # in atom-ID order
    np.testing.assert_array_equal(loaded.radii, [0.5, 1, 0.75])
    centers, radii, info = ndio.read_data(path)
    np.testing.assert_array_equal(info["ids"], [1, 2, 3])
    np.testing.assert_array_equal(info["density"], [2500, 2600, 2500])
    np.testing.assert_array_equal(info["box"], [[0, 0, -1], [10, 10, 10]])
    # Without the style comment, rows of 7 (or 10, with image flags) values are read as sphere rows.
    path.write_text(HAND_DATA.replace("Atoms # sphere", "Atoms"))
    assert_same_spheres(nd.Packing.load(path), loaded)


def test_read_a_hand_written_yade_file(tmp_path):
    path = tmp_path / "pack.txt"
    path.write_text("#format x_y_z_r\n# made by hand\n0 0 0 1\n\n2.5\t0\t0\t1.5\t7\n"
                    "#another comment\n-1e-3 1E2 3 0.25\n")
    loaded = nd.Packing.load(path)
    np.testing.assert_array_equal(loaded.centers, [[0, 0, 0], [2.5, 0, 0], [-1e-3, 100, 3]])
    np.testing.assert_array_equal(loaded.radii, [1, 1.5, 0.25])
    path.write_text("#format id_x_y_z_r_matId\n4 1 2 3 0.5 1\n")  # Yade's other layout
    centers, radii = ndio.read_yade(path)
    np.testing.assert_array_equal(centers, [[1, 2, 3]])
    np.testing.assert_array_equal(radii, [0.5])
    path.write_text("1 2 3 0.5\n")  # no header: x_y_z_r, as in Yade
    assert len(nd.Packing.load(path)) == 1


# ---------------------------------------------------------------------------------- errors
def test_dimensions_a_format_cannot_hold_are_refused(tmp_path):
    tesseract = spheres_only(np.zeros((1, 4)), [0.5])
    for name, format in (("t.data", None), ("t.data", "liggghts"), ("t.txt", None)):
        with pytest.raises(DimensionError, match="not a 4-D packing"):
            tesseract.save(tmp_path / name, format=format)
    with pytest.raises(DimensionError, match=r"lammps format \(\.data\) holds spheres in 2 to 3 dimensions, not a 1-D"):
        spheres_only(np.zeros((1, 1)), [0.5]).save(tmp_path / "rod.data")
    with pytest.raises(DimensionError, match=r"yade format \(\.txt\) holds 3-D spheres, not a 2-D packing"):
        spheres_only(np.zeros((1, 2)), [0.5]).save(tmp_path / "disk.txt")
    with pytest.raises(DimensionError, match="not a 4-D packing"):
        ndio.check(tmp_path / "t.data", None, 4)
    assert not list(tmp_path.iterdir())


@pytest.mark.parametrize("density", ["abc", 0, -2.5, float("nan"), True])
def test_bad_density_is_refused(cube, tmp_path, density):
    with pytest.raises(NdpackError, match="density must be a positive number"):
        cube.save(tmp_path / "bed.data", density=density)


def test_bad_lammps_files_get_clear_errors(cube, tmp_path):
    text = cube.save(tmp_path / "bed.data").read_text()
    lines = text.splitlines()
    cut = tmp_path / "cut.data"
    cut.write_text("\n".join(lines[:-10]) + "\n")  # fewer rows than "50 atoms"
    with pytest.raises(NdpackError, match=rf"cut.data .*truncated: its header says {len(cube)} atoms, its Atoms "
                                          rf"section has {len(cube) - 10} rows"):
        nd.Packing.load(cut)
    bad = tmp_path / "bad.data"
    for changes, message in (
        ([("0 0 0 xy xz yz", "1 0 0 xy xz yz")], "triclinic box"),
        ([("# sphere", "# full")], "atom_style full, not sphere"),
        ([("Atoms # sphere", "Atoms"), ("2500 1 2 3 0 0 0", "2500 1 2 3 0 0")], "names no atom style.* 9 values"),
        ([("2500 1 2 3 0 0 0", "2500 1 2")], "has 6 values; an atom_style sphere row has 7"),
        ([("3 atoms", "4 atoms")], "truncated: its header says 4 atoms"),
        ([("\n1 1 1 2500", "\n2 1 1 2500")], "atom ID 2 is used twice"),
        ([("1 1 1 2500", "1 1 0 2500")], "radii are not positive"),
    ):
        source = HAND_DATA
        for change in changes:
            assert change[0] in source
            source = source.replace(*change)
        bad.write_text(source)
        with pytest.raises(NdpackError, match=message):
            nd.Packing.load(bad)
    bad.write_text("LAMMPS data\n\n2 atoms\n")
    with pytest.raises(NdpackError, match="2 atoms but it has no Atoms section"):
        nd.Packing.load(bad)


def test_bad_yade_files_get_clear_errors(tmp_path):
    bad = tmp_path / "bad.txt"
    bad.write_text("#format x_y_z\n1 2 3\n")
    with pytest.raises(NdpackError, match="names the format x_y_z"):
        nd.Packing.load(bad)
    bad.write_text("#format x_y_z_r\n1 2 3\n")
    with pytest.raises(NdpackError, match="line 2 is not 'x y z r' numbers"):
        nd.Packing.load(bad)


# ---------------------------------------------------------------------------------- the table, the CLI
def test_the_formats_are_in_the_table():
    assert {"lammps", "liggghts", "yade"} <= set(ndio.names())
    assert ndio.SUFFIXES[".data"] == "lammps" and ndio.SUFFIXES[".txt"] == "yade"
    assert "density=1.0" in ndio.table()


def run(*args, cwd=None):
    return subprocess.run([sys.executable, "-m", "ndpack.cli", *args], capture_output=True, text=True, timeout=300,
                          cwd=cwd)


def test_cli_packs_to_a_lammps_file_and_reads_it(tmp_path):
    out = tmp_path / "out.data"
    result = run("pack", "demo", "-n", "30", "--mode", "fast", "-o", str(out), "--option", "density=2500")
    assert result.returncode == 0, result.stderr
    assert "30 atoms" in out.read_text().splitlines() and "density 2500:" in out.read_text()
    result = run("info", str(out))
    assert result.returncode == 0, result.stderr
    assert "spheres:    30 in 3-D" in result.stdout


def test_atom_types_are_size_classes_and_a_yade_cell_reads_back(tmp_path):
    cell = nd.Periodic(nd.Box(np.zeros(3), np.ones(3)))
    classes = nd.SizeDistribution.discrete([0.06, 0.1], [0.5, 0.5], by="mass")
    bed = nd.pack_dense(cell, classes, n=60, progress=False)
    bed.save(tmp_path / "bed.data")
    centers, radii, info = ndio.dem.read_data(tmp_path / "bed.data")
    text = (tmp_path / "bed.data").read_text()
    assert "2 atom types" in text and "# atom types by radius: 1 r=" in text
    small = radii < radii.max() * 0.8
    assert set(info["types"][small]) == {1} and set(info["types"][~small]) == {2}
    bed.save(tmp_path / "one.data", types="one")
    assert "1 atom types" in (tmp_path / "one.data").read_text()
    with pytest.raises(nd.NdpackError, match="types must be"):
        bed.save(tmp_path / "bad.data", types="sizes")
    # Equal spheres: one type; a few distinct radii: one type each.
    kinds, type_radii = ndio.dem.size_types([0.1, 0.2, 0.1, 0.3])
    assert kinds.tolist() == [1, 2, 1, 3] and type_radii.tolist() == [0.1, 0.2, 0.3]
    assert ndio.dem.size_types(np.linspace(0.1, 0.2, 100))[0].max() == 1
    bed.save(tmp_path / "bed.txt")
    again = nd.Packing.load(tmp_path / "bed.txt")
    assert again.params["bounds"] == [[0.0, 0.0, 0.0], [1.0, 1.0, 1.0]]
    assert again.params["period"] == [1.0, 1.0, 1.0]
    assert (again.radii == bed.radii).all() and again.verify(cell)
