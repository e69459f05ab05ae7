"""Periodic domains: ``nd.Periodic``, its images, and packings checked against every image."""

import itertools

import numpy as np
import pytest

import ndpack as nd
from ndpack import cli
from ndpack.geometry.period import Period
from ndpack.drivers.sizes import SizeDistribution
from ndpack.verify import overlapping_pairs

MARGIN = 1e-10  # the driver's gap between spheres (ndpack.drivers.greedy.protosphere.SAFETY_MARGIN, times the scale 1)


def worst_image_overlap(centers, radii, periodic, lengths):
    """Independent of ndpack.geometry.period: the largest ``r_i + r_j - |c_i - (c_j + k L)|`` over every
    pair and every shift ``k`` in {-1, 0, 1} along the periodic axes (a sphere with its own
    images included), from every copy written out and a plain k-d tree over them."""
    from scipy.spatial import cKDTree

    shifts = np.array(list(itertools.product(*[(-1, 0, 1) if flag else (0,) for flag in periodic])), dtype=float)
    copies = (centers[None] + shifts[:, None] * np.asarray(lengths, dtype=float)).reshape(-1, centers.shape[1])
    owner = np.tile(np.arange(len(radii)), len(shifts))
    moved = np.repeat(np.any(shifts != 0, axis=1), len(radii))
    found = cKDTree(copies).query_ball_point(centers, radii + radii.max())
    worst = -np.inf
    for index, near in enumerate(found):
        near = np.asarray(near, dtype=np.int64)
        near = near[(owner[near] != index) | moved[near]]  # not the sphere itself, but its images
        if len(near):
            gaps = np.linalg.norm(copies[near] - centers[index], axis=1) - radii[index] - radii[owner[near]]
            worst = max(worst, float(-gaps.min()))
    return worst


def box(dim, upper=1.0):
    return nd.Box(np.zeros(dim), np.full(dim, upper))


# ---------------------------------------------------------------------- geometry
def test_wrap_and_nearest_image():
    period = Period([0.0, -1.0], [2.0, 1.0], [True, False])
    points = np.array([[-0.5, 3.0], [2.0, 0.0], [4.25, -2.0]])
    assert np.allclose(period.wrap(points), [[1.5, 3.0], [0.0, 0.0], [0.25, -2.0]])
    delta = period.difference(np.array([[0.1, 0.0]]), np.array([[1.9, 0.5]]))
    assert np.allclose(delta, [[0.2, -0.5]])  # across the periodic face, not across the free axis
    assert period.periods == [2.0, None] and period.shortest == 2.0


def test_images_are_every_copy_within_reach():
    rng = np.random.default_rng(0)
    period = Period(np.zeros(3), np.ones(3), [True, True, False])
    centers, radii, reach = rng.random((400, 3)), rng.uniform(0.01, 0.05, 400), 0.1
    found, found_radii, source = period.images(centers, radii, reach)
    # Every shift by -1, 0, +1 along x and y, except none, kept where it comes within reach of the cell.
    expected = set()
    for index, (center, radius) in enumerate(zip(centers, radii)):
        for shift in itertools.product((-1, 0, 1), (-1, 0, 1)):
            if shift == (0, 0):
                continue
            moved = center + np.array([*shift, 0.0])
            outside = np.maximum(np.maximum(-moved, moved - 1.0), 0.0)
            if np.linalg.norm(outside) <= reach + radius:
                expected.add((index, *shift))
    shifts = np.rint(found - centers[source]).astype(int)
    assert {(int(i), int(x), int(y)) for i, (x, y, _) in zip(source, shifts)} == expected
    assert np.array_equal(found_radii, radii[source]) and len(found) == len(expected)


def test_the_faces_of_a_periodic_axis_are_no_walls():
    cell = nd.Periodic(nd.Box([0.0, 0.0], [2.0, 1.0]), axes=[0])
    # Along x (periodic) no wall: the distance is the y walls' only, everywhere along x.
    points = np.array([[0.0, 0.5], [1.0, 0.5], [1.999, 0.25]])
    assert np.allclose(cell.distance(points), [-0.5, -0.5, -0.25])
    assert cell.volume().value == 2.0 and cell.volume().exact
    assert cell.period.periods == [2.0, None]
    # The compiled backends see the same distance (the projection is data in the shape's kernel).
    backend = nd.backends.get_backend("numba")
    samples = np.random.default_rng(1).uniform(-0.5, 2.5, (200, 2))
    assert np.allclose(backend.distance(cell, samples), cell.distance(samples), atol=1e-12)


# ---------------------------------------------------------------------- packings
@pytest.mark.parametrize("dim, second", [(2, (np.sqrt(2) - 1) / 2), (3, (np.sqrt(3) - 1) / 2), (4, 0.5)])
def test_the_first_spheres_of_a_periodic_cube_are_the_lattice_holes(dim, second):
    """A unit periodic cube holds one sphere of radius 1/2 (it touches its own images); the next
    goes in the hole at the cell's body centre: radius (sqrt(d) - 1) / 2, which in 4-D is 1/2
    again (the D4 lattice)."""
    packing = nd.pack(nd.Periodic(box(dim)), n=2, backend="numpy", on_invalid="raise")
    assert packing.radii[0] == pytest.approx(0.5, abs=2 * MARGIN)
    assert packing.radii[1] == pytest.approx(second, abs=1e-6)


@pytest.mark.parametrize("shape, periodic, lengths, n", [
    (nd.Periodic(box(2)), [1, 1], [1, 1], 400),
    (nd.Periodic(nd.Box([0.0, 0.0, 0.0], [1.0, 1.0, 0.5]), axes=[0, 1]), [1, 1, 0], [1, 1, 0.5], 1500),
    (nd.Periodic(nd.Cylinder([0.0, 0.0, 0.0], [0.0, 0.0, 1.0], 0.4) & nd.Slab([0.0, 0.0, 1.0], 0.0, 1.0), axes=2),
     [0, 0, 1], [0, 0, 1], 800),
    (nd.Periodic(box(4)), [1, 1, 1, 1], [1, 1, 1, 1], 1500),
])
@pytest.mark.parametrize("mode", ["fast", "faithful"])
def test_no_sphere_meets_any_image_of_another(shape, periodic, lengths, n, mode):
    if mode == "faithful":
        n = min(n, 150)
    packing = nd.pack(shape, n=n, mode=mode, backend="numba", on_invalid="raise")
    assert len(packing) == n and packing.repair is None
    assert worst_image_overlap(packing.centers, packing.radii, periodic, lengths) <= 0
    lower, upper = shape.bounds
    axes = np.asarray(periodic, dtype=bool)
    assert np.all(packing.centers[:, axes] >= lower[axes]) and np.all(packing.centers[:, axes] < upper[axes])
    assert np.all(shape.distance(packing.centers) + packing.radii <= 0)  # inside along the walls
    # Spheres cross the periodic faces: some reach past the cell there.
    assert np.any(packing.centers[:, axes] - packing.radii[:, None] < lower[axes])


def test_a_periodic_box_fills_as_on_the_reference_backend():
    shape = nd.Periodic(nd.Box([0.0, 0.0], [1.0, 0.8]), axes=[0])
    packings = {name: nd.pack(shape, n=40, grid=16, backend=name, on_invalid="raise")
                for name in ("numpy", "numba", "warp")}
    for name, packing in packings.items():
        assert worst_image_overlap(packing.centers, packing.radii, [1, 0], [1, 0]) <= 0, name
        assert packing.fill == pytest.approx(packings["numpy"].fill, rel=2e-3), name
        assert np.allclose(packing.radii[:3], packings["numpy"].radii[:3], atol=1e-6), name


def test_equal_spheres_in_a_periodic_box():
    packing = nd.pack(nd.Periodic(box(3)), n=10_000, mode="fast", backend="numba", min_radius=0.05,
                      max_radius=0.05, on_invalid="raise")
    assert np.all(packing.radii == 0.05) and packing.stop_reason == "min_radius"
    assert worst_image_overlap(packing.centers, packing.radii, [1, 1, 1], [1, 1, 1]) <= 0
    assert packing.fill > 0.38  # random sequential addition's saturation in 3-D


def test_sizes_in_a_4d_periodic_box():
    lognormal = SizeDistribution.lognormal(0.05, 0.25, by="mass")
    packing = nd.pack_sizes(nd.Periodic(box(4)), lognormal, n=10_000, grid=8, backend="numba")
    report = lognormal.report(packing)
    assert len(packing) == 10_000 and packing.params["unplaced"] == 0 and packing.repair is None
    assert report.ks <= 0.05, report
    assert worst_image_overlap(packing.centers, packing.radii, [1] * 4, [1] * 4) <= 0


# ---------------------------------------------------------------------- verification
def test_verify_sees_overlaps_across_the_faces():
    shape = nd.Periodic(box(2), axes=[0])
    # Disjoint in the plane, but 0.1 apart across the face x = 0 = 1 with radii 0.1 each.
    centers, radii = np.array([[0.05, 0.5], [0.95, 0.5]]), np.array([0.1, 0.1])
    assert len(overlapping_pairs(centers, radii)[0]) == 0
    report = nd.verify(centers, shape, radii=radii)
    assert not report.ok and report.overlapping.tolist() == [[0, 1]]
    assert report.worst_overlap == pytest.approx(0.1)
    # Across the free axis y the same pair is apart.
    assert nd.verify(centers[:, ::-1], nd.Periodic(box(2), axes=[0]), radii=radii).overlapping.size == 0
    assert nd.verify(centers[:, ::-1], nd.Periodic(box(2), axes=[1]), radii=radii).overlapping.tolist() == [[0, 1]]


def test_a_sphere_wider_than_the_period_meets_itself():
    pairs, worst = overlapping_pairs(np.array([[0.5, 0.5]]), np.array([0.6]), 0.0,
                                     Period([0, 0], [1, 1], [True, False]))
    assert pairs.tolist() == [[0, 0]] and worst == pytest.approx(0.2)


# ---------------------------------------------------------------------- files and command line
def test_the_command_line_packs_and_verifies_a_periodic_box(tmp_path, capsys):
    data, npz = tmp_path / "bed.data", tmp_path / "bed.npz"
    assert cli.main(["pack", "box:dim=3", "--periodic", "0,1", "-n", "150", "--mode", "fast", "-q",
                     "-o", str(data)]) == 0
    text = data.read_text()
    assert "boundary p p f" in text and "0 1 xlo xhi" in text
    assert cli.main(["pack", "box:dim=2", "--periodic", "all", "-n", "100", "-q", "-o", str(npz)]) == 0
    capsys.readouterr()
    assert cli.main(["verify", str(npz)]) == 0
    assert "Periodic(Box" in capsys.readouterr().out
    packing = nd.Packing.load(npz)
    assert packing.params["period"] == [1.0, 1.0]


@pytest.mark.parametrize("make, message", [
    (lambda: nd.Periodic(nd.HalfSpace([0.0, 1.0], 0.0)), "bounded shape"),
    (lambda: nd.Periodic(box(2), axes=[2]), "axis numbers from 0 to 1"),
    (lambda: nd.Periodic(box(2), axes=[]), "no periodic axis"),
    (lambda: nd.Periodic(box(3), axes=[True, False]), "one per axis"),
])
def test_bad_periodic_shapes_are_refused(make, message):
    with pytest.raises(nd.ShapeError, match=message):
        make()


def test_a_distribution_wider_than_the_period_is_refused():
    cell = nd.Periodic(nd.Box([0.0, 0.0], [1.0, 4.0]), axes=[0])
    with pytest.raises(nd.ParameterError, match="half the shortest period"):
        nd.pack_sizes(cell, SizeDistribution.discrete([0.6], [1.0]), n=3)
