"""Other libraries' shapes as oracles: manifold3d solids and cross-sections, trimesh, shapely;
mixed freely with ndpack shapes in CSG."""

from __future__ import annotations

import numpy as np
import pytest

import ndpack as nd
from ndpack.errors import ShapeError
from ndpack.shapes.adapters import as_oracle

manifold3d = pytest.importorskip("manifold3d")


def points_in(lower, upper, count=2000, seed=0):
    lower, upper = np.asarray(lower, float), np.asarray(upper, float)
    pad = 0.2 * (upper - lower)
    return np.random.default_rng(seed).uniform(lower - pad, upper + pad, (count, len(lower)))


def test_manifold_cube_is_an_exact_box():
    solid = as_oracle(manifold3d.Manifold.cube([1.0, 2.0, 3.0]))
    assert isinstance(solid, nd.TriangleMesh) and solid.sign_method == "pseudonormal"
    box = nd.Box([0, 0, 0], [1, 2, 3])
    points = points_in([0, 0, 0], [1, 2, 3])
    np.testing.assert_allclose(solid.distance(points), box.distance(points), rtol=0, atol=1e-12)
    assert solid.volume().value == pytest.approx(6.0, rel=1e-12)


def test_manifolds_mix_with_ndpack_shapes_in_csg():
    cube = manifold3d.Manifold.cube([2.0, 2.0, 2.0])
    box = nd.Box([0, 0, 0], [2, 2, 2])
    cut = nd.Ball([2, 2, 2], 1.0)
    points = points_in([0, 0, 0], [2, 2, 2], seed=1)
    expected = (box - cut).distance(points)
    for shape in (cube - cut, nd.Box([-1, -1, -1], [3, 3, 3]) & cube - cut):
        np.testing.assert_allclose(shape.distance(points), expected, rtol=0, atol=1e-12)
    # The manifold on the right of an operator works too.
    np.testing.assert_allclose((cut | cube).distance(points), (cut | box).distance(points), atol=1e-12)
    np.testing.assert_allclose((nd.Box([1, 1, 1], [5, 5, 5]) - cube).distance(points),
                               (nd.Box([1, 1, 1], [5, 5, 5]) - box).distance(points), atol=1e-12)


def test_manifold_part_offset_inward_packs_inside():
    solid = (manifold3d.Manifold.cube([3.0, 2.0, 1.0])
             - manifold3d.Manifold.cylinder(2.0, 0.5, 0.5, 32).translate([1.5, 1.0, -0.5]))
    mesh = as_oracle(solid)
    packing = nd.pack(mesh.offset(-0.05), n=40, seed=0, backend="numpy", progress=False)
    assert packing.verify().ok
    # Each sphere keeps a 0.05 margin from the part's own surface.
    assert np.all(-mesh.distance(packing.centers) >= packing.radii + 0.05 - 1e-9)


def test_invalid_and_empty_manifolds_say_what_is_wrong():
    # Two triangles sharing one edge: not a closed 2-manifold.
    mesh = manifold3d.Mesh(vert_properties=np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=np.float32),
                           tri_verts=np.array([[0, 1, 2], [0, 3, 1]], dtype=np.uint32))
    with pytest.raises(ShapeError, match="not valid.*NotManifold"):
        nd.pack(manifold3d.Manifold(mesh), n=5)
    empty = (manifold3d.Manifold.cube([1.0, 1.0, 1.0])
             - manifold3d.Manifold.cube([2.0, 2.0, 2.0]).translate([-0.5, -0.5, -0.5]))
    box = nd.Box([0, 0, 0], [1, 1, 1])
    assert box - empty is box  # an empty part of a tree is left out (tests/shapes/test_empty.py)
    with pytest.raises(ShapeError, match="nothing to pack: the manifold3d solid is empty"):
        nd.pack(empty, n=5)


def test_cross_section_is_an_exact_polygon_with_holes():
    section = (manifold3d.CrossSection.square([4.0, 4.0])
               - manifold3d.CrossSection.square([2.0, 2.0]).translate([1.0, 1.0]))
    polygon = as_oracle(section)
    assert isinstance(polygon, nd.Polygon) and polygon.volume().value == pytest.approx(12.0)
    frame = nd.Box([0, 0], [4, 4]) - nd.Box([1, 1], [3, 3])
    points = points_in([0, 0], [4, 4], seed=2)
    inside = frame.distance(points) < 0  # the difference is exact inside
    np.testing.assert_allclose(polygon.distance(points)[inside], frame.distance(points)[inside], atol=1e-12)
    packing = nd.pack(section, n=30, seed=0, backend="numpy", progress=False)
    # The largest circle sits in a corner, touching two outer sides and the hole's corner.
    assert packing.verify().ok and packing.radii[0] == pytest.approx(2 - np.sqrt(2), rel=1e-6)


def test_rings_with_islands_in_holes_follow_the_even_odd_rule():
    square = lambda a, b: [(a, a), (b, a), (b, b), (a, b)]  # noqa: E731
    polygon = nd.Polygon.from_rings([square(0, 6), square(1, 5)[::-1], square(2, 4), [(8, 0), (9, 0), (9, 1)]])
    assert polygon.volume().value == pytest.approx(36 - 16 + 4 + 0.5)
    inside = polygon.contains([[0.5, 0.5], [1.5, 1.5], [3, 3], [8.8, 0.1]])
    assert inside.tolist() == [True, False, True, True]


def test_shapely_polygons():
    shapely = pytest.importorskip("shapely")
    ring = shapely.Polygon([(0, 0), (3, 0), (3, 3), (0, 3)], [[(1, 1), (2, 1), (2, 2), (1, 2)]])
    multi = shapely.MultiPolygon([ring, shapely.Polygon([(4, 0), (5, 0), (5, 1), (4, 1)])])
    polygon = as_oracle(multi)
    assert polygon.volume().value == pytest.approx(multi.area)
    points = points_in([0, 0], [5, 3], seed=3)
    boundary = multi.boundary
    expected = np.array([boundary.distance(shapely.Point(p)) for p in points])
    expected *= np.where([multi.contains(shapely.Point(p)) for p in points], -1, 1)
    np.testing.assert_allclose(polygon.distance(points), expected, atol=1e-12)
    with pytest.raises(ShapeError, match="LineString has no area"):
        as_oracle(shapely.LineString([(0, 0), (1, 1)]))
    bowtie = shapely.Polygon([(0, 0), (1, 1), (1, 0), (0, 1)])
    with pytest.raises(ShapeError, match="make_valid"):
        as_oracle(bowtie)


def test_trimesh_objects_are_meshes():
    trimesh = pytest.importorskip("trimesh")
    mesh = as_oracle(trimesh.creation.box(extents=[1.0, 2.0, 3.0]))
    assert isinstance(mesh, nd.TriangleMesh)
    points = points_in([-0.5, -1, -1.5], [0.5, 1, 1.5], seed=4)
    np.testing.assert_allclose(mesh.distance(points), nd.Box([-0.5, -1, -1.5], [0.5, 1, 1.5]).distance(points),
                               atol=1e-12)


def test_manifold_part_example_packs_at_small_size():
    import importlib.util
    from pathlib import Path

    path = Path(__file__).resolve().parents[2] / "examples" / "manifold_part.py"
    spec = importlib.util.spec_from_file_location("manifold_part", path)
    example = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(example)
    shape = example.part(segments=16) - nd.HalfSpace([0, 0, -1], -1.4)
    packing = nd.pack(shape, n=30, seed=0, backend="numpy", progress=False)
    assert packing.verify().ok and packing.radii[0] == pytest.approx(0.7, rel=1e-3)  # half the trimmed height
