"""CSG nodes: distances against exact references, exactness flags, gradients, bounds, errors."""

import numpy as np
import pytest

import ndpack as nd
from ndpack.oracle import monte_carlo_volume

rng = np.random.default_rng(0)


def polygon_of_boxes(*corners):
    """Exact 2D reference: the rectangle outline through the given corner list."""
    return nd.Polygon(np.array(corners, dtype=float))


def sample(lower, upper, count=4000, dim=2):
    return lower + (upper - lower) * rng.random((count, dim))


A = nd.Box([0, 0], [2, 1])
B = nd.Box([1, 0], [2, 2])
L_SHAPE = polygon_of_boxes([0, 0], [2, 0], [2, 2], [1, 2], [1, 1], [0, 1])


def test_union_is_exact_outside_and_a_bound_inside():
    union = A | B
    assert (union.exact_inside, union.exact_outside) == (False, True)
    points = sample(-1, 3)
    got, want = union.distance(points), L_SHAPE.distance(points)
    outside = want > 0
    np.testing.assert_allclose(got[outside], want[outside], atol=1e-12)
    assert np.all(np.sign(got) == np.sign(want))
    assert np.all(np.abs(got[~outside]) <= np.abs(want[~outside]) + 1e-12)
    # ... and strictly smaller somewhere: near the inner corner (1, 1) the union's min is loose.
    assert np.any(np.abs(got[~outside]) < np.abs(want[~outside]) - 1e-3)


def test_intersection_is_exact_inside():
    both = A & B
    square = nd.Box([1, 0], [2, 1])
    assert (both.exact_inside, both.exact_outside, both.convex) == (True, False, True)
    points = sample(-1, 3)
    got, want = both.distance(points), square.distance(points)
    inside = want < 0
    np.testing.assert_allclose(got[inside], want[inside], atol=1e-12)
    assert np.all(got[~inside] <= want[~inside] + 1e-12) and np.all(got[~inside] >= 0)


def test_difference_is_exact_inside_when_the_cut_is_exact_outside():
    cut = nd.Box([0, 0], [2, 2]) - nd.Box([1, 1], [3, 3])
    assert cut.exact_inside and not cut.exact_outside
    notched = polygon_of_boxes([0, 0], [2, 0], [2, 1], [1, 1], [1, 2], [0, 2])
    points = sample(-1, 3)
    want = notched.distance(points)
    inside = want < 0
    np.testing.assert_allclose(cut.distance(points)[inside], want[inside], atol=1e-12)
    assert np.all(np.sign(cut.distance(points)) == np.sign(want))
    loose = nd.Box([0, 0], [2, 2]) - (nd.Box([1, 1], [3, 3]) & nd.Ball([2, 2], 1.2))
    assert not loose.exact_inside


def test_complement_swaps_sides():
    ball = nd.Ball([0, 0, 0], 1.0)
    outside = ~ball
    points = sample(-2, 2, dim=3)
    np.testing.assert_array_equal(outside.distance(points), -ball.distance(points))
    assert not outside.is_bounded and outside.volume().value == np.inf
    assert (~(A & B)).exact_outside and not (~(A & B)).exact_inside
    assert ~outside is ball
    cube_minus_ball = nd.Box([-2] * 3, [2] * 3) & ~ball
    np.testing.assert_allclose(
        cube_minus_ball.distance(points), (nd.Box([-2] * 3, [2] * 3) - ball).distance(points)
    )


@pytest.mark.parametrize("dim", [2, 3, 5, 8])
def test_rigid_motions_and_scaling_match_moved_primitives(dim):
    center = rng.normal(size=dim)
    ball = nd.Ball(np.zeros(dim), 1.0)
    points = rng.normal(size=(500, dim)) * 2
    np.testing.assert_allclose(ball.translate(center).distance(points), nd.Ball(center, 1.0).distance(points))
    np.testing.assert_allclose(
        ball.scale_by(2.5, center=center).distance(points), nd.Ball(center - 2.5 * center, 2.5).distance(points)
    )
    # A rotated box against the exact distance computed in the box's own frame.
    rotation = nd.rotation(dim, 0.7, (0, dim - 1)) @ nd.rotation(dim, -0.4, (1, 0))
    box = nd.Box(-np.arange(1, dim + 1) / dim, np.ones(dim))
    turned = box.rotate(rotation, center=center)
    np.testing.assert_allclose(turned.distance(points), box.distance((points - center) @ rotation + center), atol=1e-12)
    assert turned.exact_inside and turned.exact_outside and turned.convex
    # Bounds enclose: the rotated corners all lie inside them.
    corners = np.array(np.meshgrid(*zip(box.bounds[0], box.bounds[1]))).reshape(dim, -1).T
    moved = (corners - center) @ rotation.T + center
    assert np.all(moved >= turned.bounds[0] - 1e-12) and np.all(moved <= turned.bounds[1] + 1e-12)
    assert turned.volume().value == pytest.approx(box.volume().value)
    assert ball.scale_by(2.0).volume().value == pytest.approx(2.0**dim * ball.volume().value)


def test_offsets_match_rounded_and_shrunk_boxes():
    box = nd.Box([0, 0, 0], [2, 1, 1])
    points = sample(-1, 3, dim=3)
    dilated = box.offset(0.25)
    np.testing.assert_allclose(
        dilated.distance(points), nd.RoundedBox([-0.25] * 3, [2.25, 1.25, 1.25], 0.25).distance(points), atol=1e-12
    )
    assert dilated.exact_inside and dilated.exact_outside  # a convex child, exact on both sides
    eroded = box.offset(-0.2)
    inner = nd.Box([0.2] * 3, [1.8, 0.8, 0.8])
    inside = inner.distance(points) < 0
    np.testing.assert_allclose(eroded.distance(points)[inside], inner.distance(points)[inside], atol=1e-12)
    assert eroded.exact_inside and not eroded.exact_outside
    assert not (A | B).offset(0.1).exact_inside  # not convex: only a bound inside


def test_shell_of_a_ball_is_a_spherical_layer():
    layer = nd.Ball([0, 0, 0], 1.0).shell(0.2)
    points = sample(-1.5, 1.5, dim=3)
    radius = np.linalg.norm(points, axis=1)
    np.testing.assert_allclose(layer.distance(points), np.abs(radius - 1.0) - 0.1, atol=1e-12)
    assert not layer.exact_inside
    assert np.all(layer.bounds[1] >= 1.1)


def test_smooth_union_is_a_conservative_fillet():
    a, b = nd.Ball([-0.5, 0], 0.6), nd.Ball([0.5, 0], 0.6)
    blend = a.smooth_union(b, 0.4)
    points = sample(-1.5, 1.5)
    da, db = a.distance(points), b.distance(points)
    got = blend.distance(points)
    assert np.all(got <= np.minimum(da, db) + 1e-12)
    far = np.abs(da - db) >= 0.4
    np.testing.assert_allclose(got[far], np.minimum(da, db)[far])
    assert not blend.exact_inside and not blend.exact_outside
    # 1-Lipschitz on random pairs, hence a lower bound of the distance to its own boundary.
    other = points + rng.normal(scale=0.05, size=points.shape)
    ratio = np.abs(got - blend.distance(other)) / np.linalg.norm(points - other, axis=1)
    assert ratio.max() <= 1 + 1e-9
    assert blend.bounds[0, 0] <= -1.1 - 0.1 and blend.bounds[1, 0] >= 1.1 + 0.1


def test_gradients_match_finite_differences_away_from_kinks():
    shape = (
        (nd.Box([-1, -1, -1], [1, 1, 1]) - nd.Ball([1, 1, 1], 0.8)) | nd.Capsule([0, 0, 0], [2, 0, 0], 0.3)
    ).rotate(
        nd.rotation(3, 0.5, (0, 2))
    ).translate([0.1, 0.2, 0.3])
    points = sample(-1.5, 1.5, count=2000, dim=3)
    distance, gradient = shape.distance_and_gradient(points)
    step = 1e-6
    numeric = np.stack(
        [(shape.distance(points + step * e) - shape.distance(points - step * e)) / (2 * step) for e in np.eye(3)],
        axis=1,
    )
    smooth = np.abs(np.linalg.norm(numeric, axis=1) - 1) < 1e-6  # off the kinks, |grad| is 1
    assert smooth.mean() > 0.8
    np.testing.assert_allclose(gradient[smooth], numeric[smooth], atol=1e-5)
    np.testing.assert_allclose(np.linalg.norm(gradient, axis=1), 1.0)


def test_monte_carlo_volume_of_csg():
    union = A | B
    volume = union.volume(samples=200_000, seed=3)
    assert not volume.exact
    assert abs(volume.value - 3.0) < 5 * volume.error
    assert union.volume(samples=200_000, seed=3) is volume  # cached
    exact = monte_carlo_volume(nd.Box([0, 0], [1, 1]), 100_000, 0)
    assert abs(exact.value - 1.0) < 5 * exact.error


def test_operators_chain_and_flatten():
    c = nd.Ball([3, 3], 0.5)
    union = A | B | c
    assert isinstance(union, nd.Union) and len(union.children) == 3
    assert isinstance(A & B & c.translate([-2, -2.5]), nd.Intersection)
    assert isinstance(A - c, nd.Difference) and isinstance(~A, nd.Complement)
    assert A.union(B, c).children == union.children
    assert "Union" in repr(union) and "Ball" in repr(union)


def test_bad_csg_is_refused():
    with pytest.raises(nd.DimensionError, match="different dimensions"):
        A & nd.Ball([0, 0, 0], 1)
    for apart in (A & nd.Box([5, 5], [6, 6]), nd.Intersection(A, nd.Box([5, 5], [6, 6]))):
        with pytest.raises(nd.ShapeError, match="nothing to pack: the intersection .* do not overlap"):
            nd.pack(apart, 5)  # parts that cannot meet: an empty set, refused where it is packed
    with pytest.raises(nd.ShapeError, match="not orthogonal"):
        A.rotate([[2, 0], [0, 1]])
    with pytest.raises(nd.ShapeError, match="positive"):
        A.scale_by(-1)
    with pytest.raises(nd.ShapeError, match="positive"):
        A.shell(0)
    with pytest.raises(nd.ShapeError, match="at least two"):
        nd.Union(A)
    with pytest.raises(TypeError, match="ndpack.Function"):
        A | (lambda p: p)


def test_non_finite_points_are_refused():
    with pytest.raises(nd.ParameterError, match="points must be finite; row 1"):
        A.distance([[0.0, 0.0], [np.nan, 1.0]])
