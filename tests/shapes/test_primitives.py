"""Tests of ndpack.shapes.primitives against independent references.

Every reference distance here is computed another way than the shape does it: brute force over
box faces, golden-section search along segments and circles, a rotated frame for cylinders,
Eberly's bisection for ellipsoids, vertex enumeration by Qhull for polytopes, barycentric
coordinates for simplices. In 2D and 3D a dense sample of the boundary checks the references.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from functools import cache

import numpy as np
import pytest
from ndpack.errors import DimensionError, ShapeError
from ndpack.oracle import ball_volume, check_packable, monte_carlo_volume
from ndpack.shapes.primitives import (
    Ball,
    Box,
    Capsule,
    ConvexPolytope,
    Cylinder,
    Ellipsoid,
    HalfSpace,
    RoundedBox,
    Simplex,
    Slab,
    Torus,
)
from scipy.spatial import HalfspaceIntersection, cKDTree

DIMS = list(range(2, 9))
ND_KINDS = [
    "ball",
    "box",
    "rounded_box",
    "capsule",
    "cylinder",
    "ellipsoid",
    "polytope",
    "simplex",
    "halfspace",
    "slab",
]
CASES = [(kind, dim) for kind in ND_KINDS for dim in DIMS] + [("torus", 3)]
CASE_IDS = [f"{kind}-{dim}d" for kind, dim in CASES]
TOL = 1e-9


# ---------------------------------------------------------------------- independent references
def unit_vectors(rng, n, dim):
    v = rng.normal(size=(n, dim))
    return v / np.linalg.norm(v, axis=1, keepdims=True)


def golden_min(fun, lo, hi, iterations=90):
    """Vectorised golden-section search of unimodal ``fun`` on [lo, hi]; returns the minimum value."""
    ratio = (math.sqrt(5) - 1) / 2
    lo, hi = np.array(lo, dtype=float), np.array(hi, dtype=float)
    for _ in range(iterations):
        left = hi - ratio * (hi - lo)
        right = lo + ratio * (hi - lo)
        go_left = fun(left) < fun(right)
        hi = np.where(go_left, right, hi)
        lo = np.where(go_left, lo, left)
    return fun((lo + hi) / 2)


def box_reference(x, lo, hi):
    """Signed distance to [lo, hi] by brute force over its 2d faces."""
    inside = np.all((x > lo) & (x < hi), axis=1)
    best = np.full(len(x), np.inf)
    for axis in range(x.shape[1]):
        for value in (lo[axis], hi[axis]):
            on_face = np.clip(x, lo, hi)
            on_face[:, axis] = value
            best = np.minimum(best, np.linalg.norm(x - on_face, axis=1))
    return np.where(inside, -best, best)


def segment_distance(x, a, b):
    """Distance to the segment ab by golden-section search over its parameter (convex in t)."""
    return golden_min(
        lambda t: np.linalg.norm(x - a - t[:, None] * (b - a), axis=1),
        np.zeros(len(x)),
        np.ones(len(x)),
    )


def cylinder_reference(x, a, b, r):
    """Signed distance to a cylinder in a rotated frame whose first axis is the cylinder's."""
    axis = (b - a) / np.linalg.norm(b - a)
    basis, _ = np.linalg.qr(np.column_stack([axis, np.eye(len(a))[:, :-1]]))
    y = (x - (a + b) / 2) @ basis
    s, z = y[:, 0], y[:, 1:]
    half = np.linalg.norm(b - a) / 2
    zn = np.linalg.norm(z, axis=1)
    inside = (np.abs(s) < half) & (zn < r)
    # Projection onto a product of convex sets is the product of the projections.
    ds = np.abs(s) - np.clip(np.abs(s), 0, half)
    dz = np.maximum(zn - r, 0)
    outside = np.hypot(ds, dz)
    depth = np.minimum(half - np.abs(s), r - zn)
    return np.where(inside, -depth, outside)


def ellipsoid_reference(x, c, radii):
    """True signed distance to an axis-aligned ellipsoid (Eberly's bisection, any dimension)."""
    y = np.abs(x - c)
    # The nearest point is a^2 y / (t + a^2) with t the root of sum (a y / (t + a^2))^2 = 1 in
    # (-min a^2, inf). Bisect on log(s), s = t + min a^2, to resolve roots near -min a^2.
    a2 = radii**2
    shift = a2 - a2.min()
    lo = np.full(len(x), np.log(1e-30 * a2.min()))
    hi = np.log(np.linalg.norm(radii * y, axis=1) + a2.min())
    for _ in range(200):
        s = np.exp((lo + hi) / 2)
        f = (((radii * y) / (s[:, None] + shift)) ** 2).sum(axis=1) - 1
        lo, hi = np.where(f > 0, (lo + hi) / 2, lo), np.where(f > 0, hi, (lo + hi) / 2)
    s = np.exp((lo + hi) / 2)
    nearest = a2 * y / (s[:, None] + shift)
    distance = np.linalg.norm(y - nearest, axis=1)
    inside = ((y / radii) ** 2).sum(axis=1) < 1
    return np.where(inside, -distance, distance)


def torus_reference(x, c, big, small):
    """Distance to the core circle (grid + golden search over its angle) minus the tube radius."""
    p = x - c

    def to_circle(phi):
        return np.linalg.norm(
            p - big * np.column_stack([np.cos(phi), np.sin(phi), np.zeros_like(phi)]), axis=1
        )

    grid = np.linspace(0, 2 * np.pi, 64, endpoint=False)
    best = grid[np.argmin([to_circle(np.full(len(x), g)) for g in grid], axis=0)]
    step = grid[1]
    return golden_min(to_circle, best - step, best + step) - small


def simplex_reference(x, vertices):
    """Largest signed distance to the facet hyperplanes (found by SVD), oriented away from the
    opposite vertex: the exact distance inside, a lower bound outside."""
    dim = vertices.shape[1]
    plane = []
    for i in range(dim + 1):
        facet = np.delete(vertices, i, axis=0)
        normal = np.linalg.svd(facet[1:] - facet[0])[2][-1]  # spans the null space
        normal *= -np.sign((vertices[i] - facet[0]) @ normal)
        plane.append((x - facet[0]) @ normal)
    worst = np.max(plane, axis=0)
    # Independent membership by barycentric coordinates.
    matrix = np.vstack([vertices.T, np.ones(dim + 1)])
    weights = np.linalg.solve(matrix, np.vstack([x.T, np.ones(len(x))])).T
    clear = np.abs(worst) > 1e-12
    assert np.array_equal(np.all(weights > 0, axis=1)[clear], worst[clear] < 0)
    return worst


# ---------------------------------------------------------------------- the cases
@dataclass
class Case:
    shape: object
    reference: Callable  # signed distance, zero exactly on the boundary
    interior: np.ndarray  # a point well inside
    box: np.ndarray  # (2, d) region to sample test points in
    support: Callable | None = None  # h(u) for convex bounded shapes: tight bounds are +-h(+-e_i)
    boundary: Callable | None = None  # (rng, n) -> points on the boundary (2D / 3D)
    exact_outside_ref: bool = True  # False: outside, the reference is only a lower bound


def _grow(bounds, factor=0.3):
    extent = bounds[1] - bounds[0]
    return np.array([bounds[0] - factor * extent, bounds[1] + factor * extent])


@cache
def make_case(kind, dim):
    rng = np.random.default_rng([dim, (ND_KINDS + ["torus"]).index(kind)])
    if kind == "ball":
        c, r = rng.uniform(-1, 1, dim), rng.uniform(0.5, 2)
        return Case(
            Ball(c, r),
            lambda x: np.linalg.norm(x - c, axis=1) - r,
            c,
            _grow(np.array([c - r, c + r])),
            support=lambda u: u @ c + r * np.linalg.norm(u, axis=1),
            boundary=lambda g, n: c + r * unit_vectors(g, n, dim),
        )
    if kind in ("box", "rounded_box"):
        lo = rng.uniform(-2, -0.5, dim)
        hi = lo + rng.uniform(0.5, 3, dim)
        r = rng.uniform(0.1, 0.45) * (hi - lo).min() if kind == "rounded_box" else 0.0
        shape = RoundedBox(lo, hi, r) if r else Box(lo, hi)
        inner_lo, inner_hi = lo + r, hi - r

        def boundary(g, n):
            # Project points outside the inner box onto it, then step out by r.
            y = g.uniform(lo - 1, hi + 1, (4 * n, dim))
            q = np.clip(y, inner_lo, inner_hi)
            gap = np.linalg.norm(y - q, axis=1)
            y, q, gap = y[gap > 0], q[gap > 0], gap[gap > 0]
            return (q + r * (y - q) / gap[:, None])[:n]

        return Case(
            shape,
            # Dilating a convex set by r subtracts r from its signed distance.
            lambda x: box_reference(x, inner_lo, inner_hi) - r,
            (lo + hi) / 2,
            _grow(np.array([lo, hi])),
            support=lambda u: np.maximum(u * lo, u * hi).sum(axis=1),
            boundary=boundary,
        )
    if kind == "capsule":
        a, b = rng.normal(size=(2, dim))
        r = rng.uniform(0.3, 1)

        def boundary(g, n):
            axis = (b - a) / np.linalg.norm(b - a)
            u = unit_vectors(g, n, dim)
            across = u - (u @ axis)[:, None] * axis
            across /= np.linalg.norm(across, axis=1, keepdims=True)
            t = g.random(n)
            side = a + t[:, None] * (b - a) + r * across
            cap_a = a + r * np.where((u @ axis)[:, None] <= 0, u, -u)
            cap_b = b + r * np.where((u @ axis)[:, None] >= 0, u, -u)
            return np.vstack([side, cap_a[: n // 2], cap_b[: n // 2]])

        return Case(
            Capsule(a, b, r),
            lambda x: segment_distance(x, a, b) - r,
            (a + b) / 2,
            _grow(np.array([np.minimum(a, b) - r, np.maximum(a, b) + r])),
            support=lambda u: np.maximum(u @ a, u @ b) + r * np.linalg.norm(u, axis=1),
            boundary=boundary,
        )
    if kind == "cylinder":
        a, b = rng.normal(size=(2, dim))
        r = rng.uniform(0.3, 1)
        axis = (b - a) / np.linalg.norm(b - a)
        mid, half = (a + b) / 2, np.linalg.norm(b - a) / 2

        def support(u):
            along = u @ axis
            across = np.linalg.norm(u - along[:, None] * axis, axis=1)
            return u @ mid + half * np.abs(along) + r * across

        def boundary(g, n):
            u = unit_vectors(g, n, dim)
            across = u - (u @ axis)[:, None] * axis
            across /= np.linalg.norm(across, axis=1, keepdims=True)
            side = mid + (g.uniform(-half, half, n))[:, None] * axis + r * across
            rho = r * np.sqrt(g.random(n))[:, None]
            caps = np.where(g.random(n)[:, None] < 0.5, a, b) + rho * across
            return np.vstack([side, caps])

        return Case(
            Cylinder(a, b, r),
            lambda x: cylinder_reference(x, a, b, r),
            mid,
            _grow(np.array([np.minimum(a, b) - r, np.maximum(a, b) + r])),
            support=support,
            boundary=boundary,
        )
    if kind == "ellipsoid":
        c, radii = rng.uniform(-1, 1, dim), rng.uniform(0.3, 2, dim)
        return Case(
            Ellipsoid(c, radii),
            lambda x: ellipsoid_reference(x, c, radii),
            c,
            _grow(np.array([c - radii, c + radii])),
            support=lambda u: u @ c + np.linalg.norm(u * radii, axis=1),
            boundary=lambda g, n: c + radii * unit_vectors(g, n, dim),
        )
    if kind == "polytope":
        # Half-spaces tangent to a ball of radius s at c (none redundant), rows scaled at random.
        # Simplex-like directions (rotated at random) keep it bounded; few facets keep the
        # vertex count, and so Qhull's volume, manageable in 8D.
        c, s = rng.uniform(-0.5, 0.5, dim), rng.uniform(0.5, 1.5)
        spanning = np.vstack([np.eye(dim), -np.ones(dim) / np.sqrt(dim)])
        rotation = np.linalg.qr(rng.normal(size=(dim, dim)))[0]
        n = np.vstack([spanning @ rotation, unit_vectors(rng, 3, dim)])
        k = rng.uniform(0.5, 3, len(n))
        raw_normals, raw_offsets = k[:, None] * n, k * (s + n @ c)
        shape = ConvexPolytope(raw_normals, raw_offsets)
        vertices = HalfspaceIntersection(
            np.hstack([raw_normals, -raw_offsets[:, None]]), c
        ).intersections
        assert np.all(np.isfinite(vertices)) and len(vertices) > dim

        def reference(x):
            excess = (x @ raw_normals.T - raw_offsets) / np.linalg.norm(raw_normals, axis=1)
            return excess.max(axis=1)  # exact inside, a lower bound outside

        def boundary(g, n_points):
            # Cast rays from c: the first plane each one crosses.
            v = unit_vectors(g, n_points, dim)
            rates = v @ raw_normals.T
            room = raw_offsets - raw_normals @ c
            t = np.where(rates > 0, room / np.where(rates > 0, rates, 1), np.inf).min(axis=1)
            return c + t[:, None] * v

        return Case(
            shape,
            reference,
            c,
            _grow(np.array([vertices.min(axis=0), vertices.max(axis=0)])),
            support=lambda u: (u @ vertices.T).max(axis=1),
            boundary=boundary,
            exact_outside_ref=False,
        )
    if kind == "simplex":
        vertices = rng.normal(size=(dim + 1, dim))

        def boundary(g, n):
            # Random points of random facets (barycentric weights with one of them zero).
            w = g.exponential(size=(n, dim + 1))
            w[np.arange(n), g.integers(0, dim + 1, n)] = 0
            return (w / w.sum(axis=1, keepdims=True)) @ vertices

        return Case(
            Simplex(vertices),
            lambda x: simplex_reference(x, vertices),
            vertices.mean(axis=0),
            _grow(np.array([vertices.min(axis=0), vertices.max(axis=0)])),
            support=lambda u: (u @ vertices.T).max(axis=1),
            boundary=boundary,
            exact_outside_ref=False,
        )
    if kind == "halfspace":
        normal, offset = 3 * rng.normal(size=dim), rng.normal()
        length = np.linalg.norm(normal)
        return Case(
            HalfSpace(normal, offset),
            lambda x: (x @ normal - offset) / length,
            (offset / length - 1) * normal / length,
            np.array([np.full(dim, -3.0), np.full(dim, 3.0)]),
        )
    if kind == "slab":
        normal = 3 * rng.normal(size=dim)
        lower = rng.uniform(-1, 0)
        upper = lower + rng.uniform(0.5, 2)
        unit = normal / np.linalg.norm(normal)

        def reference(x):
            h = x @ unit
            return np.where(
                (h > lower) & (h < upper),
                -np.minimum(h - lower, upper - h),
                np.maximum(lower - h, h - upper),
            )

        return Case(
            Slab(normal, lower, upper),
            reference,
            (lower + upper) / 2 * unit,
            np.array([np.full(dim, -3.0), np.full(dim, 3.0)]),
        )
    if kind == "torus":
        c = rng.uniform(-1, 1, 3)
        big, small = rng.uniform(1.5, 2.5), rng.uniform(0.3, 1.0)

        def boundary(g, n):
            phi, theta = g.uniform(0, 2 * np.pi, (2, n))
            ring = big + small * np.cos(theta)
            return c + np.column_stack(
                [ring * np.cos(phi), ring * np.sin(phi), small * np.sin(theta)]
            )

        reach = np.array([big + small, big + small, small])
        return Case(
            Torus(c, big, small),
            lambda x: torus_reference(x, c, big, small),
            c + np.array([big, 0, 0]),
            _grow(np.array([c - reach, c + reach])),
            boundary=boundary,
        )
    raise AssertionError(kind)


@cache
def sample(kind, dim, n=300):
    """Test points: uniform in the case's box, and the same pulled towards an interior point."""
    case = make_case(kind, dim)
    rng = np.random.default_rng([dim, 99])
    lo, hi = case.box
    uniform = rng.uniform(lo, hi, (n, dim))
    # Pulled towards the interior point, the cube of a uniform number weighting the small pulls.
    pull = np.vstack([rng.random((n, 1)), rng.random((n, 1)) ** 3])
    pulled = case.interior + pull * (rng.uniform(lo, hi, (2 * n, dim)) - case.interior)
    return np.vstack([uniform, pulled])


def split(kind, dim):
    """Points, shape distances and reference distances, with enough points on each side."""
    case = make_case(kind, dim)
    x = sample(kind, dim)
    f, ref = case.shape.distance(x), case.reference(x)
    inside = case.shape.distance(x) < 0
    assert inside.sum() >= 30 and (~inside).sum() >= 30, "test points do not cover both sides"
    return case, x, f, ref


# ---------------------------------------------------------------------- generic checks
@pytest.mark.parametrize("kind, dim", CASES, ids=CASE_IDS)
def test_sign(kind, dim):
    case, x, f, ref = split(kind, dim)
    assert case.shape.distance(case.interior)[0] < 0
    far = case.interior + 100 * unit_vectors(np.random.default_rng(dim), 50, dim)
    away = case.reference(far) > 0 if not case.shape.is_bounded else np.ones(50, bool)
    assert away.any() and np.all(case.shape.distance(far[away]) > 0)
    clear = np.abs(ref) > TOL
    assert np.array_equal(np.sign(f[clear]), np.sign(ref[clear]))
    assert np.array_equal(case.shape.contains(x), f < 0)


@pytest.mark.parametrize("kind, dim", CASES, ids=CASE_IDS)
def test_exact_against_reference(kind, dim):
    case, _, f, ref = split(kind, dim)
    shape = case.shape
    inside, outside = ref < 0, ref > 0
    assert inside.sum() >= 30 and outside.sum() >= 30
    if shape.exact_inside:
        np.testing.assert_allclose(f[inside], ref[inside], rtol=0, atol=TOL)
    if shape.exact_outside:
        assert case.exact_outside_ref
        np.testing.assert_allclose(f[outside], ref[outside], rtol=0, atol=TOL)
    # Conservative everywhere: never larger in magnitude than the true distance.
    true = inside | (outside & case.exact_outside_ref)
    assert np.all(np.abs(f[true]) <= np.abs(ref[true]) + 1e-12 * (1 + np.abs(ref[true])))


@pytest.mark.parametrize("kind, dim", CASES, ids=CASE_IDS)
def test_lipschitz(kind, dim):
    shape = make_case(kind, dim).shape
    x = sample(kind, dim)
    rng = np.random.default_rng(dim)
    pairs = [x[rng.permutation(len(x))], x + 1e-3 * rng.normal(size=x.shape)]
    fx = shape.distance(x)
    for y in pairs:
        slope_room = np.linalg.norm(x - y, axis=1) * (1 + 1e-9) + 1e-13
        assert np.all(np.abs(fx - shape.distance(y)) <= slope_room)


@pytest.mark.parametrize("kind, dim", CASES, ids=CASE_IDS)
def test_gradient(kind, dim):
    shape = make_case(kind, dim).shape
    x = sample(kind, dim)[::3]
    f, g = shape.distance_and_gradient(x)
    np.testing.assert_array_equal(f, shape.distance(x))
    np.testing.assert_array_equal(g, shape.gradient(x))
    np.testing.assert_allclose(np.linalg.norm(g, axis=1), 1.0, rtol=0, atol=1e-12)

    def central(step):
        diff = np.empty_like(x)
        for axis in range(dim):
            e = np.zeros(dim)
            e[axis] = step
            diff[:, axis] = (shape.distance(x + e) - shape.distance(x - e)) / (2 * step)
        return diff

    fine, coarse = central(1e-6), central(4e-6)
    smooth = np.max(np.abs(fine - coarse), axis=1) < 1e-6  # away from kinks
    assert smooth.mean() > 0.9
    fd = fine[smooth] / np.linalg.norm(fine[smooth], axis=1, keepdims=True)
    np.testing.assert_allclose(g[smooth], fd, rtol=0, atol=1e-5)


EXACT_CASES = [(k, d) for k, d in CASES if k != "ellipsoid"]  # exact on at least one side


@pytest.mark.parametrize("kind, dim", EXACT_CASES, ids=[f"{k}-{d}d" for k, d in EXACT_CASES])
def test_nearest_boundary_point(kind, dim):
    case, x, f, _ = split(kind, dim)
    shape = case.shape
    use = ((f < 0) & shape.exact_inside) | ((f > 0) & shape.exact_outside)
    assert use.sum() >= 30
    p = shape.nearest_boundary_point(x[use])
    # Independent check that p is on the boundary: with 1-Lipschitz f this proves exactness.
    np.testing.assert_allclose(case.reference(p), 0.0, rtol=0, atol=TOL)
    np.testing.assert_allclose(
        np.linalg.norm(x[use] - p, axis=1), np.abs(f[use]), rtol=1e-12, atol=1e-15
    )


@pytest.mark.parametrize("kind, dim", CASES, ids=CASE_IDS)
def test_volume(kind, dim):
    shape = make_case(kind, dim).shape
    volume = shape.volume()
    assert volume.exact
    if not shape.is_bounded:
        assert volume.value == math.inf
        return
    estimate = monte_carlo_volume(shape, 200_000, seed=dim)
    assert abs(volume.value - estimate.value) <= 5 * estimate.error


@pytest.mark.parametrize("kind, dim", CASES, ids=CASE_IDS)
def test_bounds(kind, dim):
    case = make_case(kind, dim)
    shape = case.shape
    bounds = shape.bounds
    assert bounds.shape == (2, dim) and bounds.dtype == np.float64
    if not shape.is_bounded:
        with pytest.raises(ShapeError):
            check_packable(shape)
        return
    check_packable(shape)
    # Inside points, from a larger box and pulled towards the interior, lie within the bounds.
    rng = np.random.default_rng(dim)
    y = np.vstack([rng.uniform(*_grow(bounds, 0.5), (20_000, dim)), sample(kind, dim)])
    inside = y[shape.distance(y) < 0]
    assert len(inside) >= 30
    assert np.all((inside >= bounds[0]) & (inside <= bounds[1]))
    if dim <= 3:  # dense enough for the inside points to span most of the box
        span = np.ptp(inside, axis=0) / np.ptp(bounds, axis=0)
        assert np.all(span > 0.6)
    if case.support is not None:
        # Tight: the box of a convex set is [-h(-e_i), h(e_i)] with h its support function.
        eye = np.eye(dim)
        np.testing.assert_allclose(bounds[1], case.support(eye), rtol=0, atol=TOL)
        np.testing.assert_allclose(bounds[0], -case.support(-eye), rtol=0, atol=TOL)


BOUNDARY_CASES = [(k, d) for k, d in CASES if d <= 3 and k not in ("halfspace", "slab")]


@pytest.mark.parametrize("kind, dim", BOUNDARY_CASES, ids=[f"{k}-{d}d" for k, d in BOUNDARY_CASES])
def test_against_dense_boundary_sample(kind, dim):
    case = make_case(kind, dim)
    shape = case.shape
    rng = np.random.default_rng(7)
    boundary = case.boundary(rng, 20_000 if dim == 2 else 100_000)
    scale = float(np.ptp(shape.bounds, axis=0).max())
    # The sample lies on the boundary (checked by the shape and by the reference).
    assert np.abs(shape.distance(boundary)).max() < TOL * scale
    known = case.reference(boundary[:: len(boundary) // 2000])
    assert np.abs(known).max() < TOL * scale
    x = sample(kind, dim)
    nearest = cKDTree(boundary).query(x)[0]
    f = shape.distance(x)
    # Sampled boundary points are at least as far as the nearest boundary point.
    assert np.all(np.abs(f) <= nearest + 1e-12)
    exact = np.where(f < 0, shape.exact_inside, shape.exact_outside)
    resolution = (0.01 if dim == 2 else 0.05) * scale
    assert np.all(nearest[exact] - np.abs(f[exact]) <= resolution)


# ---------------------------------------------------------------------- specific properties
@pytest.mark.parametrize("dim", DIMS)
def test_ellipsoid_bound_and_equal_radii(dim):
    case, x, f, ref = split("ellipsoid", dim)
    assert not case.shape.exact_inside and not case.shape.exact_outside
    # A strict bound somewhere (radii differ), never above the true distance.
    assert np.any(np.abs(f) < np.abs(ref) - 1e-3)
    # Equal radii: a ball, and then exact.
    c = np.linspace(-1, 1, dim)
    sphere = Ellipsoid(c, np.full(dim, 1.5))
    np.testing.assert_allclose(sphere.distance(x), np.linalg.norm(x - c, axis=1) - 1.5, atol=1e-12)


@pytest.mark.parametrize("dim", DIMS)
def test_capsule_of_zero_length_is_a_ball(dim):
    c = np.linspace(-1, 2, dim)
    capsule, ball = Capsule(c, c, 0.7), Ball(c, 0.7)
    x = sample("ball", dim)
    np.testing.assert_allclose(capsule.distance(x), ball.distance(x), atol=1e-12)
    assert capsule.volume().value == pytest.approx(ball.volume().value, rel=1e-12)
    np.testing.assert_allclose(capsule.bounds, ball.bounds)


@pytest.mark.parametrize("dim", [2, 3, 5, 7])
def test_polytope_box_matches_box(dim):
    lo, hi = -np.arange(1, dim + 1) / 2, np.ones(dim)
    cube = ConvexPolytope(np.vstack([np.eye(dim), -2 * np.eye(dim)]), np.concatenate([hi, -2 * lo]))
    assert cube.chebyshev_radius == pytest.approx((hi - lo).min() / 2)
    np.testing.assert_allclose(cube.bounds, [lo, hi], atol=TOL)
    assert cube.volume().value == pytest.approx(np.prod(hi - lo), rel=1e-9)
    x = np.random.default_rng(dim).uniform(lo - 1, hi + 1, (400, dim))
    f, ref = cube.distance(x), box_reference(x, lo, hi)
    inside = ref < 0
    np.testing.assert_allclose(f[inside], ref[inside], atol=TOL)
    # Outside only a bound, but one within a factor sqrt(d) (max of d distances vs their norm).
    assert np.all(f[~inside] <= ref[~inside] + 1e-12)
    assert np.all(f[~inside] >= ref[~inside] / np.sqrt(dim) - 1e-12)
    assert np.any(f[~inside] < ref[~inside] - 1e-3)


def test_polytope_with_many_vertices_falls_back_to_monte_carlo():
    # 8D, 29 random facets: thousands of vertices, too many for Qhull's triangulation.
    rng = np.random.default_rng(3)
    normals = np.vstack([np.eye(8), -np.ones(8), rng.normal(size=(20, 8))])
    polytope = ConvexPolytope(normals, np.ones(len(normals)))
    volume = polytope.volume(samples=20_000)
    assert not volume.exact and 0 < volume.value < math.inf
    assert volume == monte_carlo_volume(polytope, 20_000, 0)


@pytest.mark.parametrize("dim", [2, 3, 4])
def test_unbounded_polytope(dim):
    # A cone-like wedge: x_0 <= 1 and x_0 - x_1 <= 0 is unbounded below.
    normals = np.zeros((2, dim))
    normals[0, 0], normals[1, 0], normals[1, 1] = 1, 1, -1
    wedge = ConvexPolytope(normals, [1.0, 0.0])
    assert not wedge.is_bounded
    assert wedge.bounds[1, 0] == pytest.approx(1.0)
    assert wedge.bounds[0, 0] == -np.inf and wedge.bounds[1, 1] == np.inf
    assert wedge.volume().value == math.inf
    assert wedge.distance(wedge.chebyshev_center)[0] < 0


@pytest.mark.parametrize("dim", DIMS)
def test_simplex_matches_polytope_from_lp(dim):
    vertices = make_case("simplex", dim).shape.vertices
    simplex = Simplex(vertices[::-1])  # other orientation of the vertex order
    general = ConvexPolytope(simplex.normals, simplex.offsets)
    assert simplex.chebyshev_radius == pytest.approx(general.chebyshev_radius, rel=1e-7)
    np.testing.assert_allclose(simplex.bounds, general.bounds, atol=1e-9)
    assert simplex.volume().value == pytest.approx(general.volume().value, rel=1e-9)
    # The vertices are on the boundary, the centroid inside, the vertices pushed out outside.
    centroid = vertices.mean(axis=0)
    np.testing.assert_allclose(simplex.distance(vertices), 0, atol=1e-12)
    assert simplex.distance(centroid)[0] < 0
    assert np.all(simplex.distance(centroid + 1.01 * (vertices - centroid)) > 0)
    # The incentre is at distance r from every facet.
    np.testing.assert_allclose(
        simplex.offsets - simplex.normals @ simplex.chebyshev_center, simplex.chebyshev_radius
    )


@pytest.mark.parametrize("dim", [2, 3, 6])
def test_axis_aligned_half_spaces_and_slabs(dim):
    e0 = np.eye(dim)[0]
    upper = HalfSpace(2 * e0, 3.0)
    assert upper.bounds[1, 0] == 1.5 and np.all(np.isinf(upper.bounds[0]))
    assert np.all(np.isinf(upper.bounds[1, 1:]))
    lower = HalfSpace(-e0, 1.0)  # x_0 >= -1
    assert lower.bounds[0, 0] == -1.0 and np.all(np.isinf(lower.bounds[1]))
    slab = Slab(-3 * np.eye(dim)[1], 0.5, 2.0)  # -2 <= x_1 <= -0.5
    np.testing.assert_array_equal(slab.bounds[:, 1], [-2.0, -0.5])
    assert np.all(np.isinf(slab.bounds[:, 0]))
    point = np.zeros(dim)
    point[1] = -1.0
    assert slab.distance(point)[0] == pytest.approx(-0.5)


@pytest.mark.parametrize("dim", [2, 3, 7])
def test_cylinder_axis_aligned(dim):
    a, b = np.zeros(dim), 2 * np.eye(dim)[0]
    cylinder = Cylinder(a, b, 0.5)
    expected = np.full((2, dim), 0.5)
    expected[0] *= -1
    expected[:, 0] = [0.0, 2.0]
    np.testing.assert_allclose(cylinder.bounds, expected, atol=1e-15)
    assert cylinder.volume().value == pytest.approx(2 * float(ball_volume(dim - 1, 0.5)))


def test_rounded_box_steiner_volume_2d_3d():
    # 2D: the four corners each lose (1 - pi/4) r^2. 3D: the inner box, six face slabs,
    # twelve quarter cylinders along the edges (three whole cylinders) and eight ball octants.
    a, b, r = 3.0, 2.0, 0.5
    assert RoundedBox([0, 0], [a, b], r).volume().value == pytest.approx(
        a * b - (4 - math.pi) * r**2
    )
    a, b, c = 3.0, 2.0, 1.5
    inner = np.array([a, b, c]) - 2 * r
    expected = (
        np.prod(inner)
        + 2 * r * (inner[0] * inner[1] + inner[1] * inner[2] + inner[0] * inner[2])
        + math.pi * r**2 * inner.sum()
        + 4 / 3 * math.pi * r**3
    )
    assert RoundedBox([0, 0, 0], [a, b, c], r).volume().value == pytest.approx(expected)


def test_torus_volume_and_hole():
    torus = Torus([0, 0, 0], 2.0, 0.5)
    assert torus.volume().value == pytest.approx(2 * math.pi**2 * 2.0 * 0.25)
    assert torus.distance([0, 0, 0])[0] == pytest.approx(1.5)  # the hole is outside
    assert torus.distance([2, 0, 0])[0] == pytest.approx(-0.5)
    assert not torus.convex
    # Degenerate gradient points still give unit vectors.
    g = torus.gradient([[0, 0, 0], [0, 2, 0], [0, 0, 5]])
    np.testing.assert_allclose(np.linalg.norm(g, axis=1), 1.0)


def test_degenerate_points_have_unit_gradients():
    shapes_and_points = [
        (Ball([1, 2], 1), [[1, 2]]),
        (Box([0, 0, 0], [2, 2, 2]), [[1, 1, 1]]),
        (Capsule([0, 0, 0], [1, 0, 0], 0.5), [[0.5, 0, 0], [0, 0, 0]]),
        (Cylinder([0, 0, 0], [0, 0, 1], 0.5), [[0, 0, 0.5], [0, 0, 2]]),
        (Ellipsoid([0, 0], [1, 2]), [[0, 0]]),
        (Slab([1, 0], -1, 1), [[0, 0]]),
    ]
    for shape, points in shapes_and_points:
        f, g = shape.distance_and_gradient(points)
        np.testing.assert_allclose(np.linalg.norm(g, axis=1), 1.0)
        if shape.exact_inside:
            # Even at a degenerate point, following the gradient lands on the boundary.
            p = np.asarray(points, float) - f[:, None] * g
            np.testing.assert_allclose(shape.distance(p), 0, atol=1e-12)


@pytest.mark.parametrize("kind, dim", [(k, 3) for k in ND_KINDS] + [("torus", 3)])
def test_repr_round_trips(kind, dim):
    shape = make_case(kind, dim).shape
    text = repr(shape)
    assert text.startswith(type(shape).__name__ + "(")
    classes = (
        Ball,
        Box,
        RoundedBox,
        HalfSpace,
        Slab,
        Capsule,
        Cylinder,
        ConvexPolytope,
        Simplex,
        Ellipsoid,
        Torus,
    )
    names = {cls.__name__: cls for cls in classes}
    copy = eval(text, names)
    x = sample(kind, dim)
    np.testing.assert_allclose(copy.distance(x), shape.distance(x), atol=1e-12)


def test_single_point_and_wrong_dimension():
    ball = Ball([0, 0, 0], 1)
    assert ball.distance([0, 0, 0]).shape == (1,)
    with pytest.raises(DimensionError):
        ball.distance([[0, 0]])


# ---------------------------------------------------------------------- bad input
@pytest.mark.parametrize(
    "build, error",
    [
        (lambda: Ball([0, 0], 0), ShapeError),
        (lambda: Ball([0, 0], -1), ShapeError),
        (lambda: Ball([0, 0], np.inf), ShapeError),
        (lambda: Ball([0, np.nan], 1), ShapeError),
        (lambda: Ball([0], 1), DimensionError),
        (lambda: Ball([[0, 0]], 1), DimensionError),
        (lambda: Ball([0, 0], [1, 2]), ShapeError),
        (lambda: Box([0, 0], [1, 0]), ShapeError),
        (lambda: Box([0, 0], [1, -1]), ShapeError),
        (lambda: Box([0, 0], [1, 1, 1]), DimensionError),
        (lambda: RoundedBox([0, 0], [1, 2], 0.5), ShapeError),
        (lambda: RoundedBox([0, 0], [1, 2], 0), ShapeError),
        (lambda: HalfSpace([0, 0], 1), ShapeError),
        (lambda: HalfSpace([1, 0], np.nan), ShapeError),
        (lambda: Slab([1, 0], 1, 1), ShapeError),
        (lambda: Slab([1, 0], 2, 1), ShapeError),
        (lambda: Slab([0, 0], 0, 1), ShapeError),
        (lambda: Capsule([0, 0], [1, 1], 0), ShapeError),
        (lambda: Capsule([0, 0], [1, 1, 1], 1), DimensionError),
        (lambda: Cylinder([0, 0, 0], [0, 0, 0], 1), ShapeError),
        (lambda: Cylinder([0, 0, 0], [0, 0, 1], -1), ShapeError),
        (lambda: ConvexPolytope([[1, 0], [-1, 0]], [0, 0]), ShapeError),  # flat
        (lambda: ConvexPolytope([[1, 0], [-1, 0]], [0, -1]), ShapeError),  # empty
        (lambda: ConvexPolytope([[1, 0], [0, 0]], [1, 1]), ShapeError),  # zero normal
        (lambda: ConvexPolytope([[1, 0], [0, 1]], [1, 1, 1]), DimensionError),
        (lambda: ConvexPolytope([1, 0], [1]), DimensionError),
        (lambda: Simplex([[0, 0], [1, 1], [2, 2]]), ShapeError),  # collinear
        (lambda: Simplex([[0, 0], [1, 0], [0, 1], [1, 1]]), DimensionError),
        (lambda: Simplex([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 1e-14]]), ShapeError),
        (lambda: Ellipsoid([0, 0], [1, 0]), ShapeError),
        (lambda: Ellipsoid([0, 0], [1, 2, 3]), DimensionError),
        (lambda: Torus([0, 0], 2, 1), DimensionError),
        (lambda: Torus([0, 0, 0, 0], 2, 1), DimensionError),
        (lambda: Torus([0, 0, 0], 1, 2), ShapeError),
        (lambda: Torus([0, 0, 0], 1, 1), ShapeError),
        (lambda: Torus([0, 0, 0], 2, 0), ShapeError),
    ],
)
def test_bad_input_raises(build, error):
    with pytest.raises(error) as info:
        build()
    assert len(str(info.value)) > 20  # says what was wrong


def test_the_diagonal_of_the_bounds_is_the_unit_of_relative_figures():
    assert Box([0, 0], [3, 4]).diagonal == pytest.approx(5.0)
    assert (Ball([1, 1, 1], 1.0) - Ball([1, 1, 1], 0.5)).diagonal == pytest.approx(2 * np.sqrt(3))
    assert HalfSpace([0, 0, 1], 0.0).diagonal == np.inf
