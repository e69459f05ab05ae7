"""Tests of ndpack.shapes.plugin: user functions as distance oracles."""

import numpy as np
import pytest

import ndpack as nd

from ndpack.errors import BoundsError, DimensionError, OracleError, ParameterError, ShapeError
from ndpack.oracle import Oracle
from ndpack.shapes.plugin import Function, plugin

SQUARE_BOUNDS = [[-1.5, -1.5], [1.5, 1.5]]


def disc(p):
    """The unit disc."""
    return np.linalg.norm(p, axis=1) - 1.0


def random_points(n, dim=2, seed=0):
    return np.random.default_rng(seed).uniform(-1.5, 1.5, (n, dim))


def test_disc_plugin_agrees_with_exact_distance():
    shape = Function(disc, dim=2, bounds=SQUARE_BOUNDS, exact_inside=True, exact_outside=True)
    points = random_points(500)
    np.testing.assert_array_equal(shape.distance(points), np.linalg.norm(points, axis=1) - 1)
    assert isinstance(shape, Oracle)
    assert shape.exact and shape.exact_outside and not shape.convex
    np.testing.assert_array_equal(shape.bounds, SQUARE_BOUNDS)
    assert shape.contains([[0, 0], [2, 0]]).tolist() == [True, False]
    # Finite-difference gradient (no gradient given): radial, and nearest points on the circle.
    gradient = shape.gradient(points)
    radial = points / np.linalg.norm(points, axis=1)[:, None]
    np.testing.assert_allclose(gradient, radial, atol=1e-6)
    nearest = shape.nearest_boundary_point(points)
    np.testing.assert_allclose(np.linalg.norm(nearest, axis=1), 1, atol=1e-6)
    estimate = shape.volume(samples=100_000)
    assert abs(estimate.value - np.pi) < 5 * estimate.error


def test_flags_default_to_lower_bound():
    shape = Function(disc, dim=2, bounds=SQUARE_BOUNDS)
    assert not shape.exact_inside and not shape.exact_outside


def test_function_does_not_see_callers_array():
    def in_place(p):
        p *= 2  # works on its own copy
        return np.linalg.norm(p, axis=1) / 2 - 1

    points = random_points(10)
    before = points.copy()
    Function(in_place, 2, SQUARE_BOUNDS).distance(points)
    np.testing.assert_array_equal(points, before)


def test_nan_raises_oracle_error_naming_the_point():
    def holey(p):
        d = disc(p)
        d[p[:, 0] > 1.0] = np.nan
        return d

    shape = Function(holey, 2, SQUARE_BOUNDS)
    with pytest.raises(OracleError) as info:
        shape.distance([[0, 0], [1.25, 0.5]])
    message = str(info.value)
    assert "'holey'" in message
    assert "NaN or infinity for 1 of 2 points" in message
    assert "[1.25, 0.5]" in message


def test_infinite_value_raises():
    shape = Function(lambda p: np.full(len(p), -np.inf), 2, SQUARE_BOUNDS)
    with pytest.raises(OracleError, match="returned NaN or infinity for 3 of 3 points"):
        shape.distance(np.zeros((3, 2)))


@pytest.mark.parametrize(
    "fn, shape_text",
    [
        (lambda p: disc(p)[:, None], r"\(5, 1\)"),
        (lambda p: disc(p)[:3], r"\(3,\)"),
        (lambda p: 0.0, r"\(\) .*single number.*vectorised"),
        (lambda p: p, r"\(5, 2\)"),
    ],
)
def test_wrong_output_shape_raises(fn, shape_text):
    shape = Function(fn, 2, SQUARE_BOUNDS)
    with pytest.raises(OracleError, match=shape_text) as info:
        shape.distance(random_points(5))
    assert "return one distance per point, shape (n,)" in str(info.value)
    assert "expected (5,)" in str(info.value)


def test_non_numeric_output_raises():
    shape = Function(lambda p: ["inside"] * len(p), 2, SQUARE_BOUNDS)
    with pytest.raises(OracleError, match="not an array of numbers"):
        shape.distance(random_points(5))


def test_user_exceptions_propagate_unchanged():
    class Boom(Exception):
        pass

    def broken(p):
        raise Boom("user bug")

    with pytest.raises(Boom, match="user bug"):
        Function(broken, 2, SQUARE_BOUNDS).distance(random_points(3))


@pytest.mark.parametrize(
    "dim, bounds, error, message",
    [
        (2, [[-1, -1], [1]], BoundsError, "bounds must"),
        (2, [[-1, -1, -1], [1, 1, 1]], BoundsError, r"shape \(2, 2\)"),
        (2, [-1, 1], BoundsError, r"shape \(2, 2\)"),
        (2, [[-1, -1], [1, -1]], BoundsError, "lower < upper"),
        (2, [[1, -1], [-1, 1]], BoundsError, "lower < upper"),
        (2, [[-np.inf, -1], [1, 1]], BoundsError, "finite"),
        (2, [[np.nan, -1], [1, 1]], BoundsError, "finite"),
        (0, [[], []], DimensionError, "integer >= 1"),
        (2.5, SQUARE_BOUNDS, DimensionError, "integer >= 1"),
        (True, [[-1], [1]], DimensionError, "integer >= 1"),
        ("2", SQUARE_BOUNDS, DimensionError, "integer >= 1"),
    ],
)
def test_bad_construction_raises(dim, bounds, error, message):
    with pytest.raises(error, match=message):
        Function(disc, dim, bounds)
    assert issubclass(error, ShapeError)


def test_not_callable_raises_type_error_with_hint():
    with pytest.raises(TypeError, match="pass the function itself"):
        Function(disc(np.zeros((1, 2))), 2, SQUARE_BOUNDS)
    with pytest.raises(TypeError, match="gradient must be a callable"):
        Function(disc, 2, SQUARE_BOUNDS, gradient=np.zeros(2))


def test_check_lipschitz():
    exact = Function(disc, 2, SQUARE_BOUNDS)
    ratio = exact.check_lipschitz()
    assert 0.99 < ratio <= 1 + 1e-9

    doubled = Function(lambda p: 2 * disc(p), 2, SQUARE_BOUNDS, name="doubled")
    with pytest.raises(OracleError) as info:
        doubled.check_lipschitz()
    message = str(info.value)
    assert "'doubled' is not a conservative distance" in message
    assert "Lipschitz constant at least 1.99" in message or "constant at least 2" in message
    assert "divide it by" in message

    # A lower bound (here half the distance) is fine.
    assert Function(lambda p: disc(p) / 2, 2, SQUARE_BOUNDS).check_lipschitz() <= 0.5 + 1e-9
    with pytest.raises(ParameterError):
        exact.check_lipschitz(samples=0)


def test_pack_checks_the_slope_of_every_plugin_in_the_tree_once():
    calls = []

    def counted(p):
        calls.append(len(p))
        return disc(p)

    steep = Function(lambda p: 2 * disc(p), 2, SQUARE_BOUNDS, name="steep")
    with pytest.raises(OracleError, match="'steep' is not a conservative distance"):
        nd.pack(nd.Box([-2, -2], [2, 2]) - steep.translate([0.5, 0]), n=5, backend="numpy")
    fine = Function(counted, 2, SQUARE_BOUNDS, name="fine")
    shape = fine | nd.Ball([0.2, 0.0], 0.3)
    nd.pack(shape, n=5, backend="numpy", grid=8)
    assert 4000 in calls  # the check: 2,000 pairs in one call
    calls.clear()
    nd.pack(shape, n=5, backend="numpy", grid=8)
    assert 4000 not in calls  # not again for the same plug-in


def test_user_gradient_is_used_and_normalised():
    calls = []

    def radial(p):
        calls.append(len(p))
        return 3.0 * p  # not unit length: normalised by the oracle

    shape = Function(disc, 2, SQUARE_BOUNDS, gradient=radial, exact_inside=True)
    points = random_points(50)
    distance, gradient = shape.distance_and_gradient(points)
    assert calls == [50]  # one call, not 2 * dim finite-difference evaluations
    unit = points / np.linalg.norm(points, axis=1)[:, None]
    np.testing.assert_allclose(gradient, unit, atol=1e-15)
    np.testing.assert_array_equal(distance, disc(points))


def test_bad_user_gradient_raises():
    wrong_shape = Function(disc, 2, SQUARE_BOUNDS, gradient=lambda p: p[:, 0])
    with pytest.raises(OracleError, match=r"shape \(n, 2\)"):
        wrong_shape.gradient(random_points(4))

    def nan_gradient(p):
        g = p.copy()
        g[0, 1] = np.nan
        return g

    with pytest.raises(OracleError, match="gradient function of 'disc' returned NaN or infinity"):
        Function(disc, 2, SQUARE_BOUNDS, gradient=nan_gradient).gradient(random_points(4))


def test_decorator():
    @plugin(dim=2, bounds=[[-1, -1], [1, 1]], exact_inside=True)
    def unit_disc(p):
        """Docstring kept."""
        return np.linalg.norm(p, axis=1) - 1.0

    assert isinstance(unit_disc, Function)
    assert unit_disc.exact_inside and not unit_disc.exact_outside
    assert repr(unit_disc) == "Function('unit_disc', dim=2)"
    assert unit_disc.__doc__ == "Docstring kept."
    np.testing.assert_array_equal(unit_disc([[0, 0], [0, 2]]), [-1, 1])  # still callable
    np.testing.assert_array_equal(unit_disc.distance([0.0, 0.5]), [-0.5])  # a single point


def test_decorator_without_arguments_explains():
    with pytest.raises(TypeError, match=r"@ndpack.plugin\(dim=..., bounds=...\)"):

        @plugin
        def unit_disc(p):
            return disc(p)


def test_repr_and_name():
    assert repr(Function(disc, 2, SQUARE_BOUNDS)) == "Function('disc', dim=2)"
    assert repr(Function(lambda p: disc(p), 2, SQUARE_BOUNDS)) == "Function('<lambda>', dim=2)"
    assert repr(Function(disc, 2, SQUARE_BOUNDS, name="my disc")) == "Function('my disc', dim=2)"


def test_four_dimensional_plugin():
    @plugin(dim=4, bounds=[[-2] * 4, [2] * 4], exact_inside=True, exact_outside=True)
    def hyperball(p):
        return np.linalg.norm(p - 0.5, axis=1) - 1.5

    points = np.random.default_rng(1).uniform(-2, 2, (300, 4))
    expected = np.linalg.norm(points - 0.5, axis=1) - 1.5
    np.testing.assert_allclose(hyperball.distance(points), expected)
    nearest = hyperball.nearest_boundary_point(points)
    np.testing.assert_allclose(np.linalg.norm(nearest - 0.5, axis=1), 1.5, atol=1e-5)
    assert hyperball.check_lipschitz(samples=500) <= 1 + 1e-6
    with pytest.raises(DimensionError):
        hyperball.distance(np.zeros((3, 2)))


def test_decorator_without_bounds_explains():
    with pytest.raises(BoundsError, match=r"plugin needs bounds: a \(2, 3\) box"):
        plugin(dim=3)
