"""Tests of ndpack.shapes.polygon.Polygon against an independent, scalar reference."""

import math
import tracemalloc

import numpy as np
import pytest

from ndpack.errors import ShapeError
from ndpack.oracle import monte_carlo_volume
from ndpack.shapes.polygon import Polygon

SQUARE = [[0, 0], [2, 0], [2, 2], [0, 2]]
SQUARE_HOLE = [[0.5, 0.5], [1.5, 0.5], [1.5, 1.5], [0.5, 1.5]]
L_SHAPE = [[0, 0], [2, 0], [2, 1], [1, 1], [1, 2], [0, 2]]


# ---------------------------------------------------------------------- reference
def segment_nearest(p, a, b):
    """Nearest point to p on segment ab, by plain scalar arithmetic."""
    ax, ay = a
    bx, by = b
    ex, ey = bx - ax, by - ay
    t = ((p[0] - ax) * ex + (p[1] - ay) * ey) / (ex * ex + ey * ey)
    t = min(1.0, max(0.0, t))
    return (ax + t * ex, ay + t * ey)


def winding_number(p, ring):
    """Sum of the signed angles subtended by the edges: +-1 inside a ring, 0 outside."""
    total = 0.0
    for a, b in zip(ring, ring[1:] + ring[:1]):
        u = (a[0] - p[0], a[1] - p[1])
        v = (b[0] - p[0], b[1] - p[1])
        total += math.atan2(u[0] * v[1] - u[1] * v[0], u[0] * v[0] + u[1] * v[1])
    return round(total / (2 * math.pi))


def reference(p, outer, holes=()):
    """Signed distance and all per-edge (distance, nearest point) pairs for one point."""
    rings = [[tuple(map(float, v)) for v in ring] for ring in [outer, *holes]]
    per_edge = []
    for ring in rings:
        for a, b in zip(ring, ring[1:] + ring[:1]):
            q = segment_nearest(p, a, b)
            per_edge.append((math.dist(p, q), q))
    unsigned = min(d for d, _ in per_edge)
    inside = winding_number(p, rings[0]) != 0 and all(winding_number(p, h) == 0 for h in rings[1:])
    return (-unsigned if inside else unsigned), per_edge


def reference_distances(points, outer, holes=()):
    return np.array([reference(tuple(p), outer, holes)[0] for p in points])


def random_points(shape, n, seed, margin=0.5):
    rng = np.random.default_rng(seed)
    lower, upper = shape.bounds
    return lower - margin + (upper - lower + 2 * margin) * rng.random((n, 2))


def star(n, seed):
    """A random star-shaped (generally concave) polygon around the origin."""
    rng = np.random.default_rng(seed)
    angles = np.sort(rng.uniform(0, 2 * np.pi, n))
    radii = rng.uniform(1.0, 2.0, n)
    return np.column_stack([radii * np.cos(angles), radii * np.sin(angles)])


# ---------------------------------------------------------------------- values
def test_square_known_values():
    square = Polygon(SQUARE)
    points = [[1, 1], [0.5, 1], [3, 1], [-1, -1], [2, 1], [0, 0]]
    expected = [-1, -0.5, 1, math.sqrt(2), 0, 0]
    np.testing.assert_allclose(square.distance(points), expected, atol=1e-15)
    assert square.exact_inside and square.exact_outside and not square.convex
    np.testing.assert_array_equal(square.bounds, [[0, 0], [2, 2]])


def test_square_with_hole_inside_the_hole_is_outside():
    shape = Polygon(SQUARE, holes=[SQUARE_HOLE])
    points = [[1, 1], [1, 1.2], [0.25, 1], [1.5, 1], [3, 1]]
    np.testing.assert_allclose(shape.distance(points), [0.5, 0.3, -0.25, 0, 1], atol=1e-15)
    assert not shape.contains([[1, 1]])[0]
    assert shape.contains([[0.25, 0.25]])[0]
    assert shape.volume().value == 3.0 and shape.volume().exact


@pytest.mark.parametrize(
    "outer, holes",
    [
        (SQUARE, [SQUARE_HOLE]),
        (L_SHAPE, []),
        (star(40, seed=1), [0.3 * star(12, seed=2)]),
        (star(25, seed=3), [0.2 * star(8, seed=4) + [0.8, 0], 0.2 * star(8, seed=5) - [0.8, 0]]),
    ],
)
def test_matches_scalar_reference(outer, holes):
    shape = Polygon(outer, holes)
    points = random_points(shape, 300, seed=0)
    expected = reference_distances(points, outer, holes)
    np.testing.assert_allclose(shape.distance(points), expected, atol=1e-12)


def test_l_shape_concave_corner():
    shape = Polygon(L_SHAPE)
    # The notch square (1..2, 1..2) is outside, its points nearest to a notch edge; inside, near
    # the re-entrant corner, the nearest boundary point is the corner itself.
    points = [[1.6, 1.5], [1.2, 1.9], [0.9, 0.9], [1.1, 1.05]]
    expected = [0.5, 0.2, -math.sqrt(0.02), 0.05]
    np.testing.assert_allclose(shape.distance(points), expected, atol=1e-15)
    np.testing.assert_allclose(
        shape.nearest_boundary_point([[1.6, 1.5], [0.9, 0.9]]), [[1.6, 1.0], [1.0, 1.0]], atol=1e-15
    )


def test_orientation_and_closing_vertex_do_not_matter():
    points = random_points(Polygon(SQUARE), 200, seed=1)
    base = Polygon(SQUARE, holes=[SQUARE_HOLE]).distance_and_gradient(points)
    outer_cw = SQUARE[::-1]
    hole_closed = SQUARE_HOLE + SQUARE_HOLE[:1]
    variants = [
        Polygon(outer_cw, holes=[SQUARE_HOLE]),
        Polygon(SQUARE + SQUARE[:1], holes=[SQUARE_HOLE[::-1]]),
        Polygon(np.roll(outer_cw, 2, axis=0), holes=[hole_closed]),
    ]
    for shape in variants:
        distance, gradient = shape.distance_and_gradient(points)
        np.testing.assert_allclose(distance, base[0], atol=1e-15)
        np.testing.assert_allclose(gradient, base[1], atol=1e-12)
        assert len(shape.outer) == 4 and len(shape.holes[0]) == 4


def test_vertices_are_on_the_boundary():
    outer = star(30, seed=7)
    shape = Polygon(outer)
    np.testing.assert_allclose(shape.distance(outer), 0, atol=1e-15)


# ---------------------------------------------------------------------- oracle rules
def test_one_lipschitz_on_random_pairs():
    shape = Polygon(star(50, seed=8), holes=[0.4 * star(10, seed=9)])
    rng = np.random.default_rng(2)
    x = random_points(shape, 4000, seed=3)
    # Half independent pairs, half close pairs (which probe the local slope).
    close = x[2000:] + 0.01 * rng.standard_normal((2000, 2))
    y = np.concatenate([random_points(shape, 2000, seed=4), close])
    change = np.abs(shape.distance(x) - shape.distance(y))
    assert np.all(change <= np.linalg.norm(x - y, axis=1) * (1 + 1e-9) + 1e-14)


def test_gradient_matches_finite_differences_away_from_medial_axis():
    outer, holes = star(30, seed=10), [0.3 * star(9, seed=11)]
    shape = Polygon(outer, holes)
    points = random_points(shape, 400, seed=5)
    # Keep points with a unique nearest boundary point, by a margin: every edge nearly as close
    # as the nearest one must reach it at the same point (a shared vertex).
    keep = []
    for p in points:
        signed, per_edge = reference(tuple(p), outer, holes)
        nearest = min(per_edge)[1]
        close = [q for d, q in per_edge if d < abs(signed) + 1e-2]
        keep.append(abs(signed) > 1e-3 and all(math.dist(q, nearest) < 1e-9 for q in close))
    points = points[np.array(keep)]
    assert len(points) > 200

    step = 1e-6
    fd = np.column_stack([
        (shape.distance(points + step * e) - shape.distance(points - step * e)) / (2 * step)
        for e in np.eye(2)
    ])
    gradient = shape.gradient(points)
    np.testing.assert_allclose(gradient, fd, atol=1e-6)
    np.testing.assert_allclose(np.linalg.norm(gradient, axis=1), 1, atol=1e-12)


def test_nearest_point_is_on_an_edge_at_the_distance():
    outer, holes = L_SHAPE, [[[0.2, 0.2], [0.6, 0.2], [0.4, 0.5]]]
    shape = Polygon(outer, holes)
    points = random_points(shape, 300, seed=6)
    nearest = shape.nearest_boundary_point(points)
    on_boundary = np.abs(reference_distances(nearest, outer, holes))
    assert on_boundary.max() < 1e-12
    np.testing.assert_allclose(
        np.linalg.norm(points - nearest, axis=1), np.abs(shape.distance(points)), atol=1e-12
    )


def test_gradient_on_the_boundary_is_the_outward_normal():
    shape = Polygon(SQUARE, holes=[SQUARE_HOLE])
    points = [[1, 0], [2, 1], [1, 2], [0, 1], [1, 0.5], [0.5, 1]]
    expected = [[0, -1], [1, 0], [0, 1], [-1, 0], [0, 1], [1, 0]]
    np.testing.assert_allclose(shape.gradient(points), expected, atol=1e-15)
    # Inside, the gradient points towards the nearest boundary point.
    np.testing.assert_allclose(shape.gradient([[0.2, 1.0]]), [[-1, 0]], atol=1e-15)


@pytest.mark.parametrize(
    "outer, holes", [(L_SHAPE, []), (SQUARE, [SQUARE_HOLE]), (star(20, seed=12), [])]
)
def test_area_exact_vs_monte_carlo(outer, holes):
    shape = Polygon(outer, holes)
    estimate = monte_carlo_volume(shape, 200_000, seed=1)
    assert abs(estimate.value - shape.volume().value) < 5 * estimate.error


def test_regular_polygon():
    hexagon = Polygon.regular(6, radius=2.0, center=(1, -1))
    np.testing.assert_allclose(hexagon.distance([[1, -1]]), [-2 * math.cos(math.pi / 6)])
    np.testing.assert_allclose(hexagon.volume().value, 1.5 * math.sqrt(3) * 4)
    np.testing.assert_allclose(hexagon.bounds[:, 0], [-1, 3])
    with pytest.raises(ShapeError, match="n_sides"):
        Polygon.regular(2)
    with pytest.raises(ShapeError, match="radius"):
        Polygon.regular(5, radius=0)


def test_many_vertices_bounded_memory():
    n_sides, n_points = 2000, 10_000
    shape = Polygon.regular(n_sides, radius=1.0)
    points = random_points(shape, n_points, seed=7, margin=0.2)
    tracemalloc.start()
    try:
        distance, gradient = shape.distance_and_gradient(points)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    # Unchunked, each (points, edges) temporary alone would take 8 * 2e7 bytes = 160 MB.
    assert peak < 80e6
    # The regular polygon lies between its incircle and its circumcircle.
    radius = np.linalg.norm(points, axis=1)
    apothem = math.cos(math.pi / n_sides)
    assert np.all(distance >= radius - 1 - 1e-12) and np.all(distance <= radius - apothem + 1e-12)
    np.testing.assert_allclose(np.linalg.norm(gradient, axis=1), 1, atol=1e-12)


def test_chunking_does_not_change_results():
    shape = Polygon(star(40, seed=13), holes=[0.3 * star(7, seed=14)])
    points = random_points(shape, 500, seed=8)
    whole = shape.distance_and_gradient(points)
    shape.chunk_pairs = 100  # two points per chunk
    chunked = shape.distance_and_gradient(points)
    np.testing.assert_array_equal(whole[0], chunked[0])
    np.testing.assert_array_equal(whole[1], chunked[1])


def test_repr_counts_vertices():
    assert repr(Polygon(SQUARE)) == "Polygon(4 vertices)"
    assert repr(Polygon(SQUARE, holes=[SQUARE_HOLE, [[0.2, 0.2], [0.4, 0.2], [0.3, 0.4]]])) == (
        "Polygon(4 vertices, 2 holes of 4, 3 vertices)"
    )


# ---------------------------------------------------------------------- bad input
@pytest.mark.parametrize("scale", [1e-9, 1.0, 1e9])
def test_the_crossing_check_is_scale_free(scale):
    # manifold3d, which computes the even-odd area, rounds coordinates at a fixed precision.
    polygon = Polygon(np.array(SQUARE) * scale + 3 * scale, [np.array(SQUARE_HOLE) * scale + 3 * scale])
    assert polygon.volume().value == pytest.approx(3.0 * scale**2, rel=1e-12)
    with pytest.raises(ShapeError, match="cross themselves"):
        Polygon(np.array([[0, 0], [2, 2], [2, 0], [0, 1]]) * scale)
    # A simple sliver is not refused for manifold3d's rounding of its thin side.
    for thickness in (1e-3, 1e-7):
        sliver = Polygon(np.array([[0, 0], [1, 0], [1, thickness], [0, thickness]]) * scale)
        assert sliver.volume().value == pytest.approx(thickness * scale**2, rel=1e-6)


@pytest.mark.parametrize(
    "outer, holes, message",
    [
        ([[0, 0], [1, 0]], (), "at least 3"),
        ([[0, 0], [1, 0], [0, 0]], (), "at least 3"),
        ([[0, 0], [1, 0], [1, np.nan]], (), "non-finite"),
        ([[0, 0], [1, 0], [np.inf, 1]], (), "non-finite"),
        ([[0, 0], [1, 1], [2, 2]], (), "zero area"),
        # A bow-tie: its loops' signed areas cancel, but its vertices are not on one line.
        ([[0, 0], [1, 1], [1, 0], [0, 1]], (), "the outer ring crosses itself.*bow-tie"),
        ([[0, 0, 0], [1, 0, 0], [0, 1, 0]], (), r"\(m, 2\)"),
        ([0, 1, 2, 3], (), r"\(m, 2\)"),
        ([["a", "b"], [1, 0], [0, 1]], (), r"\(m, 2\)"),
        (SQUARE, [[[3, 3], [4, 3], [4, 4]]], "hole 0 is not inside"),
        (SQUARE, [[[1, 1], [3, 1], [1, 1.5]]], "hole 0 is not inside"),
        (SQUARE, [[[0.5, 0.5], [1, 0.5]]], "hole 0 needs at least 3"),
        (SQUARE, [[[0.5, 0.5], [1, 1], [1.5, 1.5]]], "hole 0 has zero area"),
        (SQUARE, np.array(SQUARE_HOLE), r"holes=\[hole\]"),
        (SQUARE, [[0.5, 0.5], [1.5, 0.5], [1, 1]], r"holes=\[hole\]"),
        # A self-crossing ring: its signed area (1) is not the region's (5/3, even-odd), which
        # packed to a fill of 1.5 before.
        ([[0, 0], [2, 2], [2, 0], [0, 1]], (), "cross themselves.*1.66667"),
        # Two holes that overlap: the even-odd region is not the square less both holes.
        (SQUARE, [[[0.2, 0.2], [1, 0.2], [1, 1], [0.2, 1]], [[0.6, 0.6], [1.4, 0.6], [1.4, 1.4], [0.6, 1.4]]],
         "cross themselves or each other"),
    ],
)
def test_bad_input_raises_shape_error(outer, holes, message):
    with pytest.raises(ShapeError, match=message):
        Polygon(outer, holes)
