"""Coverings (ndpack.cover) and sphere-trees, checked against independent samples and exact bounds."""

import numpy as np
import pytest
import trimesh
from scipy.spatial import cKDTree

import ndpack as nd
from ndpack.io import read_sph
from ndpack.drivers.collision.sphere_tree import covering_tree, inner_tree

FAST = dict(samples=6000, check_samples=20000)


def outside_union(points, centers, radii):
    """Independent of ndpack.geometry.ball_union: a k-d tree of the centres, each point against every
    centre within the largest radius. (n,) bool: the points no sphere holds."""
    tree = cKDTree(centers)
    missed = np.ones(len(points), dtype=bool)
    for i, near in enumerate(tree.query_ball_point(points, radii.max())):
        near = np.asarray(near, dtype=np.int64)
        if len(near):
            missed[i] = not np.any(np.linalg.norm(centers[near] - points[i], axis=1) <= radii[near] * (1 + 1e-12))
    return missed


def box_faces(lower, upper, count, rng):
    """Uniform points on a box's faces, by area, without ndpack."""
    lower, upper = np.asarray(lower, float), np.asarray(upper, float)
    dim = len(lower)
    extent = upper - lower
    areas = np.array([np.prod(np.delete(extent, axis)) for axis in range(dim)])
    axes = rng.choice(dim, size=count, p=areas / areas.sum())
    points = lower + extent * rng.random((count, dim))
    side = rng.random(count) < 0.5
    points[np.arange(count), axes] = np.where(side, lower[axes], upper[axes])
    return points


def test_box_is_covered_within_the_protrusion_asked():
    lower, upper = np.zeros(3), np.array([1.0, 2.0, 0.5])
    tolerance = 0.02 * np.linalg.norm(upper - lower)
    covering = nd.cover(nd.Box(lower, upper), protrusion=tolerance, **FAST)
    assert covering.report.covered and covering.report.boundary_covered == 1.0
    rng = np.random.default_rng(11)
    faces = box_faces(lower, upper, 30000, rng)
    inside = lower + (upper - lower) * rng.random((10000, 3))
    assert not outside_union(faces, covering.centers, covering.radii).any()
    assert not outside_union(inside, covering.centers, covering.radii).any()
    # Exact for a box: a ball centred inside reaches out by its radius less the distance to the nearest face.
    clearance = np.minimum(covering.centers - lower, upper - covering.centers).min(axis=1)
    assert np.all(clearance > 0)
    assert np.all(covering.radii - clearance <= tolerance * (1 + 1e-9))
    assert covering.report.max_protrusion <= tolerance * (1 + 1e-9)
    assert covering.report.outside_volume > 0


def test_polygon_outline_is_covered():
    outer = [[0, 0], [3, 0], [3, 1], [1, 1], [1, 3], [0, 3]]
    hole = [[0.3, 0.3], [0.6, 0.3], [0.6, 0.6], [0.3, 0.6]]
    shape = nd.Polygon(outer, holes=[hole])
    tolerance = 0.01 * np.linalg.norm([3, 3])
    covering = nd.cover(shape, protrusion=tolerance, **FAST)
    assert covering.report.covered
    # Independent samples on every edge, by length.
    rng = np.random.default_rng(3)
    rings = [np.array(outer, float), np.array(hole, float)]
    starts = np.vstack([ring for ring in rings])
    ends = np.vstack([np.roll(ring, -1, axis=0) for ring in rings])
    lengths = np.linalg.norm(ends - starts, axis=1)
    which = rng.choice(len(starts), size=20000, p=lengths / lengths.sum())
    t = rng.random(20000)[:, None]
    edge_points = starts[which] + t * (ends[which] - starts[which])
    assert not outside_union(edge_points, covering.centers, covering.radii).any()
    assert np.all(covering.radii + shape.distance(covering.centers) <= tolerance * (1 + 1e-9))
    # No disc covers the hole's inside beyond the tolerance: its centre is farther than that from the hole.
    middle = np.array([0.45, 0.45])
    assert np.all(np.linalg.norm(covering.centers - middle, axis=1) - covering.radii > 0.15 - tolerance - 1e-9)


def test_mesh_is_covered_and_spheres_reach_out_no_farther_than_asked():
    capsule = trimesh.creation.capsule(height=0.3, radius=0.08, count=[24, 24])
    mesh = nd.TriangleMesh(capsule.vertices, capsule.faces)
    diagonal = mesh.diagonal
    tolerance = 0.01 * diagonal
    covering = nd.cover(mesh, protrusion=tolerance, **FAST)
    assert covering.report.covered
    surface, _ = trimesh.sample.sample_surface(capsule, 30000, seed=5)
    assert not outside_union(np.asarray(surface), covering.centers, covering.radii).any()
    # Measured, not bounded: points spread over every sphere are within the tolerance of the mesh
    # (the mesh's distance is exact outside).
    rng = np.random.default_rng(0)
    directions = rng.standard_normal((64, 3))
    directions /= np.linalg.norm(directions, axis=1)[:, None]
    shells = (covering.centers[:, None, :] + covering.radii[:, None, None] * directions[None]).reshape(-1, 3)
    assert mesh.distance(shells).max() <= tolerance * (1 + 1e-9)
    assert len(covering) < 2000


def test_four_dimensional_shape_is_covered():
    shape = nd.Box(np.zeros(4), np.ones(4)) - nd.Ball(np.ones(4), 0.6)
    tolerance = 0.12 * 2.0
    covering = nd.cover(shape, protrusion=tolerance, samples=3000, check_samples=10000)
    assert covering.dim == 4 and covering.report.covered
    assert covering.report.boundary_samples == 10000
    assert covering.report.max_protrusion <= tolerance * (1 + 1e-9)
    # The corner cut away stays mostly clear: no centre lies in it.
    assert np.all(np.linalg.norm(covering.centers - 1.0, axis=1) > 0.6)


def test_lower_bound_oracle_keeps_the_bound():
    shape = nd.Ball([0, 0, 0], 1.0) | nd.Ball([1.2, 0, 0], 0.7)  # a union: a lower bound inside
    tolerance = 0.05
    covering = nd.cover(shape, protrusion=tolerance, **FAST)
    assert covering.report.covered
    # The exact distance to a union of balls is the least of the two; reaching out is bounded by it.
    rng = np.random.default_rng(1)
    directions = rng.standard_normal((64, 3))
    directions /= np.linalg.norm(directions, axis=1)[:, None]
    shells = (covering.centers[:, None, :] + covering.radii[:, None, None] * directions[None]).reshape(-1, 3)
    exact = np.minimum(np.linalg.norm(shells, axis=1) - 1.0, np.linalg.norm(shells - [1.2, 0, 0], axis=1) - 0.7)
    assert exact.max() <= tolerance * (1 + 1e-9)


def test_count_mode_keeps_the_count_and_more_spheres_reach_out_less():
    box = nd.Box([0, 0, 0], [1.0, 2.0, 0.5])
    few = nd.cover(box, n=8, **FAST)
    more = nd.cover(box, n=64, **FAST)
    assert len(few) <= 8 and len(more) <= 64
    assert few.report.covered and more.report.covered
    assert more.report.max_protrusion < 0.7 * few.report.max_protrusion
    # 8 balls on a 2 x 4 grid of 0.5-cubes reach out by (sqrt(3) - 1) / 4 = 0.183; the greedy cover
    # and its recentring reach 0.22-0.29 (docs/collision.md): within 75% of the grid.
    assert few.report.max_protrusion < 1.75 * (np.sqrt(3) - 1) / 4


def test_backends_give_coverings_of_the_same_quality():
    shape = nd.Box([0, 0, 0], [1, 1, 1]) - nd.Ball([1, 1, 1], 0.5)
    results = [nd.cover(shape, protrusion=0.1, backend=backend, **FAST) for backend in ("numpy", "numba")]
    assert all(result.report.covered for result in results)
    counts = [len(result) for result in results]
    assert max(counts) <= 1.25 * min(counts)


def test_check_covering_sees_a_gap_and_refuses_bad_radii():
    box = nd.Box([0, 0, 0], [1, 1, 1])
    covering = nd.cover(box, n=8, **FAST)
    report = nd.check_covering(box, covering.centers[1:], covering.radii[1:], samples=5000)
    assert not report.covered and report.worst_gap > 0 and "NOT COVERED" in report.summary()
    with pytest.raises(nd.ParameterError, match="radii"):
        nd.check_covering(box, covering.centers, covering.radii[:-1])


@pytest.mark.parametrize("kwargs, message", [
    (dict(), "either n"), (dict(n=4, protrusion=0.1), "either n"), (dict(n=0), "positive integer"),
    (dict(protrusion=-1.0), "positive length"), (dict(protrusion=0.1, samples=10), "at least 100"),
])
def test_bad_requests_are_refused(kwargs, message):
    with pytest.raises(nd.ParameterError, match=message):
        nd.cover(nd.Box([0, 0], [1, 1]), **kwargs)


def test_covering_saves_as_spheres():
    covering = nd.cover(nd.Box([0, 0, 0], [1, 1, 1]), n=8, **FAST)
    packing = covering.as_packing()
    assert packing.params["covering"]["n"] == 8
    assert np.array_equal(packing.radii, covering.radii)


# ------------------------------------------------------------------------------------------------ trees
def test_covering_tree_levels_cover_and_nest(tmp_path):
    box = nd.Box([0, 0, 0], [1.0, 2.0, 0.5])
    tree = covering_tree(box, branching=4, depth=3, samples=5000)
    sizes = [len(r) for r in tree.radii]
    assert sizes[0] == 1 and sizes[1] <= 4 and sizes[2] <= 16
    for level in range(1, tree.depth):
        assert np.bincount(tree.parents[level]).max() <= 4
    checked = tree.check(samples=20000)
    assert checked["uncovered"] == [0, 0, 0] and checked["nested"] == 0
    # Independently: every face point inside a child is inside its parent, and each level covers.
    points = box_faces([0, 0, 0], [1, 2, 0.5], 20000, np.random.default_rng(9))
    for level in range(tree.depth):
        assert not outside_union(points, tree.centers[level], tree.radii[level]).any()
    assert tree.protrusion[2] < tree.protrusion[1] < tree.protrusion[0]
    path = tree.save(tmp_path / "box.sph")
    for level in range(3):
        centers, radii = read_sph(path, level=level)
        assert np.allclose(np.sort(radii), np.sort(tree.radii[level]))
    assert path.read_text().splitlines()[0] == "3 4"


def test_inner_tree_encloses_children_and_keeps_the_packing_as_leaves(tmp_path):
    packing = nd.pack(nd.Box([0, 0, 0], [1, 1, 1]) - nd.Ball([1, 1, 1], 0.5), n=200, seed=0)
    tree = inner_tree(packing, branching=8)
    assert tree.depth == 4  # 8^2 < 200 <= 8^3
    assert tree.check()["enclosed"]
    for level in range(1, tree.depth):
        parent = tree.parents[level]
        reach = np.linalg.norm(tree.centers[level] - tree.centers[level - 1][parent], axis=1) + tree.radii[level]
        assert np.all(reach <= tree.radii[level - 1][parent] * (1 + 1e-12))
        assert np.bincount(parent).max() <= 8
    leaves = tree.level(-1)
    assert np.allclose(np.sort(leaves[1]), np.sort(packing.radii))
    path = tree.save(tmp_path / "inner.sph")
    assert np.allclose(np.sort(read_sph(path)[1]), np.sort(packing.radii))
    flat = inner_tree(nd.pack(nd.Box([0, 0], [1, 1]), n=30, seed=0), branching=2)
    assert flat.check()["enclosed"] and flat.depth == 6
    with pytest.raises(nd.DimensionError, match="3-D"):
        flat.save(tmp_path / "flat.sph")


def test_open_mesh_covering_says_so_and_a_saved_covering_verifies_as_one(tmp_path, capsys):
    from ndpack.cli import main

    sphere = trimesh.creation.icosphere(subdivisions=2)
    sphere.update_faces(np.flatnonzero(sphere.triangles_center[:, 2] < 0.85))  # a hole at the top
    sphere.remove_unreferenced_vertices()
    path = tmp_path / "open.obj"
    sphere.export(path)
    out = tmp_path / "open.npz"
    assert main(["cover", str(path), "--protrusion", "0.03", "-o", str(out), "--samples", "2000",
                 "--check-samples", "4000", "--holes", "cap"]) == 0
    printed = capsys.readouterr().out
    assert "note:" in printed and "capped" in printed
    assert main(["verify", str(out)]) == 0
    assert "a covering of" in capsys.readouterr().out
    # Spheres shrunk by a tenth leave gaps: verify must say so and fail.
    saved = nd.io.load(out)
    saved.radii[:] *= 0.9
    shrunk = tmp_path / "shrunk.npz"
    nd.io.save(saved, shrunk)
    assert main(["verify", str(shrunk)]) == 1
    assert "NOT COVERED" in capsys.readouterr().out
    assert main(["info", str(out)]) == 0
    assert "a covering" in capsys.readouterr().out


def test_compiled_queries_answer_as_the_shape_does():
    from ndpack.drivers.collision.set_cover import CompiledQueries

    part = nd.Box([0, 0, 0], [1, 2, 0.5]) - nd.Ball([1, 2, 0.5], 0.4) | nd.Capsule([0, 0, 0], [1, 0, 0], 0.2)
    compiled = CompiledQueries.where_it_pays(part, backend="numba")
    assert isinstance(compiled, CompiledQueries) and compiled.bounds is part.bounds
    points = part.bounds[0] + np.ptp(part.bounds, axis=0) * np.random.default_rng(4).random((5000, 3))
    distance, gradient = compiled._distance_and_gradient(points)
    reference, reference_gradient = part._distance_and_gradient(points)
    assert np.allclose(compiled._distance(points), reference, rtol=0, atol=1e-12)
    assert np.allclose(distance, reference, rtol=0, atol=1e-12)
    # Finite differences on one side, analytic on the other: equal but where the gradient jumps.
    assert np.mean(np.linalg.norm(gradient - reference_gradient, axis=1) < 1e-6) > 0.99
    # Meshes answer with their own compiled queries, and the NumPy backend is the shape itself.
    capsule = trimesh.creation.capsule(height=0.3, radius=0.08)
    mesh = nd.TriangleMesh(capsule.vertices, capsule.faces)
    assert CompiledQueries.where_it_pays(mesh, backend="numba") is mesh
    assert CompiledQueries.where_it_pays(part, backend="numpy") is part
