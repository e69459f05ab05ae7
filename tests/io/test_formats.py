"""Packing files in every format: save, load back, compare; and clear errors for bad files.

The packings run on the NumPy reference (conftest), with small grids: the numba backend would
spend most of this file's time compiling, and the formats do not depend on the backend.
"""

import base64
import json

import numpy as np
import pytest
import trimesh

import ndpack as nd
from ndpack import io as ndio
from ndpack.geometry.ball_union import enclosing_sphere


@pytest.fixture(scope="module")
def cube():
    return nd.pack(nd.Box([0, 0, 0], [1, 1, 1]), 40, seed=0, grid=16)


@pytest.fixture(scope="module")
def square():
    return nd.pack(nd.Box([0, 0], [2, 1]) - nd.Ball([0, 0], 0.5), 30, seed=0, grid=32)


@pytest.fixture(scope="module")
def tesseract():
    return nd.pack(nd.Box([0, 0, 0, 0], [1, 1, 1, 1]), 20, seed=0, grid=6)


def assert_same_spheres(loaded, packing, rounds=True):
    assert loaded.centers.shape == packing.centers.shape and loaded.centers.dtype == np.float64
    np.testing.assert_array_equal(loaded.centers, packing.centers)
    np.testing.assert_array_equal(loaded.radii, packing.radii)
    if rounds:
        np.testing.assert_array_equal(loaded.rounds, packing.rounds)


def assert_same_metadata(loaded, packing):
    assert loaded.volume == packing.volume and loaded.volume_error == packing.volume_error
    assert loaded.params == packing.params and loaded.stop_reason == packing.stop_reason


# ---------------------------------------------------------------------------------- exact formats
@pytest.mark.parametrize("name", ["cube", "square", "tesseract"])
@pytest.mark.parametrize("suffix", [".npz", ".csv", ".json"])
def test_native_formats_are_exact_in_any_dimension(request, tmp_path, name, suffix):
    packing = request.getfixturevalue(name)
    loaded = nd.Packing.load(packing.save(tmp_path / f"p{suffix}"))
    assert_same_spheres(loaded, packing)
    assert_same_metadata(loaded, packing)
    if suffix != ".csv":  # npz and json keep everything
        for key in ("time", "count", "fill"):
            np.testing.assert_array_equal(getattr(loaded.stats, key), getattr(packing.stats, key))
        np.testing.assert_array_equal(loaded.medial_axis, packing.medial_axis)
        np.testing.assert_array_equal(loaded.medial_radii, packing.medial_radii)


def test_json_is_plain_json(cube, tmp_path):
    document = json.loads(cube.save(tmp_path / "p.json").read_text())
    assert document["format"] == "ndpack-packing" and document["dim"] == 3
    assert len(document["centers"]) == 40 and len(document["centers"][0]) == 3
    assert set(document["stats"]) == {"time", "count", "fill"}


@pytest.mark.parametrize("name", ["cube", "square"])
@pytest.mark.parametrize("suffix, options", [
    (".ply", {}), (".ply", {"encoding": "ascii"}),
    (".vtp", {}), (".vtp", {"encoding": "ascii"}), (".vtp", {"header_type": "UInt32"}),
])
def test_ply_and_vtp_are_exact_and_keep_the_dimension(request, tmp_path, name, suffix, options):
    packing = request.getfixturevalue(name)
    loaded = nd.Packing.load(packing.save(tmp_path / f"p{suffix}", **options))
    assert_same_spheres(loaded, packing)
    assert_same_metadata(loaded, packing)
    assert loaded.dim == packing.dim


def test_ply_layout_and_trimesh_reads_the_points(cube, square, tmp_path):
    path = cube.save(tmp_path / "p.ply")
    header = path.read_bytes().split(b"end_header")[0].decode()
    assert "format binary_little_endian 1.0" in header and "element vertex 40" in header
    assert "property double radius" in header and "property int round" in header
    cloud = trimesh.load(path)
    assert isinstance(cloud, trimesh.PointCloud)
    np.testing.assert_array_equal(cloud.vertices, cube.centers)
    ascii_cloud = trimesh.load(cube.save(tmp_path / "a.ply", encoding="ascii"))
    np.testing.assert_array_equal(ascii_cloud.vertices, cube.centers)
    # 2-D: z = 0, and the dimension is said in a comment.
    flat = square.save(tmp_path / "flat.ply")
    assert "comment ndpack-dimension 2" in flat.read_bytes().split(b"end_header")[0].decode()
    np.testing.assert_array_equal(trimesh.load(flat).vertices[:, 2], 0)


def test_vtp_layout(cube, tmp_path):
    import xml.etree.ElementTree as ET

    root = ET.parse(cube.save(tmp_path / "p.vtp", encoding="ascii")).getroot()
    piece = root.find("PolyData/Piece")
    assert root.get("type") == "PolyData" and piece.get("NumberOfVerts") == "40"
    names = {node.get("Name"): node.get("type") for node in piece.findall("PointData/DataArray")}
    assert names == {"radius": "Float64", "diameter": "Float64", "round": "Int64"}
    diameter = np.array(piece.find("PointData/DataArray[@Name='diameter']").text.split(), dtype=float)
    np.testing.assert_array_equal(diameter, 2 * cube.radii)
    np.testing.assert_array_equal(np.array(piece.find("Verts/DataArray[@Name='offsets']").text.split(), int),
                                  np.arange(1, 41))


def test_vtp_reads_a_header_encoded_apart_from_the_data(cube, tmp_path):
    # VTK's own writer may base64 the byte-count header and the data as two streams.
    path = cube.save(tmp_path / "p.vtp", header_type="UInt32")
    text = path.read_text()
    joint = text.split('Name="radius" format="binary">')[1].split("<")[0]
    raw = base64.b64decode(joint)
    apart = (base64.b64encode(raw[:4]) + base64.b64encode(raw[4:])).decode()
    assert apart[7] == "="
    path.write_text(text.replace(joint, apart))
    np.testing.assert_array_equal(nd.Packing.load(path).radii, cube.radii)


# ---------------------------------------------------------------------------------- sphere meshes
@pytest.mark.parametrize("subdivisions", [0, 1, 2])
def test_sphere_mesh_has_its_triangles_on_its_spheres(cube, subdivisions):
    mesh = ndio.sphere_mesh(cube.centers, cube.radii, subdivisions)
    per_vertex = 10 * 4**subdivisions + 2
    assert len(mesh.faces) == 40 * 20 * 4**subdivisions and len(mesh.vertices) == 40 * per_vertex
    owner = np.repeat(np.arange(40), per_vertex)
    distance = np.linalg.norm(mesh.vertices - cube.centers[owner], axis=1)
    np.testing.assert_allclose(distance, cube.radii[owner], rtol=1e-14)
    assert mesh.is_watertight and mesh.is_winding_consistent
    assert mesh.volume > 0  # outward normals


@pytest.mark.parametrize("suffix, options, tol", [
    (".obj", {}, 1e-12),                   # 17 decimals: float64 to rounding
    (".obj", {"subdivisions": 0}, 1e-12),
    (".stl", {}, 1e-6),                    # float32 vertices
    (".glb", {}, 1e-6),                    # glTF positions are float32
])
def test_sphere_mesh_files_give_back_the_spheres(cube, tmp_path, suffix, options, tol):
    path = cube.save(tmp_path / f"p{suffix}", **options)
    loaded = nd.Packing.load(path)
    # Absolute tolerance in units of the packing's size (1 here); relative to the radii too.
    np.testing.assert_allclose(loaded.centers, cube.centers, rtol=0, atol=tol)
    np.testing.assert_allclose(loaded.radii, cube.radii, rtol=tol, atol=tol)
    assert np.isnan(loaded.volume) and np.all(loaded.rounds == 0)
    mesh = trimesh.load(path, force="mesh")
    assert len(mesh.faces) == 40 * 20 * 4 ** options.get("subdivisions", 1)


def test_spheres_that_share_a_vertex_are_still_told_apart():
    # Two unit spheres touching at (1, 0, 0), a vertex of both icospheres.
    centers, radii = np.array([[0.0, 0, 0], [2.0, 0, 0]]), np.array([1.0, 1.0])
    mesh = ndio.sphere_mesh(centers, radii)
    assert len(trimesh.Trimesh(mesh.vertices, mesh.faces).vertices) == 2 * 42 - 1  # merged: one shared
    found_centers, found_radii = ndio.spheres_from_mesh(mesh.vertices, mesh.faces)
    np.testing.assert_allclose(found_centers, centers, atol=1e-15)
    np.testing.assert_allclose(found_radii, radii, rtol=1e-15)


# ---------------------------------------------------------------------------------- .sph and cuRobo
def test_sph_is_a_two_level_tree_with_a_bounding_root(cube, tmp_path):
    path = cube.save(tmp_path / "p.sph")
    lines = path.read_text().splitlines()
    assert lines[0] == "2 40" and len(lines) == 42
    root = np.array(lines[1].split(), dtype=float)
    assert root[4] == 1 and all(len(line.split()) == 5 for line in lines[1:])
    reach = np.linalg.norm(cube.centers - root[:3], axis=1) + cube.radii
    assert reach.max() <= root[3] * (1 + 1e-15)
    loaded = nd.Packing.load(path)
    assert_same_spheres(loaded, cube, rounds=False)
    centers, radii = ndio.read_sph(path, level=0)
    np.testing.assert_array_equal(centers[0], root[:3])


def test_sph_reads_a_toolkit_tree(tmp_path):
    # 3 levels, branching 2: unused slots (radius -1), auxiliary columns, the trailing options text.
    text = """3 2
0.000000 0.000000 0.000000 2.000000 1.000000
-1.000000 0.000000 0.000000 1.000000 1.000000 -1.0 0.0 0.0 1.0 0.5
1.000000 0.000000 0.000000 1.000000 1.000000

-1.500000 0.000000 0.000000 0.500000 1.000000
-0.500000 0.000000 0.000000 0.500000 1.000000
1.000000 0.000000 0.000000 0.900000 1.000000
0.000000 0.000000 0.000000 -1.000000 1.000000


Options :
  depth : 2
"""
    path = tmp_path / "toolkit.sph"
    path.write_text(text)
    centers, radii = ndio.read_sph(path)
    np.testing.assert_array_equal(radii, [0.5, 0.5, 0.9])
    np.testing.assert_array_equal(centers[:, 0], [-1.5, -0.5, 1.0])
    assert len(ndio.read_sph(path, level=1)[1]) == 2
    assert len(nd.Packing.load(path)) == 3


def test_curobo_collision_spheres(cube, tmp_path):
    path = cube.save(tmp_path / "spheres.json", format="curobo", link="gripper")
    document = json.loads(path.read_text())
    spheres = document["collision_spheres"]["gripper"]
    assert len(spheres) == 40 and set(spheres[0]) == {"center", "radius"}
    loaded = nd.Packing.load(path)  # told apart from ndpack's JSON by its content
    assert_same_spheres(loaded, cube, rounds=False)
    assert_same_spheres(nd.Packing.load(path, format="curobo"), cube, rounds=False)
    # Several links are read one after another; disabled spheres (radius < 0) are dropped.
    document["collision_spheres"]["base"] = [{"center": [5, 5, 5], "radius": 0.5}, {"center": [0, 0, 0], "radius": -1}]
    path.write_text(json.dumps(document))
    assert len(nd.Packing.load(path)) == 41


def test_curobo_yaml_round_trip(cube, tmp_path):
    import yaml

    path = cube.save(tmp_path / "spheres.yml", link="gripper")  # .yml is cuRobo YAML without format=
    document = yaml.safe_load(path.read_text())
    spheres = document["collision_spheres"]["gripper"]
    assert len(spheres) == 40 and set(spheres[0]) == {"center", "radius"}
    np.testing.assert_array_equal([s["center"] for s in spheres], cube.centers)
    np.testing.assert_array_equal([s["radius"] for s in spheres], cube.radii)
    assert_same_spheres(nd.Packing.load(path), cube, rounds=False)
    assert_same_spheres(nd.Packing.load(cube.save(tmp_path / "s.yaml", format="curobo")), cube, rounds=False)
    # cuRobo's own files: quoted keys, comments, a whole robot configuration around the spheres,
    # numbers YAML 1.1 would read as strings, and disabled spheres (radius < 0), dropped.
    (tmp_path / "robot.yml").write_text("""# a cuRobo robot
robot_cfg:
  kinematics:
    base_link: "base"   # a comment
    collision_spheres:
      "panda_link0":
        - "center": [0.0, 0.0, 0.085]
          "radius": 0.03
        - center: [1e-05, -2, 3.5e+2]
          radius: 1.5e-3
      panda_link1: []
      panda_hand:
      - center: [0, 0, 0]
        radius: -1
""")
    loaded = nd.Packing.load(tmp_path / "robot.yml")
    np.testing.assert_array_equal(loaded.centers, [[0.0, 0.0, 0.085], [1e-05, -2, 350.0]])
    np.testing.assert_array_equal(loaded.radii, [0.03, 1.5e-3])
    # Tiny and huge numbers are written so that YAML 1.1 (PyYAML) reads them as the same floats.
    tiny = nd.Packing(np.array([[1e-05, -2e-20, 1e16]]), np.array([1e-07]), np.zeros(1, np.int64), 1.0)
    path = ndio.save(tiny, tmp_path / "tiny.yml")
    assert "1.0e-05" in path.read_text()
    sphere = yaml.safe_load(path.read_text())["collision_spheres"]["body"][0]
    assert sphere == {"center": [1e-05, -2e-20, 1e16], "radius": 1e-07}
    # Link names that YAML would read as something else are quoted.
    text = ndio.curobo_yaml({"yes": (np.zeros((1, 3)), [1.0]), "1": (np.zeros((0, 3)), []),
                                "a b": ([[0, 0, 0]], [2])})
    assert list(yaml.safe_load(text)["collision_spheres"]) == ["yes", "1", "a b"]
    with pytest.raises(nd.NdpackError, match="not a readable ndpack packing.*no 'collision_spheres'"):
        (tmp_path / "other.yml").write_text("robot: {}\n")
        nd.Packing.load(tmp_path / "other.yml")


# ---------------------------------------------------------------------------------- medial axis
@pytest.mark.parametrize("name, suffixes", [("cube", [".ply", ".csv"]), ("square", [".ply"]), ("tesseract", [".csv"])])
def test_medial_axis_sample(request, tmp_path, name, suffixes):
    packing = request.getfixturevalue(name)
    for suffix in suffixes:
        path = packing.save(tmp_path / f"medial{suffix}", format="medial")
        points, radii = ndio.load_medial(path)
        np.testing.assert_array_equal(points, packing.medial_axis)
        np.testing.assert_array_equal(radii, packing.medial_radii)
    if ".csv" in suffixes:
        header = (tmp_path / "medial.csv").read_text().splitlines()[1]
        assert header == ",".join([*(f"x{i}" for i in range(packing.dim)), "radius"])


def test_medial_and_packing_files_are_not_mixed_up(cube, tmp_path):
    medial = cube.save(tmp_path / "medial.ply", format="medial")
    with pytest.raises(nd.NdpackError, match="medial-axis sample.*load_medial"):
        nd.Packing.load(medial)
    with pytest.raises(nd.NdpackError, match="load_medial"):
        nd.Packing.load(medial, format="medial")
    with pytest.raises(nd.NdpackError, match="holds a packing"):
        ndio.load_medial(cube.save(tmp_path / "spheres.ply"))


# ---------------------------------------------------------------------------------- errors
def test_format_table():
    assert ndio.names() == ["npz", "csv", "json", "ply", "vtp", "mesh", "sph", "curobo", "lammps", "liggghts",
                            "yade", "medial"]
    text = ndio.table()
    assert all(name in text for name in ndio.names()) and ".glb" in text and "subdivisions=1" in text


def test_the_registry_keeps_one_format_per_name_and_suffix():
    from ndpack.io.registry import Format, register

    ply = ndio.FORMATS["ply"]
    with pytest.raises(ValueError, match="'ply' is already registered"):
        register(ply)
    with pytest.raises(ValueError, match=r"cannot be the default for \.ply"):
        register(Format("other", (".ply",), "3", "-", {}, ply.write, ply.read), default_for=(".ply",))
    assert "other" not in ndio.FORMATS and ndio.SUFFIXES[".ply"] == "ply"


def test_unknown_suffix_name_and_option(cube, tmp_path):
    with pytest.raises(nd.NdpackError, match=r"unknown suffix '\.xyz'.*\.npz or \.csv.*\.ply.*\.sph"):
        cube.save(tmp_path / "p.xyz")
    with pytest.raises(nd.NdpackError, match="unknown format 'xyz'.*curobo"):
        cube.save(tmp_path / "p.ply", format="xyz")
    with pytest.raises(nd.NdpackError, match=r"as curobo: its file name must end in \.json"):
        cube.save(tmp_path / "p.ply", format="curobo")
    with pytest.raises(nd.NdpackError, match="no option colour.*encoding"):
        cube.save(tmp_path / "p.ply", colour="red")
    with pytest.raises(nd.NdpackError, match="encoding must be"):
        cube.save(tmp_path / "p.vtp", encoding="base64")


@pytest.mark.parametrize("suffix, format", [(".ply", None), (".vtp", None), (".stl", None), (".sph", None),
                                            (".json", "curobo")])
def test_dimensions_each_format_cannot_hold(tesseract, square, tmp_path, suffix, format):
    with pytest.raises(nd.DimensionError, match="not a 4-D packing: use .npz, .csv or .json"):
        tesseract.save(tmp_path / f"p{suffix}", format=format)
    if suffix not in (".ply", ".vtp"):
        with pytest.raises(nd.DimensionError, match="3-D spheres, not a 2-D packing"):
            square.save(tmp_path / f"p{suffix}", format=format)
    assert not (tmp_path / f"p{suffix}").exists()


def test_medial_ply_needs_at_most_3d(tesseract, tmp_path):
    with pytest.raises(nd.DimensionError, match=r"write it to a \.csv file"):
        tesseract.save(tmp_path / "m.ply", format="medial")


@pytest.mark.parametrize("suffix", [".npz", ".csv", ".json", ".ply", ".vtp", ".obj", ".stl", ".glb", ".sph"])
def test_garbage_and_missing_files(tmp_path, suffix):
    path = tmp_path / f"garbage{suffix}"
    path.write_bytes(b"this is not a packing\n\x00\xff\n")
    with pytest.raises(nd.NdpackError, match=r"garbage\.\w+ is not a readable ndpack packing \(\w+ format\): ") as info:
        nd.Packing.load(path)
    assert "\n" not in str(info.value)
    with pytest.raises(nd.NdpackError, match="no such packing file"):
        nd.Packing.load(tmp_path / f"missing{suffix}")


def test_other_ply_files_are_refused_not_misread(tmp_path):
    box = tmp_path / "box.ply"
    trimesh.creation.box().export(box)
    with pytest.raises(nd.NdpackError, match="elements vertex, face|list property"):
        nd.Packing.load(box)
    points = tmp_path / "points.ply"
    trimesh.PointCloud(np.eye(3)).export(points)
    with pytest.raises(nd.NdpackError, match="no radius"):
        nd.Packing.load(points)


def test_a_truncated_binary_ply(cube, tmp_path):
    path = cube.save(tmp_path / "p.ply")
    path.write_bytes(path.read_bytes()[:-10])
    with pytest.raises(nd.NdpackError, match="truncated"):
        nd.Packing.load(path)


def test_unwritable_path(cube, tmp_path):
    with pytest.raises(nd.NdpackError, match="cannot write"):
        cube.save(tmp_path / "no-such-folder" / "p.sph")


def test_enclosing_sphere_encloses_and_is_nearly_smallest():
    # Two spheres: the smallest enclosing one spans both, radius (1 + 4 + 0.5) / 2.
    center, radius = enclosing_sphere([[0, 0, 0], [4, 0, 0]], [1.0, 0.5])
    assert radius == pytest.approx(2.75, rel=2e-3) and center[0] == pytest.approx(1.75, abs=0.01)
    # Points all over a unit sphere, off the origin: the smallest is that sphere.
    rng = np.random.default_rng(0)
    directions = rng.standard_normal((4000, 3))
    points = directions / np.linalg.norm(directions, axis=1)[:, None] + [3.0, -1.0, 2.0]
    center, radius = enclosing_sphere(points, np.zeros(len(points)))
    assert 0.999 < radius < 1.002
    # A lopsided cluster: every sphere inside, and no larger than the box's middle gives.
    centers = np.vstack([rng.random((500, 3)) * 0.1, [[1, 1, 1], [1, 0, 0]]])
    radii = rng.uniform(0.001, 0.02, len(centers))
    center, radius = enclosing_sphere(centers, radii)
    assert np.all(np.linalg.norm(centers - center, axis=1) + radii <= radius * (1 + 1e-12))
    middle = ((centers - radii[:, None]).min(axis=0) + (centers + radii[:, None]).max(axis=0)) / 2
    assert radius <= (np.linalg.norm(centers - middle, axis=1) + radii).max()


# ---------------------------------------------------------------------------------- every file verifies
PART = "import ndpack as nd\nshape = nd.Box([0, 0, 0], [1, 2, 0.5]) - nd.Ball([1, 2, 0.5], 0.4)\n"
OUTLINE = "import ndpack as nd\nshape = nd.Box([0, 0], [2, 1]) - nd.Ball([0, 0], 0.5)\n"


@pytest.fixture(scope="module")
def part():
    # Many spheres far from the origin's float32 exactness: 300, down to small radii.
    return nd.pack(nd.Box([0, 0, 0], [1, 2, 0.5]) - nd.Ball([1, 2, 0.5], 0.4), 300, mode="fast", seed=0)


WRITTEN = [(name, suffix) for name, fmt in ndio.FORMATS.items() if fmt.read is not None for suffix in fmt.suffixes]


@pytest.mark.parametrize("name, suffix", WRITTEN)
def test_every_file_ndpack_writes_verifies(part, square, tmp_path, capsys, name, suffix):
    from ndpack.cli import main

    fmt = ndio.FORMATS[name]
    for packing, source in ((part, PART), (square, OUTLINE)):
        if packing.dim not in fmt.dim_range(suffix):
            continue
        script = tmp_path / f"shape{packing.dim}.py"
        script.write_text(source)
        path = ndio.save(packing, tmp_path / f"spheres{packing.dim}{suffix}", format=name)
        assert main(["verify", str(path), "--shape", str(script)]) == 0, capsys.readouterr().out
        assert "valid" in capsys.readouterr().out
