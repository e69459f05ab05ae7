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
from ndpack.verify import sphere_directions

igl = pytest.importorskip("igl")
trimesh = pytest.importorskip("trimesh")

MESHES = Path(__file__).resolve().parents[1] / "data" / "meshes"
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


def test_open_bunny_is_closed_by_caps_and_signed_by_them():
    with pytest.warns(MeshWarning, match=r"open \(5 holes, the largest 0.0459 across\).*holes='cap'"):
        mesh = nd.TriangleMesh.load(MESHES / "stanford-bunny-12k.ply")
    assert mesh.holes == 5 and not mesh.closed and mesh.sign_method == "winding" and not mesh.exact_inside
    assert any(note.startswith("capped 5 holes with") for note in mesh.notes)
    capped = trimesh.Trimesh(mesh.vertices, mesh.faces, process=False)
    assert capped.is_watertight and capped.is_winding_consistent
    assert np.array_equal(mesh.faces[: len(mesh.given_faces)], mesh.given_faces)
    points = around(mesh, 4000, seed=2)
    distance = mesh.distance(points)
    # libigl on the capped surface: the caps count for the distance and the sign everywhere.
    expected, _, _ = reference_signed(mesh, points)
    clear = np.abs(expected) > 1e-6 * mesh.scale
    assert (expected[clear] < 0).sum() > 200
    assert np.array_equal(distance[clear] < 0, expected[clear] < 0)
    assert np.abs(np.abs(distance) - np.abs(expected)).max() <= 1e-9 * mesh.scale
    # Away from the holes (farther from every rim than a tenth of the bunny's size) the given
    # triangles' own winding number agrees.
    edges = trimesh.Trimesh(mesh.vertices, mesh.given_faces, process=False).edges_sorted
    unique, counts = np.unique(edges, axis=0, return_counts=True)
    rim = mesh.vertices[unique[counts == 1]]  # (b, 2, 3): edges of one triangle only
    t = np.linspace(0, 1, 8)[:, None, None]
    rim_points = ((1 - t) * rim[:, 0] + t * rim[:, 1]).reshape(-1, 3)
    from scipy.spatial import cKDTree

    away = cKDTree(rim_points).query(points)[0] > 0.1 * np.ptp(mesh.vertices, axis=0).max()
    given = igl.winding_number(mesh.vertices, mesh.given_faces, points) > 0.5
    assert away.sum() > 1000 and np.array_equal(distance[away & clear] < 0, given[away & clear])
    with pytest.raises(ShapeError, match=r"open: 5 holes \(the largest 0.0459 across.*holes='cap'"):
        nd.TriangleMesh.load(MESHES / "stanford-bunny-12k.ply", holes="refuse")


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
    with pytest.warns(MeshWarning, match="a cap of a hole folds over"):
        nd.TriangleMesh.load(MESHES / "stanford-bunny-12k.ply", sign="pseudonormal", holes="cap")
    with warnings.catch_warnings():
        warnings.simplefilter("error", MeshWarning)  # asked for knowingly: silent
        assert nd.TriangleMesh.load(MESHES / "stanford-bunny-12k.ply", holes="cap").sign_method == "winding"
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


TETRA = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=float)
TETRA_FACES = [[0, 2, 1], [0, 1, 3], [1, 2, 3], [2, 0, 3]]


@pytest.mark.parametrize("vertices, faces, error, message", [
    ([[0, 0], [1, 0], [0, 1]], [[0, 1, 2]], DimensionError, r"3-D vertices.*\(3, 2\).*Polygon"),
    ([0.0, 1.0, 2.0], [[0, 1, 2]], DimensionError, r"shape \(v, 3\); got \(3,\)"),
    (np.zeros((0, 3)), [[0, 1, 2]], ShapeError, r"no vertices"),
    ([["a", "b", "c"]] * 3, [[0, 1, 2]], ShapeError, r"vertices must be a \(v, 3\) array"),
    (np.where(TETRA == 1, np.nan, TETRA), TETRA_FACES, ShapeError,
     r"^3 of the mesh's 4 vertices are not finite \(NaN or infinity\), the first at index 1: fix"),
    (np.vstack([TETRA[:3], [[0, 0, np.inf]]]), TETRA_FACES, ShapeError,
     r"^1 of the mesh's 4 vertices is not finite .* index 3"),
    (TETRA, [[0, 1, 4], [0, 1, 2], [-1, 2, 3]], ShapeError,
     r"^2 of 3 faces refer to vertices that do not exist \(indices -1\.\.\.4, but there are 4 vertices; "
     r"the first such face is row 0, \[0, 1, 4\]\)"),
    (TETRA, [[0, 1, 2, 3]], ShapeError, r"\(f, 3\) array.*got shape \(1, 4\); triangulate"),
    (TETRA, [0, 1, 2], ShapeError, r"\(f, 3\) array.*got shape \(3,\)"),
    (TETRA, [[0, 1, 2], [0, 1]], ShapeError, r"faces must be an \(f, 3\) array"),
    (TETRA, np.zeros((0, 3), dtype=int), ShapeError, r"no triangles \(faces has shape \(0, 3\), for 4 vertices\)"),
    (TETRA, [[0, 1, 2.5]], ShapeError, r"whole-number vertex indices, got float64"),
    (TETRA, [[0, 1, np.nan]], ShapeError, r"whole-number vertex indices"),
    (np.zeros((4, 3)), TETRA_FACES, ShapeError, r"all its triangles' vertices are the same point"),
])
def test_bad_arrays_say_what_is_wrong(vertices, faces, error, message):
    with pytest.raises(error, match=message) as caught:
        nd.TriangleMesh(vertices, faces)
    assert "\n" not in str(caught.value)


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


# ---------------------------------------------------------------------- units
def lumpy_soup():
    """A lumpy closed icosphere (80 triangles) off the origin, as a triangle soup (every corner its
    own vertex, as in an STL file) with one triangle without area: what cleaning must repair."""
    sphere = trimesh.creation.icosphere(subdivisions=1)
    rng = np.random.default_rng(1)
    vertices = sphere.vertices * (1 + 0.15 * rng.random((len(sphere.vertices), 1))) + [0.3, -0.2, 0.1]
    soup = vertices[sphere.faces].reshape(-1, 3)
    collinear = [soup[0], soup[1], 0.5 * (soup[0] + soup[1])]
    return np.vstack([soup, collinear]), np.arange(len(soup) + 3).reshape(-1, 3)


def test_cleaning_and_packing_do_not_depend_on_the_units(tmp_path):
    # Before: at 3e-8 trimesh's absolute tolerances welded 496 of 642 vertices of an icosphere,
    # and at 1e-8 the mesh was refused as having no triangles with area.
    soup, faces = lumpy_soup()
    reference = nd.TriangleMesh(soup, faces)
    assert reference.closed and reference.notes == ["welded 200 duplicate vertices", "dropped 1 triangles without area"]
    options = dict(n=40, grid=12, seed=0, backend="numpy", progress=False)
    expected = nd.pack(reference, **options)
    for scale in (1e-8, 1e8, 2.0**-27):
        mesh = nd.TriangleMesh(soup * scale, faces)
        assert mesh.notes == reference.notes and mesh.sign_method == "pseudonormal"
        np.testing.assert_array_equal(mesh.faces, reference.faces)
        np.testing.assert_allclose(mesh.vertices / scale, reference.vertices, rtol=0, atol=1e-15)
        assert mesh.volume().value / scale**3 == pytest.approx(reference.volume().value, rel=1e-13)
        packing = nd.pack(mesh, **options)
        assert len(packing) == 40 and packing.verify().ok
        if scale == 2.0**-27:  # a power of two scales every float exactly: the same packing, bit for bit
            np.testing.assert_array_equal(packing.centers / scale, expected.centers)
            np.testing.assert_array_equal(packing.radii / scale, expected.radii)
        else:  # rounding differs, and the iterations carry it to ~1e-9 (measured: 1.4e-9 at most)
            np.testing.assert_allclose(packing.centers / scale, expected.centers, rtol=0, atol=1e-7)
            np.testing.assert_allclose(packing.radii / scale, expected.radii, rtol=1e-7)
    # Far from the origin (1e5 sizes away) too: the cleaning happens around the mesh's centre.
    given = soup * 1e-8 + 1e-3
    moved = nd.TriangleMesh(given, faces)
    assert moved.notes == reference.notes and np.array_equal(moved.faces, reference.faces)
    assert (moved.vertices[:, None] == given[None]).all(axis=2).any(axis=1).all()  # given vertices, bit for bit
    # A file is cleaned the same way: trimesh's own processing (absolute tolerances) is not used.
    path = tmp_path / "tiny.obj"  # written in full precision (trimesh's PLY is float32, its OBJ fixed-point)
    path.write_text("".join(f"v {x:.17g} {y:.17g} {z:.17g}\n" for x, y, z in soup * 1e-8)
                    + "".join(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in faces))
    loaded = nd.TriangleMesh.load(path)
    assert loaded.notes == reference.notes and np.array_equal(loaded.faces, reference.faces)


# ---------------------------------------------------------------------- holes
def box_with_open_side() -> trimesh.Trimesh:
    """A unit cube (192 triangles) without its +x side: one planar, square hole."""
    box = trimesh.creation.box().subdivide().subdivide()
    return trimesh.Trimesh(box.vertices, box.faces[box.face_normals[:, 0] < 0.9], process=False)


def test_a_hole_is_capped_and_the_distance_respects_the_cap():
    closed = nd.TriangleMesh.from_trimesh(trimesh.creation.box())
    side = box_with_open_side()
    with pytest.warns(MeshWarning, match=r"open \(1 hole, 1.41 across\)"):
        capped = nd.TriangleMesh.from_trimesh(side)
    assert capped.holes == 1 and not capped.closed and capped.sign_method == "winding"
    assert len(capped.faces) - len(capped.given_faces) == 16  # one triangle per rim edge
    assert "capped 1 hole with 16 triangles (fans to each rim's centre; the largest hole 1.41 across)" in capped.notes
    assert capped.volume().value == pytest.approx(1.0, rel=1e-12)
    # The cap covers the missing side exactly: the same distances as the closed cube's.
    points = np.random.default_rng(0).uniform(-0.7, 0.7, (3000, 3))
    np.testing.assert_allclose(capped.distance(points), closed.distance(points), rtol=0, atol=1e-12)
    # What the distance to the given triangles alone allowed: a sphere that reaches through the
    # hole (centre 0.1 inside, radius 0.3). Both checks now see it, the independent one too.
    reaching = nd.verify(np.array([[0.4, 0.0, 0.0]]), capped, radii=[0.3], independent=True)
    assert not reaching.ok and reaching.outside.tolist() == [0] and reaching.samples_outside.tolist() == [0]
    with pytest.raises(ShapeError, match=r"^the mesh is open: 1 hole \(the largest 1.41 across, for a mesh 1 across"):
        nd.TriangleMesh.from_trimesh(side, holes="refuse")
    assert nd.TriangleMesh.from_trimesh(trimesh.creation.box(), holes="refuse").holes == 0
    with pytest.raises(ShapeError, match=r"holes must be one of \('cap', 'refuse'\), got 'fill'"):
        nd.TriangleMesh.from_trimesh(side, holes="fill")


def test_a_packing_records_what_inside_means_at_the_holes(tmp_path):
    side = box_with_open_side()
    with pytest.warns(MeshWarning, match="open"):
        by_default = nd.TriangleMesh.from_trimesh(side)
    capped = nd.TriangleMesh.from_trimesh(side, holes="cap")
    closed = nd.TriangleMesh.from_trimesh(trimesh.creation.box())
    refusing = nd.TriangleMesh.from_trimesh(trimesh.creation.box(), holes="refuse")
    assert (by_default.hole_option, capped.hole_option, closed.hole_option, refusing.hole_option) == (
        "cap", "cap", None, "refuse")
    options = dict(n=4, grid=6, backend="numpy", progress=False)
    packing = nd.pack(capped, **options)
    assert packing.params["holes"] == "cap" and nd.pack(by_default, **options).params["holes"] == "cap"
    assert "holes" not in nd.pack(closed, **options).params
    assert nd.pack(refusing, **options).params["holes"] == "refuse"
    # In a tree: capped wins over refused (capping leaves a closed mesh as it is).
    assert nd.pack(capped - nd.Ball([0.5, 0, 0], 0.2), **options).params["holes"] == "cap"
    assert nd.pack(refusing | nd.Ball([0.5, 0, 0], 0.2), **options).params["holes"] == "refuse"
    for suffix in (".npz", ".json", ".csv"):
        assert nd.Packing.load(packing.save(tmp_path / f"capped{suffix}")).params["holes"] == "cap"


def test_rims_of_any_shape_are_closed():
    # Two holes that share a vertex (a rim that touches itself), and an edge of three triangles.
    sphere = trimesh.creation.icosphere(subdivisions=1)
    shared = np.flatnonzero((sphere.faces == 0).any(axis=1))[[0, 2]]  # two faces around vertex 0, not adjacent
    faces = np.delete(sphere.faces, shared, axis=0)
    fin = np.vstack([sphere.faces, [[sphere.faces[0, 0], sphere.faces[0, 1], len(sphere.vertices)]]])
    for vertices, given in ((sphere.vertices, faces), (np.vstack([sphere.vertices, [[0, 0, 3.0]]]), fin)):
        mesh = nd.TriangleMesh(vertices, given, holes="cap")
        edges = np.sort(mesh.faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
        directed = mesh.faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2)
        # Every edge is used as often in each direction: the capped surface is closed.
        balance = np.where(directed[:, 0] < directed[:, 1], 1, -1)
        _, inverse = np.unique(edges, axis=0, return_inverse=True)
        assert not np.bincount(inverse.ravel(), balance).any()
        assert mesh.holes == 1 and mesh.sign_method == "winding"


@pytest.mark.parametrize("name", ["icosphere with three holes", "box with an open side", "two crossing boxes"])
def test_open_and_self_crossing_meshes_pack_inside_by_the_exact_winding_number(name):
    sphere = trimesh.creation.icosphere(subdivisions=2)
    if name == "icosphere with three holes":  # two planar pentagons, and a hexagon 0.009 off its plane
        holes = (sphere.faces == 0).any(axis=1) | (sphere.faces == 5).any(axis=1) | (sphere.faces == 100).any(axis=1)
        given = trimesh.Trimesh(sphere.vertices, sphere.faces[~holes], process=False)
    elif name == "box with an open side":
        given = box_with_open_side()
    else:  # one mesh of two closed boxes that cross: inside is their union
        second = trimesh.creation.box(extents=(1, 2, 1)).apply_translation((0.3, 0.4, 0.2))
        given = trimesh.util.concatenate([trimesh.creation.box(extents=(2, 1, 1)), second])
    mesh = nd.TriangleMesh.from_trimesh(given, holes="cap")
    assert mesh.sign_method == "winding"
    packing = nd.pack(mesh, n=30, grid=12, seed=0, backend="numpy", progress=False)
    report = packing.verify(independent=True)
    assert len(packing) == 30 and report.ok and report.samples_outside.size == 0, report.summary()
    if name == "box with an open side":
        # One planar hole: the given triangles' own winding number agrees with the cap.
        points = packing.centers[:, None] + packing.radii[:, None, None] * sphere_directions(48)
        assert (mesh.exact_winding_number(points.reshape(-1, 3), caps=False) > 0.5).all()
    if name == "two crossing boxes":
        assert any("crosses itself" in note for note in mesh.notes)
        assert (mesh.exact_winding_number(packing.centers) > 1.5).any()  # spheres in the overlap too


def test_exact_winding_number_matches_libigl():
    mesh = nd.TriangleMesh.from_trimesh(box_with_open_side(), holes="cap")
    points = np.random.default_rng(1).uniform(-0.8, 0.8, (500, 3))
    for caps, faces in ((True, mesh.faces), (False, mesh.given_faces)):
        expected = igl.winding_number(mesh.vertices, faces, points)
        np.testing.assert_allclose(mesh.exact_winding_number(points, caps=caps), expected, rtol=0, atol=1e-12)
    with pytest.raises(nd.ParameterError, match="independent=True checks triangle meshes"):
        nd.verify(np.zeros((1, 3)), nd.Ball([0, 0, 0], 1.0), radii=[0.5], independent=True)


def test_the_trees_sort_is_the_stable_argsort():
    """The tree's fallback split sorts by a hand-written heap sort (Numba compiles it faster than
    the mergesort argsort): the same order, ties included."""
    from ndpack.meshes import bvh

    bvh._compiled()  # compiles _stable_order too
    rng = np.random.default_rng(5)
    for count in (0, 1, 2, 3, 8, 17, 300):
        for keys in (rng.random(count), rng.integers(0, 3, count).astype(np.float64)):
            np.testing.assert_array_equal(bvh._stable_order(keys), np.argsort(keys, kind="mergesort"))



# ---------------------------------------------------------------------- stepping in
@pytest.mark.parametrize("name", ["armadillo-20k", "stanford-bunny-12k"])  # signed by pseudonormals, by winding
def test_a_mesh_steps_in_as_the_base_class_loop_does(name):
    """The mesh's compiled step in (queries.step_in) gives the numbers of Oracle._step_inside's NumPy
    loop over its _distance_and_gradient, to the bit: points outside near the surface, some on it
    (the nearest triangle's normal), each in a box around it, some boxes too small to reach inside."""
    mesh = load(name)
    rng = np.random.default_rng(3)
    corners = mesh.vertices[mesh.faces[rng.integers(len(mesh.faces), size=600)]]
    on = np.einsum("fk,fki->fi", rng.dirichlet(np.ones(3), size=len(corners)), corners)
    points = np.vstack([on[:40], on[40:] + 0.03 * mesh.scale * rng.normal(size=(len(on) - 40, 3))])
    points = points[mesh.distance(points) >= 0]
    assert (np.abs(mesh.distance(points)) <= 1e-12 * mesh.scale).sum() >= 10  # on the surface: about half of 40
    half = rng.uniform(0.001, 0.05, (len(points), 3)) * mesh.scale
    lower, upper = points - half, points + half
    got_points, got_depth = mesh._step_inside(points, lower, upper, 20, 1e-8)
    want_points, want_depth = nd.Oracle._step_inside(mesh, points, lower, upper, 20, 1e-8)
    assert np.array_equal(got_points, want_points) and np.array_equal(got_depth, want_depth)
    inside = got_depth > 0
    assert 0 < inside.sum() < len(points)  # some got in, some could not
    assert (got_points >= lower).all() and (got_points <= upper).all()
