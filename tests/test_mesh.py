"""Triangle meshes as oracles, against libigl (an independent float64 implementation).

The meshes are small copies of ``shared/data/meshes`` (``tests/data/meshes/README.md``): closed
CAD parts and scans, a decimated armadillo, the open Stanford bunny and spot with unwelded seams.
"""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest

import ndpack as nd
from ndpack.errors import DimensionError, MeshWarning, ShapeError

igl = pytest.importorskip("igl")
trimesh = pytest.importorskip("trimesh")

MESHES = Path(__file__).parent / "data" / "meshes"
CLOSED = ["cow", "fandisk", "rocker-arm", "armadillo-20k", "spot-unwelded"]


def load(name: str, **options) -> nd.TriangleMesh:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", MeshWarning)
        return nd.TriangleMesh.load(MESHES / f"{name}.ply", **options)


def around(mesh, count: int, seed: int = 0) -> np.ndarray:
    """Points in the mesh's box enlarged by 10%, half of them within 2% of its size of the surface."""
    rng = np.random.default_rng(seed)
    lower, upper = mesh.bounds
    pad = 0.1 * (upper - lower)
    wide = rng.uniform(lower - pad, upper + pad, (count // 2, 3))
    corners = mesh.vertices[mesh.faces[rng.integers(len(mesh.faces), size=count - count // 2)]]
    weights = rng.dirichlet(np.ones(3), size=len(corners))
    near = np.einsum("fk,fki->fi", weights, corners) + 0.02 * mesh.scale * rng.normal(size=(len(corners), 3))
    return np.vstack([wide, near])


def reference_signed(mesh, points):
    """libigl: exact unsigned distance and closest points; inside where the exact winding number > 1/2."""
    squared, _, closest = igl.point_mesh_squared_distance(points, mesh.vertices, mesh.faces)
    winding = igl.winding_number(mesh.vertices, mesh.faces, points)
    return np.where(winding > 0.5, -1.0, 1.0) * np.sqrt(squared), closest, winding


# ---------------------------------------------------------------------- distances and signs
@pytest.mark.parametrize("name", CLOSED)
def test_distance_matches_libigl(name):
    mesh = load(name)
    points = around(mesh, 3000)
    distance, gradient = mesh.distance_and_gradient(points)
    expected, closest, _ = reference_signed(mesh, points)
    scale = mesh.scale
    assert np.abs(np.abs(distance) - np.abs(expected)).max() <= 1e-9 * scale
    clear = np.abs(expected) > 1e-6 * scale
    assert np.array_equal(distance[clear] < 0, expected[clear] < 0)
    assert np.abs(mesh.distance(points) - distance).max() <= 1e-12 * scale
    # The gradient leads back to the nearest point, which libigl finds too.
    assert np.allclose(np.linalg.norm(gradient, axis=1), 1.0)
    assert np.abs(mesh.nearest_boundary_point(points) - closest).max() <= 1e-9 * scale


def test_bounded_queries_find_only_what_is_near():
    mesh = load("fandisk")
    points = around(mesh, 2000, seed=1)
    unsigned, closest, triangle = mesh.closest_points(points)
    bound = 0.05 * mesh.scale
    near_distance, near_closest, near_triangle = mesh.closest_points(points, max_distance=bound)
    near = unsigned < bound
    assert near.any() and (~near).any()
    np.testing.assert_allclose(near_distance[near], unsigned[near], rtol=0, atol=1e-12 * mesh.scale)
    np.testing.assert_allclose(near_closest[near], closest[near], rtol=0, atol=1e-12 * mesh.scale)
    assert np.all(near_distance[~near] == bound) and np.all(near_triangle[~near] == -1)
    assert np.isnan(near_closest[~near]).all()
    # The triangle numbers are rows of mesh.faces: the closest point lies on that triangle.
    corners = mesh.vertices[mesh.faces[triangle]]
    normal = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    offset = np.einsum("ij,ij->i", closest - corners[:, 0], normal / np.linalg.norm(normal, axis=1, keepdims=True))
    assert np.abs(offset).max() <= 1e-9 * mesh.scale


def test_open_bunny_sign_is_right_away_from_its_holes():
    with pytest.warns(MeshWarning, match="winding number"):
        mesh = nd.TriangleMesh.load(MESHES / "stanford-bunny-12k.ply")
    assert mesh.sign_method == "winding" and not mesh.closed and not mesh.exact_inside
    points = around(mesh, 4000, seed=2)
    distance = mesh.distance(points)
    expected, _, _ = reference_signed(mesh, points)
    # Away from the holes: farther from every boundary edge than a tenth of the bunny's size.
    edges = trimesh.Trimesh(mesh.vertices, mesh.faces, process=False).edges_sorted
    unique, counts = np.unique(edges, axis=0, return_counts=True)
    rim = mesh.vertices[unique[counts == 1]]  # (b, 2, 3): edges of one triangle only
    t = np.linspace(0, 1, 8)[:, None, None]
    rim_points = ((1 - t) * rim[:, 0] + t * rim[:, 1]).reshape(-1, 3)
    from scipy.spatial import cKDTree

    away = cKDTree(rim_points).query(points)[0] > 0.1 * np.ptp(mesh.vertices, axis=0).max()
    clear = away & (np.abs(expected) > 1e-6 * mesh.scale)
    assert clear.sum() > 1000 and (expected[clear] < 0).sum() > 200
    assert np.array_equal(distance[clear] < 0, expected[clear] < 0)
    assert np.abs(np.abs(distance) - np.abs(expected)).max() <= 1e-9 * mesh.scale


def test_winding_number_is_close_to_the_exact_one():
    mesh = load("rocker-arm")
    points = around(mesh, 2000, seed=3)
    _, _, exact = reference_signed(mesh, points)
    approximate = mesh.winding_number(points)
    # A first-order far field: errors of a few hundredths (measured: at most 0.08 on 20,000
    # points), far from the threshold of 1/2 that decides the sign.
    assert np.abs(approximate - exact).max() < 0.15
    assert np.median(np.abs(approximate - exact)) < 0.05
    assert np.array_equal(approximate > 0.5, exact > 0.5)


# ---------------------------------------------------------------------- the check of the mesh
def test_sign_method_follows_the_check_of_the_mesh():
    assert load("fandisk").sign_method == "pseudonormal"
    spot = load("spot-unwelded")  # texture seams split its vertices: welding closes it
    assert spot.closed and spot.sign_method == "pseudonormal"
    assert any("welded" in note for note in spot.notes)
    cow = load("cow")  # closed, but its head crosses itself
    assert cow.closed and cow.sign_method == "winding" and not cow.exact_inside
    assert any("crosses itself" in note for note in cow.notes)
    assert load("fandisk", sign="winding").sign_method == "winding"
    with pytest.warns(MeshWarning, match="open"):
        nd.TriangleMesh.load(MESHES / "stanford-bunny-12k.ply", sign="pseudonormal")
    with warnings.catch_warnings():
        warnings.simplefilter("error", MeshWarning)  # asked for knowingly: silent
        assert nd.TriangleMesh.load(MESHES / "stanford-bunny-12k.ply", sign="winding").sign_method == "winding"
    with pytest.raises(ShapeError, match="sign must be one of"):
        load("fandisk", sign="normals")


def test_inverted_and_inconsistent_triangles_are_repaired():
    source = load("fandisk")
    inverted = nd.TriangleMesh(source.vertices, source.faces[:, ::-1])
    assert any("outward" in note for note in inverted.notes)
    flipped = source.faces.copy()
    flipped[:50] = flipped[:50, ::-1]
    patched = nd.TriangleMesh(source.vertices, flipped)
    assert patched.closed and patched.sign_method == "pseudonormal"
    points = around(source, 1000, seed=4)
    for mesh in (inverted, patched):
        assert np.abs(mesh.distance(points) - source.distance(points)).max() <= 1e-12 * source.scale


def test_volume_of_a_closed_mesh_is_exact():
    mesh = load("fandisk")
    expected = trimesh.load(MESHES / "fandisk.ply", force="mesh").volume
    assert mesh.volume().exact and mesh.volume().value == pytest.approx(expected, rel=1e-12)


# ---------------------------------------------------------------------- bad input
def test_bad_files_say_what_is_wrong(tmp_path):
    with pytest.raises(ShapeError, match="no mesh file"):
        nd.TriangleMesh.load(tmp_path / "missing.stl")
    empty = tmp_path / "empty.stl"
    empty.write_bytes(b"")
    with pytest.raises(ShapeError, match="empty"):
        nd.TriangleMesh.load(empty)
    with pytest.raises(ShapeError, match="folder"):
        nd.TriangleMesh.load(tmp_path)
    garbage = tmp_path / "garbage.obj"
    garbage.write_text("this is not a mesh\n")
    with pytest.raises(ShapeError):
        nd.TriangleMesh.load(garbage)


def test_meshes_without_volume_are_refused():
    square = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], dtype=float)
    with pytest.raises(ShapeError, match="no volume"):
        nd.TriangleMesh(square, [[0, 1, 2], [0, 2, 3]])
    # Closed but flat: both sides of the same square.
    with pytest.raises(ShapeError, match="no volume"):
        nd.TriangleMesh(square, [[0, 1, 2], [0, 2, 3], [0, 2, 1], [0, 3, 2]])
    with pytest.raises(ShapeError, match="no triangles with area"):
        nd.TriangleMesh(square, [[0, 1, 1], [2, 2, 2]])


def test_bad_arrays_say_what_is_wrong():
    with pytest.raises(DimensionError, match="3-D vertices.*Polygon"):
        nd.TriangleMesh([[0, 0], [1, 0], [0, 1]], [[0, 1, 2]])
    tetra = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=float)
    with pytest.raises(ShapeError, match="refer to vertices"):
        nd.TriangleMesh(tetra, [[0, 1, 4]])
    with pytest.raises(ShapeError, match=r"\(f, 3\)"):
        nd.TriangleMesh(tetra, [[0, 1, 2, 3]])
    with pytest.raises(ShapeError, match="no triangles"):
        nd.TriangleMesh(tetra, np.zeros((0, 3), dtype=int))
    with pytest.raises(ShapeError, match="non-finite"):
        nd.TriangleMesh(np.where(tetra == 1, np.nan, tetra), [[0, 1, 2]])


def test_a_file_with_a_nan_vertex_is_refused(tmp_path):
    # trimesh's processing drops such a vertex's triangles: the file loaded as a mesh with holes.
    tetra = ["v 0 0 0", "v 1 0 0", "v 0 1 0", "v 0 0 nan", "f 1 3 2", "f 1 2 4", "f 2 3 4", "f 3 1 4"]
    path = tmp_path / "nan.obj"
    path.write_text("\n".join(tetra) + "\n")
    with pytest.raises(ShapeError, match="nan.obj' has 1 vertex with non-finite"):
        nd.TriangleMesh.load(path)


# ---------------------------------------------------------------------- packings
@pytest.mark.parametrize("name", ["armadillo-20k", "cow", "fandisk", "rocker-arm"])
def test_packing_is_inside_by_libigl(name):
    mesh = load(name)
    packing = nd.pack(mesh, n=60, seed=0, backend="numpy", progress=False)
    assert len(packing.radii) == 60 and packing.verify().ok
    # Containment by the independent reference: each centre is at least its radius inside.
    signed, _, _ = reference_signed(mesh, packing.centers)
    assert np.all(-signed >= packing.radii - 1e-9 * mesh.scale)
    # The first sphere is the largest that fits, up to the grid's resolution: no sample point
    # of the mesh's interior is farther from the surface.
    points = around(mesh, 20000, seed=5)
    assert packing.radii[0] >= 0.97 * (-mesh.distance(points)).max()
