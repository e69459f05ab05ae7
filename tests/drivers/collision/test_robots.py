"""Robots: a URDF's links covered by spheres, written as a URDF, a cuRobo YAML file and a report.

The written URDF is read back with urdf_parser_py (ROS's own URDF reader, pure Python on lxml
and PyYAML: far lighter than yourdfpy, which pulls in ``trimesh[easy]``). Every link's spheres
are checked against a reference shape built here, independently, in the link's frame (the
rotation from SciPy's fixed-axis Euler angles, not from ndpack's reader). The coverings are small
(``samples=4000``) to keep the file near half a minute on 2 cores.
"""

import json
import math
import warnings

import numpy as np
import pytest
import trimesh

import ndpack as nd
from ndpack.drivers.collision import robots
from ndpack.cli import main

FAST = {"samples": 4000, "check_samples": 8000}
SHARE = 0.08
#: The arm's collision origin: translation and roll, pitch, yaw.
ARM_XYZ, ARM_RPY = np.array([0.1, 0.2, 0.3]), np.array([0.3, -0.7, 1.2])
PLATE_XYZ, PLATE_RPY = np.array([0.0, 0.0, 0.01]), np.array([0.0, 0.0, 0.5])

URDF = """<?xml version="1.0"?>
<robot name="testbot">
  <!-- a link without geometry -->
  <link name="world"/>
  <link name="base">
    <visual>
      <geometry><mesh filename="package://testbot/meshes/base.stl"/></geometry>
    </visual>
    <collision name="base_mesh">
      <geometry><mesh filename="package://testbot/meshes/base.stl"/></geometry>
    </collision>
  </link>
  <link name="arm">
    <inertial><mass value="1"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial>
    <collision>
      <origin xyz="{arm_xyz}" rpy="{arm_rpy}"/>
      <geometry><mesh filename="../meshes/arm.stl" scale="2 2 2"/></geometry>
    </collision>
  </link>
  <link name="plate">
    <visual>
      <origin xyz="{plate_xyz}" rpy="{plate_rpy}"/>
      <geometry><box size="0.3 0.2 0.04"/></geometry>
    </visual>
  </link>{extra}
  <joint name="world_base" type="fixed"><parent link="world"/><child link="base"/></joint>
  <joint name="base_arm" type="revolute">
    <parent link="base"/><child link="arm"/><axis xyz="0 0 1"/>
    <limit lower="-1" upper="1" effort="1" velocity="1"/>
  </joint>
  <joint name="arm_plate" type="fixed"><parent link="arm"/><child link="plate"/></joint>
</robot>
"""


def numbers(values) -> str:
    return " ".join(repr(float(v)) for v in values)


def write_robot(folder, extra: str = ""):
    """A ROS-like package ``testbot`` with meshes/ and urdf/testbot.urdf; returns the URDF's path."""
    package = folder / "testbot"
    (package / "meshes").mkdir(parents=True)
    (package / "urdf").mkdir()
    trimesh.creation.box(extents=[0.2, 0.1, 0.3]).export(package / "meshes" / "base.stl")
    trimesh.creation.capsule(height=0.15, radius=0.025, count=[8, 8]).export(package / "meshes" / "arm.stl")
    path = package / "urdf" / "testbot.urdf"
    path.write_text(URDF.format(arm_xyz=numbers(ARM_XYZ), arm_rpy=numbers(ARM_RPY), plate_xyz=numbers(PLATE_XYZ),
                                plate_rpy=numbers(PLATE_RPY), extra=extra))
    return path


def fixed_axis(rpy) -> np.ndarray:
    """URDF's rpy, written out as the URDF specification states it: Rz(yaw) Ry(pitch) Rx(roll)."""
    (cr, cp, cy), (sr, sp, sy) = np.cos(rpy), np.sin(rpy)
    rz = np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
    ry = np.array([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
    rx = np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
    return rz @ ry @ rx


def reference_shapes(folder):
    """Each covered link's geometry in the link's frame, built without ndpack's URDF reader."""
    base = trimesh.load(folder / "testbot" / "meshes" / "base.stl", force="mesh")
    arm = trimesh.load(folder / "testbot" / "meshes" / "arm.stl", force="mesh")
    arm_vertices = (2 * arm.vertices) @ fixed_axis(ARM_RPY).T + ARM_XYZ
    plate = nd.Box([-0.15, -0.1, -0.02], [0.15, 0.1, 0.02]).rotate(fixed_axis(PLATE_RPY)).translate(PLATE_XYZ)
    return {"base": nd.TriangleMesh(base.vertices, base.faces),
            "arm": nd.TriangleMesh(arm_vertices, arm.faces),
            "plate": plate}


@pytest.fixture(scope="module")
def robot(tmp_path_factory):
    folder = tmp_path_factory.mktemp("robot")
    path = write_robot(folder)
    result = robots.cover_urdf(path, folder / "out", protrusion_share=SHARE, **FAST)
    return folder, path, result


# ------------------------------------------------------------------------------------- reading
def test_read_urdf_links_in_the_link_frame(tmp_path):
    path = write_robot(tmp_path)
    links = {link.name: link for link in robots.read_urdf_links(path)}
    assert list(links) == ["world", "base", "arm", "plate"]
    assert links["world"].shapes == [] and links["world"].shape is None and links["world"].source is None
    assert links["base"].source == "collision" and links["plate"].source == "visual"
    assert links["arm"].parts == ["mesh ../meshes/arm.stl (scale 2.0 2.0 2.0)"]
    references = reference_shapes(tmp_path)
    rng = np.random.default_rng(0)
    for name, reference in references.items():
        lower, upper = reference.bounds
        points = lower - 0.05 + (upper - lower + 0.1) * rng.random((2000, 3))
        np.testing.assert_allclose(links[name].shape.distance(points), reference.distance(points), atol=1e-12)
        np.testing.assert_allclose(links[name].bounds, reference.bounds, atol=1e-12)


def test_rpy_is_urdf_fixed_axis_convention():
    for rpy in ([0.3, -0.7, 1.2], [math.pi / 2, 0, 0], [0.1, 1.5, -3.0]):
        np.testing.assert_allclose(robots.rpy_matrix(rpy), fixed_axis(rpy), atol=1e-12)
    # A yaw of 90 degrees turns x into y.
    np.testing.assert_allclose(robots.rpy_matrix([0, 0, math.pi / 2]) @ [1, 0, 0], [0, 1, 0], atol=1e-15)


def test_primitives_cylinder_and_sphere(tmp_path):
    path = tmp_path / "r.urdf"
    path.write_text("""<robot name="r"><link name="tool">
      <collision><origin xyz="0 0 0.05" rpy="1.5707963267948966 0 0"/>
        <geometry><cylinder radius="0.02" length="0.1"/></geometry></collision>
      <collision><origin xyz="0 0 0.1"/><geometry><sphere radius="0.03"/></geometry></collision>
    </link></robot>""")
    (tool,) = robots.read_urdf_links(path)
    cylinder, ball = tool.shapes
    # The cylinder's axis is z turned by the roll: along -y, about (0, 0, 0.05).
    np.testing.assert_allclose(cylinder.a, [0, 0.05, 0.05], atol=1e-15)
    np.testing.assert_allclose(cylinder.b, [0, -0.05, 0.05], atol=1e-15)
    assert cylinder.radius == 0.02 and ball.radius == 0.03
    np.testing.assert_array_equal(ball.center, [0, 0, 0.1])
    assert tool.parts == ["cylinder r=0.02 l=0.1", "sphere r=0.03"]


def test_mesh_file_names_resolve(tmp_path, tmp_path_factory, monkeypatch):
    path = write_robot(tmp_path)
    mesh = tmp_path / "testbot" / "meshes" / "base.stl"
    folder = path.parent
    assert robots.resolve_mesh("package://testbot/meshes/base.stl", folder) == mesh  # a folder above
    assert robots.resolve_mesh(f"file://{mesh}", folder) == mesh
    assert robots.resolve_mesh("../meshes/base.stl", folder).resolve() == mesh
    assert robots.resolve_mesh(str(mesh), tmp_path / "elsewhere") == mesh
    other = tmp_path_factory.mktemp("elsewhere")  # no testbot folder at or above it
    with pytest.raises(nd.ShapeError, match="package://testbot/meshes/base.stl.*not found.*packages="):
        robots.resolve_mesh("package://testbot/meshes/base.stl", other)
    assert robots.resolve_mesh("package://testbot/meshes/base.stl", other, {"testbot": tmp_path / "testbot"}) == mesh
    monkeypatch.setenv("ROS_PACKAGE_PATH", str(tmp_path))
    assert robots.resolve_mesh("package://testbot/meshes/base.stl", other) == mesh
    with pytest.raises(nd.ShapeError, match="not found"):
        robots.resolve_mesh("meshes/none.stl", folder)


def test_a_missing_mesh_names_the_link_and_the_file(tmp_path):
    extra = """
  <link name="ghost">
    <collision><geometry><mesh filename="package://testbot/meshes/nothere.stl"/></geometry></collision>
  </link>"""
    path = write_robot(tmp_path, extra)
    with pytest.raises(nd.ShapeError, match="link 'ghost': mesh file 'package://testbot/meshes/nothere.stl' not "):
        robots.read_urdf_links(path)
    links = robots.read_urdf_links(path, strict=False)
    assert "nothere.stl" in links[-1].error and links[-1].shapes == []
    bad = tmp_path / "bad.urdf"
    bad.write_text('<robot name="b"><link name="l"><collision><geometry><box size="1 0 1"/></geometry>'
                   '</collision></link></robot>')
    with pytest.raises(nd.ShapeError, match="link 'l'.*size.*positive"):
        robots.read_urdf_links(bad)
    bad.write_text("<robot><link name='l'>")
    with pytest.raises(nd.ShapeError, match="not valid XML"):
        robots.read_urdf_links(bad)
    with pytest.raises(nd.ShapeError, match="xacro"):
        robots.read_urdf_links(tmp_path / "robot.urdf.xacro")


def test_cover_urdf_asks_for_one_measure(tmp_path):
    path = write_robot(tmp_path)
    with pytest.raises(nd.ParameterError, match="give one of n"):
        robots.cover_urdf(path, tmp_path / "out", n=4, protrusion_share=0.1)
    with pytest.raises(nd.ParameterError, match="protrusion_share must be a positive number"):
        robots.cover_urdf(path, tmp_path / "out", protrusion_share=-1)
    with pytest.raises(nd.ParameterError, match="no option packing"):
        robots.cover_urdf(path, tmp_path / "out", n=4, packing=None)


def test_share_out():
    assert robots._share_out(10, [1.0, 1.0]) == [5, 5]
    assert robots._share_out(10, [3.0, 1.0]) == [7, 3]
    assert sum(robots._share_out(17, [0.3, 2.0, 1.1])) == 17
    assert robots._share_out(2, [1.0, 1.0, 1.0]) == [1, 1, 1]


# ------------------------------------------------------------------------------------- covering
def test_written_urdf_parses_and_holds_the_spheres(robot):
    from urdf_parser_py.urdf import URDF as Reader  # ROS's reader (its printing is broken on 3.10+: not used)

    folder, path, result = robot
    assert result.urdf.name == "testbot_spheres.urdf" and list(result.links) == ["base", "arm", "plate"]
    assert result.skipped == ["world"] and result.failed == {} and result.covered
    model = Reader.from_xml_string(result.urdf.read_bytes())
    original = Reader.from_xml_string(path.read_bytes())
    assert [link.name for link in model.links] == [link.name for link in original.links]
    assert [joint.name for joint in model.joints] == [joint.name for joint in original.joints]
    for link in model.links:
        if link.name == "world":
            assert not link.collisions and not link.visuals
            continue
        covering = result.links[link.name]
        assert len(link.collisions) == len(covering) > 0
        for i, collision in enumerate(link.collisions):
            assert collision.name == f"{link.name}_sphere_{i}"
            assert collision.origin.xyz == covering.centers[i].tolist()  # every bit: repr-precision numbers
            assert collision.origin.rpy == [0.0, 0.0, 0.0]
            assert collision.geometry.radius == covering.radii[i]
    # Visual elements are untouched: the base's mesh and the plate's box.
    links = {link.name: link for link in model.links}
    assert links["base"].visuals[0].geometry.filename == "package://testbot/meshes/base.stl"
    assert links["plate"].visuals[0].geometry.size == [0.3, 0.2, 0.04]
    np.testing.assert_allclose(links["plate"].visuals[0].origin.rpy, PLATE_RPY)
    assert links["arm"].inertial.mass == 1.0
    text = result.urdf.read_text()
    assert "<!-- a link without geometry -->" in text
    assert text.count("<collision") == sum(map(len, result.links.values()))


def test_yaml_is_curobos_collision_spheres(robot):
    yaml = pytest.importorskip("yaml")
    _, _, result = robot
    document = yaml.safe_load(result.yaml.read_text())
    assert list(document) == ["collision_spheres"]
    spheres = document["collision_spheres"]
    assert list(spheres) == list(result.links)
    for name, covering in result.links.items():
        np.testing.assert_array_equal([s["center"] for s in spheres[name]], covering.centers)
        np.testing.assert_array_equal([s["radius"] for s in spheres[name]], covering.radii)
    assert len(nd.Packing.load(result.yaml)) == sum(map(len, result.links.values()))


def test_spheres_cover_each_link_in_its_frame(robot):
    folder, _, result = robot
    for name, reference in reference_shapes(folder).items():
        covering = result.links[name]
        report = nd.check_covering(reference, covering.centers, covering.radii, samples=8000, seed=7)
        assert report.covered, (name, report.summary())
        diagonal = reference.diagonal
        reach = covering.radii + reference.distance(covering.centers)
        assert reach.max() <= SHARE * diagonal * (1 + 1e-6), (name, reach.max() / diagonal)
    # The arm's spheres are in the link's frame: they do not cover the mesh where its file puts it.
    arm = trimesh.load(folder / "testbot" / "meshes" / "arm.stl", force="mesh")
    unplaced = nd.TriangleMesh(2 * arm.vertices, arm.faces)
    covering = result.links["arm"]
    assert not nd.check_covering(unplaced, covering.centers, covering.radii, samples=2000).covered


def test_report_json(robot):
    _, _, result = robot
    report = json.loads(result.report.read_text())
    assert report["robot"] == "testbot" and report["covered"] is True
    assert report["without_geometry"] == ["world"] and report["failed"] == []
    assert report["request"]["protrusion_share"] == SHARE and report["request"]["samples"] == 4000
    assert list(report["links"]) == ["base", "arm", "plate"]
    for name, entry in report["links"].items():
        covering = result.links[name]
        assert entry["status"] == "covered" and entry["covered"] is True
        assert entry["spheres"] == len(covering)
        assert entry["max_protrusion"] == covering.report.max_protrusion
        assert entry["relative_protrusion"] <= SHARE * (1 + 1e-6)
        assert entry["relative_protrusion"] == pytest.approx(entry["max_protrusion"] / entry["diagonal"])
    assert report["links"]["plate"]["source"] == "visual"
    assert "robot 'testbot': 3 links covered" in result.summary()


def test_a_link_of_several_geometries_gets_their_spheres_together(tmp_path):
    path = tmp_path / "tool.urdf"
    path.write_text("""<robot name="tool"><link name="tool">
      <collision><origin xyz="0 0 0.05"/><geometry><cylinder radius="0.02" length="0.1"/></geometry></collision>
      <collision><origin xyz="0 0 0.1"/><geometry><sphere radius="0.03"/></geometry></collision>
    </link></robot>""")
    result = robots.cover_urdf(path, tmp_path / "out", n=4, **FAST)
    covering = result.links["tool"]
    assert 2 <= len(covering) <= 4 and covering.report.covered
    assert [part["n"] for part in covering.params["parts"]] == [2, 2]  # shared out by the parts' diagonals
    reference = nd.Cylinder([0, 0, 0], [0, 0, 0.1], 0.02) | nd.Ball([0, 0, 0.1], 0.03)
    assert nd.check_covering(reference, covering.centers, covering.radii, samples=4000).covered
    assert json.loads(result.report.read_text())["links"]["tool"]["spheres"] == len(covering)


# ------------------------------------------------------------------------------------- command line
def test_cli_covers_a_mesh_file(tmp_path, capsys):
    yaml = pytest.importorskip("yaml")
    mesh = tmp_path / "arm.stl"
    trimesh.creation.capsule(height=0.15, radius=0.025, count=[8, 8]).export(mesh)
    out = tmp_path / "arm.yml"
    code = main(["cover", str(mesh), "-n", "6", "-o", str(out), "--option", "link=arm", "--samples", "4000",
                 "--check-samples", "8000", "-q"])
    printed = capsys.readouterr().out
    assert code == 0, printed
    assert "spheres:  " in printed and "all covered" in printed and "time:" in printed and "saved:" in printed
    spheres = yaml.safe_load(out.read_text())["collision_spheres"]["arm"]
    assert 1 <= len(spheres) <= 6
    centers = np.array([s["center"] for s in spheres])
    radii = np.array([s["radius"] for s in spheres])
    assert nd.check_covering(nd.TriangleMesh.load(mesh), centers, radii, samples=4000).covered


def test_cli_covers_a_urdf_and_reports_a_missing_mesh(tmp_path, capsys):
    extra = """
  <link name="ghost">
    <collision><geometry><mesh filename="package://testbot/meshes/nothere.stl"/></geometry></collision>
  </link>
  <link name="broken">
    <collision><geometry><mesh filename="package://testbot/meshes/empty.stl"/></geometry></collision>
  </link>"""
    path = write_robot(tmp_path, extra)
    (tmp_path / "testbot" / "meshes" / "empty.stl").write_bytes(b"")
    # Only the plate and the ghost: the other links' meshes are dropped from the file, to keep this quick.
    text = path.read_text()
    for name in ("base", "arm"):
        start = text.index(f'<link name="{name}">')
        text = text[:start] + f'<link name="{name}"/>' + text[text.index("</link>", start) + len("</link>"):]
    path.write_text(text)
    out = tmp_path / "out"
    with pytest.warns(robots.RobotWarning) as caught:
        code = main(["cover", str(path), "--protrusion", "0.1", "-o", str(out), "--samples", "4000",
                     "--check-samples", "8000", "-q"])
    messages = [str(warning.message) for warning in caught if warning.category is robots.RobotWarning]
    assert len(messages) == 2 and all("\n" not in message for message in messages)
    assert "link 'ghost' was not covered" in messages[0] and "nothere.stl" in messages[0]
    assert "link 'broken' was not covered" in messages[1] and "empty (0 bytes)" in messages[1]
    printed = capsys.readouterr().out
    assert code == 1, printed  # a link failed
    assert "ghost" in printed and "FAILED" in printed and "plate" in printed and "time:" in printed
    report = json.loads((out / "report.json").read_text())
    assert report["failed"] == ["broken", "ghost"] and report["links"]["ghost"]["status"] == "failed"
    assert "nothere.stl" in report["links"]["ghost"]["error"]
    assert report["links"]["plate"]["covered"] and report["links"]["plate"]["relative_protrusion"] <= 0.1 + 1e-9
    written = (out / "testbot_spheres.urdf").read_text()
    assert "plate_sphere_0" in written and "package://testbot/meshes/nothere.stl" in written  # the ghost as it was
    assert "ghost" not in (out / "testbot_spheres.yml").read_text()


def test_cli_cover_errors(tmp_path, capsys):
    path = write_robot(tmp_path)
    assert main(["cover", str(path), "-n", "4"]) == 2
    assert "give the output folder with -o DIR" in capsys.readouterr().err
    assert main(["cover", str(path), "-n", "4", "-o", str(tmp_path / "o"), "--format", "curobo"]) == 2
    assert "--format and --option apply to one shape's file" in capsys.readouterr().err
    assert main(["cover", "box", "-n", "4", "--package", "a=b"]) == 2
    assert "--package applies to a URDF" in capsys.readouterr().err
    for bad in (["cover", "box"], ["cover", "box", "-n", "4", "--protrusion", "0.1"],
                ["cover", "box", "--protrusion", "2"], ["cover", "box", "-n", "0"]):
        with pytest.raises(SystemExit) as exit_:
            main(bad)
        assert exit_.value.code == 2
    assert "share of the diagonal" in capsys.readouterr().err
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert main(["cover", str(tmp_path / "none.urdf"), "-n", "4", "-o", str(tmp_path / "o")]) == 2
    assert "no URDF file at" in capsys.readouterr().err
