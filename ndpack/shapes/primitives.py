"""Primitive shapes: analytic signed distance oracles in any dimension.

Shapes
------
Ball(center, radius)
    The solid ``d``-ball. Exact, convex.
Box(lower, upper)
    An axis-aligned box. Exact, convex.
RoundedBox(lower, upper, radius)
    A box with its edges and corners rounded. Exact, convex.
HalfSpace(normal, offset=0.0)
    ``{x : n . x <= offset}``. Exact, convex, unbounded.
Slab(normal, lower, upper)
    ``{x : lower <= n . x <= upper}`` for a unit normal ``n``. Exact, convex, unbounded.
Capsule(a, b, radius)
    The points within ``radius`` of the segment ``ab``. Exact, convex.
Cylinder(a, b, radius)
    A ``(d-1)``-ball orthogonal to the axis ``ab``, swept from ``a`` to ``b``. Exact, convex.
ConvexPolytope(normals, offsets)
    ``{x : normals @ x <= offsets}``. Exact inside, a lower bound outside, convex.
Simplex(vertices)
    The convex hull of ``d + 1`` affinely independent points. Exact inside, convex.
Ellipsoid(center, radii)
    An axis-aligned ellipsoid. A lower bound on both sides (exact for equal radii), convex.
Torus(center, major_radius, minor_radius)
    A ring torus around the z axis, 3D only. Exact, not convex.

Every shape evaluates its distance and analytic unit gradient on whole ``(n, d)`` arrays at once.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import linprog
from scipy.spatial import ConvexHull, HalfspaceIntersection, QhullError

from ..errors import DimensionError, ShapeError
from ..kernels import library
from ..oracle import Oracle, as_vector, ball_volume, unit_rows

__all__ = [  # in the order of the module docstring
    "Ball",
    "Box",
    "RoundedBox",
    "HalfSpace",
    "Slab",
    "Capsule",
    "Cylinder",
    "ConvexPolytope",
    "Simplex",
    "Ellipsoid",
    "Torus",
]


# ---------------------------------------------------------------------- validation helpers
def _as_point(values, name: str) -> np.ndarray:
    """A finite ``(d,)`` float64 vector with ``d >= 2``; its length sets the shape's dimension."""
    array = np.asarray(values, dtype=np.float64)
    if array.ndim != 1 or array.shape[0] < 2:
        raise DimensionError(
            f"{name} must be a vector of at least 2 coordinates (its length sets the "
            f"dimension), got an array of shape {array.shape}"
        )
    if not np.all(np.isfinite(array)):
        raise ShapeError(f"{name} must be finite, got {array.tolist()}")
    return array


def _positive(value, name: str) -> float:
    """``value`` as a positive finite float, or a ShapeError saying what was wrong."""
    if np.ndim(value) != 0:
        raise ShapeError(f"{name} must be a single number, got {value!r}")
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise ShapeError(f"{name} must be a number, got {value!r}") from None
    if not (math.isfinite(number) and number > 0):
        raise ShapeError(f"{name} must be a positive finite number, got {number}")
    return number


def _finite(value, name: str) -> float:
    """``value`` as a finite float."""
    if np.ndim(value) != 0:
        raise ShapeError(f"{name} must be a single number, got {value!r}")
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise ShapeError(f"{name} must be a number, got {value!r}") from None
    if not math.isfinite(number):
        raise ShapeError(f"{name} must be finite, got {number}")
    return number


def _unit_normal(normal, name: str = "normal") -> tuple[np.ndarray, float]:
    """The normal as a unit vector, with its original length."""
    normal = _as_point(normal, name)
    length = float(np.linalg.norm(normal))
    if length == 0.0:
        raise ShapeError(f"{name} must be a non-zero vector, got {normal.tolist()}")
    return normal / length, length


def _check_box(lower: np.ndarray, upper: np.ndarray) -> None:
    bad = np.flatnonzero(~(lower < upper))
    if bad.size:
        axis = int(bad[0])
        raise ShapeError(
            f"lower must be < upper on every axis, but on axis {axis} lower = {lower[axis]} and "
            f"upper = {upper[axis]}; swap them or give the box a positive width"
        )


def _orthogonal_unit(axis: np.ndarray) -> np.ndarray:
    """Some unit vector orthogonal to the unit vector ``axis`` (used where a direction is arbitrary)."""
    k = int(np.argmin(np.abs(axis)))
    vector = -axis[k] * axis
    vector[k] += 1.0
    return vector / np.linalg.norm(vector)


def _unit_or(vectors: np.ndarray, norms: np.ndarray, fallback: np.ndarray) -> np.ndarray:
    """Rows of ``vectors`` divided by ``norms``; rows of zero norm become ``fallback``."""
    out = np.empty_like(vectors)
    ok = norms > 0
    out[ok] = vectors[ok] / norms[ok, None]
    out[~ok] = fallback
    return out


def _plane_bounds(normal: np.ndarray, low: float, high: float) -> np.ndarray:
    """Bounds of ``{x : low <= normal . x <= high}`` (unit ``normal``): infinite unless axis-aligned."""
    dim = normal.shape[0]
    bounds = np.array([np.full(dim, -np.inf), np.full(dim, np.inf)])
    nonzero = np.flatnonzero(normal)
    if nonzero.size == 1:  # the set is bounded only along the normal's own axis
        k = int(nonzero[0])
        bounds[:, k] = sorted((low / normal[k], high / normal[k]))
    return bounds


def _floats(array: np.ndarray) -> list:
    """An array as nested lists of Python floats, for readable reprs."""
    return np.asarray(array, dtype=np.float64).tolist()


class _Analytic(Oracle):
    """Shared plumbing: the analytic gradient comes together with the distance, and the
    compiled distance is a library kernel (:mod:`ndpack.kernels.library`) on the shape's numbers.

    Subclasses define ``_leaf() -> (library function, values)``: the function and the
    parameters in the layout its comment gives.
    """

    def _gradient(self, points: np.ndarray) -> np.ndarray:
        return self._distance_and_gradient(points)[1]

    def _tape(self, tape):
        tape.leaf(*self._leaf())

    def _kernel(self, program):
        function, values = self._leaf()
        offset = program.add_params(values)
        return program.define(f"def _(p, prm):\n    return {program.use(function)}(p, prm, {offset})\n")


# ---------------------------------------------------------------------- ball and boxes
class Ball(_Analytic):
    """The solid ball ``|x - center| <= radius``.

    Parameters
    ----------
    center : (d,) array_like
        Centre; its length sets the dimension (``d >= 2``).
    radius : float
        Radius, positive.
    """

    exact_inside = True
    exact_outside = True
    convex = True

    def __init__(self, center, radius):
        self.center = _as_point(center, "center")
        self.radius = _positive(radius, "radius")
        self.dim = self.center.shape[0]
        self._bounds = np.array([self.center - self.radius, self.center + self.radius])

    def _distance(self, points):
        return np.linalg.norm(points - self.center, axis=1) - self.radius

    def _distance_and_gradient(self, points):
        offset = points - self.center
        # At the centre every direction is steepest; unit_rows picks the first axis.
        return np.linalg.norm(offset, axis=1) - self.radius, unit_rows(offset)

    def _exact_volume(self):
        return float(ball_volume(self.dim, self.radius))

    def _leaf(self):
        return library.ball, [*self.center, self.radius]

    def __repr__(self):
        return f"Ball(center={_floats(self.center)}, radius={self.radius!r})"


def _box_distance(points, center, half):
    """Exact signed distance to the box ``|x - center| <= half`` (componentwise)."""
    q = np.abs(points - center) - half
    outside = np.linalg.norm(np.maximum(q, 0.0), axis=1)
    return outside + np.minimum(q.max(axis=1), 0.0)


def _box_distance_and_gradient(points, center, half):
    offset = points - center
    sign = np.where(offset >= 0, 1.0, -1.0)
    q = np.abs(offset) - half
    positive = np.maximum(q, 0.0)
    outside = np.linalg.norm(positive, axis=1)
    distance = outside + np.minimum(q.max(axis=1), 0.0)
    # Inside (and on the boundary): the outward normal of the nearest face.
    gradient = np.zeros_like(points)
    rows = np.arange(points.shape[0])
    face = np.argmax(q, axis=1)
    gradient[rows, face] = sign[rows, face]
    # Outside: the direction from the nearest box point.
    out = outside > 0
    gradient[out] = sign[out] * positive[out] / outside[out, None]
    return distance, gradient


class Box(_Analytic):
    """The axis-aligned box ``lower <= x <= upper``.

    Parameters
    ----------
    lower, upper : (d,) array_like
        Opposite corners, ``lower < upper`` on every axis (``upper`` may be a scalar).
    """

    exact_inside = True
    exact_outside = True
    convex = True

    def __init__(self, lower, upper):
        self.lower = _as_point(lower, "lower")
        self.dim = self.lower.shape[0]
        self.upper = as_vector(upper, self.dim, "upper")
        _check_box(self.lower, self.upper)
        self._center = (self.lower + self.upper) / 2
        self._half = (self.upper - self.lower) / 2
        self._bounds = np.array([self.lower, self.upper])

    def _distance(self, points):
        return _box_distance(points, self._center, self._half)

    def _distance_and_gradient(self, points):
        return _box_distance_and_gradient(points, self._center, self._half)

    def _exact_volume(self):
        return float(np.prod(self.upper - self.lower))

    def _leaf(self):
        return library.box, [*self._center, *self._half]

    def __repr__(self):
        return f"Box(lower={_floats(self.lower)}, upper={_floats(self.upper)})"


def _elementary_symmetric(values: np.ndarray) -> np.ndarray:
    """``e_0 .. e_n`` of ``values``: the coefficients of prod_i (1 + v_i t)."""
    e = np.zeros(len(values) + 1)
    e[0] = 1.0
    for v in values:
        e[1:] = e[1:] + v * e[:-1]
    return e


class RoundedBox(_Analytic):
    """The box ``[lower, upper]`` with edges and corners rounded by ``radius``.

    It is the inner box ``[lower + radius, upper - radius]`` dilated by ``radius``, so its distance
    is the inner box's minus ``radius``, exact on both sides because the box is convex.

    Parameters
    ----------
    lower, upper : (d,) array_like
        Opposite corners of the outer box, ``lower < upper`` on every axis.
    radius : float
        Rounding radius, ``0 < radius < min(upper - lower) / 2``.
    """

    exact_inside = True
    exact_outside = True
    convex = True

    def __init__(self, lower, upper, radius):
        self.lower = _as_point(lower, "lower")
        self.dim = self.lower.shape[0]
        self.upper = as_vector(upper, self.dim, "upper")
        _check_box(self.lower, self.upper)
        self.radius = _positive(radius, "radius")
        smallest = float(np.min(self.upper - self.lower))
        if not self.radius < smallest / 2:
            raise ShapeError(
                f"radius must be < half the smallest side ({smallest / 2}), got {self.radius}; "
                "use a smaller radius, or a Ball / Capsule for fully rounded shapes"
            )
        self._center = (self.lower + self.upper) / 2
        self._inner_half = (self.upper - self.lower) / 2 - self.radius
        self._bounds = np.array([self.lower, self.upper])

    def _distance(self, points):
        return _box_distance(points, self._center, self._inner_half) - self.radius

    def _distance_and_gradient(self, points):
        distance, gradient = _box_distance_and_gradient(points, self._center, self._inner_half)
        return distance - self.radius, gradient

    def _exact_volume(self):
        # Steiner formula: vol(K + rB) = sum_k e_k(sides) * vol(B^{d-k}) * r^{d-k}.
        e = _elementary_symmetric(2 * self._inner_half)
        d, r = self.dim, self.radius
        return float(sum(e[k] * ball_volume(d - k, 1.0) * r ** (d - k) for k in range(d + 1)))

    def _leaf(self):
        return library.rounded_box, [*self._center, *self._inner_half, self.radius]

    def __repr__(self):
        return (
            f"RoundedBox(lower={_floats(self.lower)}, upper={_floats(self.upper)}, "
            f"radius={self.radius!r})"
        )


# ---------------------------------------------------------------------- flat shapes
class HalfSpace(_Analytic):
    """The half-space ``{x : normal . x <= offset}``.

    The normal is normalised and the offset divided by its length, kept as ``plane_offset``:
    the signed distance of the boundary plane from the origin (an attribute named ``offset``
    would hide the :meth:`offset` method of every shape).

    Parameters
    ----------
    normal : (d,) array_like
        Outward normal, non-zero.
    offset : float
        Right-hand side of the inequality.
    """

    exact_inside = True
    exact_outside = True
    convex = True

    def __init__(self, normal, offset=0.0):
        self.normal, length = _unit_normal(normal)
        self.plane_offset = _finite(offset, "offset") / length
        self.dim = self.normal.shape[0]
        self._bounds = _plane_bounds(self.normal, -np.inf, self.plane_offset)

    def _distance(self, points):
        return points @ self.normal - self.plane_offset

    def _distance_and_gradient(self, points):
        gradient = np.broadcast_to(self.normal, points.shape).copy()
        return self._distance(points), gradient

    def _exact_volume(self):
        return math.inf

    def _leaf(self):
        return library.half_space, [*self.normal, self.plane_offset]

    def __repr__(self):
        return f"HalfSpace(normal={_floats(self.normal)}, offset={self.plane_offset!r})"


class Slab(_Analytic):
    """The slab ``{x : lower <= n . x <= upper}`` between two parallel planes.

    Parameters
    ----------
    normal : (d,) array_like
        Direction across the slab, non-zero; it is normalised first, so ``lower`` and ``upper``
        are signed distances from the origin along the unit normal.
    lower, upper : float
        The slab's extent along the unit normal, ``lower < upper``.
    """

    exact_inside = True
    exact_outside = True
    convex = True

    def __init__(self, normal, lower, upper):
        self.normal, _ = _unit_normal(normal)
        self.lower = _finite(lower, "lower")
        self.upper = _finite(upper, "upper")
        if not self.lower < self.upper:
            raise ShapeError(
                f"lower must be < upper, got lower = {self.lower} and upper = {self.upper}; "
                "swap them or give the slab a positive thickness"
            )
        self.dim = self.normal.shape[0]
        self._mid = (self.lower + self.upper) / 2
        self._half = (self.upper - self.lower) / 2
        self._bounds = _plane_bounds(self.normal, self.lower, self.upper)

    def _distance(self, points):
        return np.abs(points @ self.normal - self._mid) - self._half

    def _distance_and_gradient(self, points):
        height = points @ self.normal - self._mid
        side = np.where(height >= 0, 1.0, -1.0)
        return np.abs(height) - self._half, side[:, None] * self.normal

    def _exact_volume(self):
        return math.inf

    def _leaf(self):
        return library.slab, [*self.normal, self._mid, self._half]

    def __repr__(self):
        return f"Slab(normal={_floats(self.normal)}, lower={self.lower!r}, upper={self.upper!r})"


# ---------------------------------------------------------------------- round shapes on a segment
class Capsule(_Analytic):
    """The points within ``radius`` of the segment from ``a`` to ``b`` (a ball when ``a == b``).

    Parameters
    ----------
    a, b : (d,) array_like
        End points of the segment.
    radius : float
        Radius, positive.
    """

    exact_inside = True
    exact_outside = True
    convex = True

    def __init__(self, a, b, radius):
        self.a = _as_point(a, "a")
        self.dim = self.a.shape[0]
        self.b = as_vector(b, self.dim, "b")
        self.radius = _positive(radius, "radius")
        self._ab = self.b - self.a
        self._length_sq = float(self._ab @ self._ab)
        self.length = math.sqrt(self._length_sq)
        self._axis = self._ab / self.length if self.length > 0 else np.eye(self.dim)[0]
        # On the segment itself every direction across the axis is steepest: pick one.
        self._across = _orthogonal_unit(self._axis)
        self._bounds = np.array(
            [np.minimum(self.a, self.b) - self.radius, np.maximum(self.a, self.b) + self.radius]
        )

    def _from_segment(self, points):
        """(n, d): each point minus its nearest point on the segment."""
        relative = points - self.a
        if self._length_sq == 0:
            return relative
        t = relative @ self._ab / self._length_sq
        vector = relative - np.clip(t, 0.0, 1.0)[:, None] * self._ab
        # Beside the segment the vector is orthogonal to it: project once more to remove the
        # round-off that would tilt the gradient of points close to the axis.
        beside = (t > 0) & (t < 1)
        vector -= np.where(beside, vector @ self._axis, 0.0)[:, None] * self._axis
        return vector

    def _distance(self, points):
        return np.linalg.norm(self._from_segment(points), axis=1) - self.radius

    def _distance_and_gradient(self, points):
        vector = self._from_segment(points)
        norm = np.linalg.norm(vector, axis=1)
        return norm - self.radius, _unit_or(vector, norm, self._across)

    def _exact_volume(self):
        d, r = self.dim, self.radius
        return float(ball_volume(d, r) + ball_volume(d - 1, r) * self.length)

    def _leaf(self):
        return library.capsule, [*self.a, *self._ab, *self._axis, self._length_sq, self.radius]

    def __repr__(self):
        return f"Capsule(a={_floats(self.a)}, b={_floats(self.b)}, radius={self.radius!r})"


class Cylinder(_Analytic):
    """A solid cylinder: the ``(d-1)``-ball of ``radius`` orthogonal to ``b - a``, swept from a to b.

    It is the product of a ball and an interval, so with ``ra`` the radial and ``ha`` the axial
    excess its exact distance is ``min(max(ra, ha), 0) + |(max(ra, 0), max(ha, 0))|``.

    Parameters
    ----------
    a, b : (d,) array_like
        Centres of the two end discs, distinct; the axis may point anywhere.
    radius : float
        Radius, positive.
    """

    exact_inside = True
    exact_outside = True
    convex = True

    def __init__(self, a, b, radius):
        self.a = _as_point(a, "a")
        self.dim = self.a.shape[0]
        self.b = as_vector(b, self.dim, "b")
        self.radius = _positive(radius, "radius")
        self.length = float(np.linalg.norm(self.b - self.a))
        if self.length == 0:
            raise ShapeError(
                f"a and b must differ (they set the axis), both are {self.a.tolist()}; "
                "use a Ball or a Capsule for a zero-length shape"
            )
        self.axis = (self.b - self.a) / self.length
        self._mid = (self.a + self.b) / 2
        self._half = self.length / 2
        self._across = _orthogonal_unit(self.axis)
        # Tight box: the end discs reach radius * sqrt(1 - u_i^2) along axis i.
        reach = self.radius * np.sqrt(np.maximum(1.0 - self.axis**2, 0.0))
        self._bounds = np.array(
            [np.minimum(self.a, self.b) - reach, np.maximum(self.a, self.b) + reach]
        )

    def _split(self, points):
        """Axial coordinate (n,) from the middle and radial vector (n, d) of each point."""
        offset = points - self._mid
        axial = offset @ self.axis
        radial = offset - axial[:, None] * self.axis
        # Project once more: round-off would tilt the radial direction of points near the axis.
        radial -= (radial @ self.axis)[:, None] * self.axis
        return axial, radial

    def _distance(self, points):
        axial, radial = self._split(points)
        ra = np.linalg.norm(radial, axis=1) - self.radius
        ha = np.abs(axial) - self._half
        return np.minimum(np.maximum(ra, ha), 0.0) + np.hypot(
            np.maximum(ra, 0.0), np.maximum(ha, 0.0)
        )

    def _distance_and_gradient(self, points):
        axial, radial = self._split(points)
        rho = np.linalg.norm(radial, axis=1)
        ra = rho - self.radius
        ha = np.abs(axial) - self._half
        out_r, out_h = np.maximum(ra, 0.0), np.maximum(ha, 0.0)
        outside = np.hypot(out_r, out_h)
        distance = np.minimum(np.maximum(ra, ha), 0.0) + outside

        across = _unit_or(radial, rho, self._across)
        along = np.where(axial >= 0, 1.0, -1.0)[:, None] * self.axis
        # Inside: the normal of the nearer of side and cap; outside: from the nearest point.
        use_side = (ra >= ha)[:, None]
        gradient = np.where(use_side, across, along)
        out = outside > 0
        blend = out_r[out, None] * across[out] + out_h[out, None] * along[out]
        gradient[out] = blend / outside[out, None]
        return distance, gradient

    def _exact_volume(self):
        return float(ball_volume(self.dim - 1, self.radius) * self.length)

    def _leaf(self):
        return library.cylinder, [*self._mid, *self.axis, self.radius, self._half]

    def __repr__(self):
        return f"Cylinder(a={_floats(self.a)}, b={_floats(self.b)}, radius={self.radius!r})"


# ---------------------------------------------------------------------- polytopes
def _max_hull_vertices(dim: int) -> int:
    """Vertex count up to which a ConvexPolytope's volume is exact (Qhull takes about a second)."""
    return {7: 700, 8: 300}.get(dim, 2000 if dim < 7 else 100)


class ConvexPolytope(_Analytic):
    """The convex polytope ``{x : normals @ x <= offsets}``, bounded or not.

    Rows are normalised, so the distance ``max_i (n_i . x - b_i)`` is exact inside (the distance
    to the nearest facet plane) and a lower bound outside (beyond edges and corners the true
    distance is larger). The Chebyshev centre (centre of the largest inscribed ball) and the
    bounds come from linear programs. The volume comes from Qhull when the polytope has at most
    a vertex limit that falls with the dimension (300 in 8D); beyond, where triangulating the
    hull takes Qhull minutes, it is a Monte Carlo estimate.

    Parameters
    ----------
    normals : (m, d) array_like
        Outward normals of the ``m`` half-spaces, non-zero rows; redundant ones are allowed.
    offsets : (m,) array_like
        Right-hand sides.

    Attributes
    ----------
    normals : (m, d) float64
        Unit outward normals.
    offsets : (m,) float64
        Offsets divided by the original row lengths.
    chebyshev_center : (d,) float64
        An interior point: the centre of the largest inscribed ball (for unbounded polytopes
        whose inscribed balls grow without limit, just some point with a unit ball inside).
    chebyshev_radius : float
        Radius of the largest inscribed ball, ``inf`` when unlimited.
    """

    exact_inside = True
    exact_outside = False
    convex = True

    def __init__(self, normals, offsets):
        normals = np.asarray(normals, dtype=np.float64)
        if normals.ndim != 2 or normals.shape[0] < 1 or normals.shape[1] < 2:
            raise DimensionError(
                "normals must be an (m, d) array with m >= 1 half-spaces in d >= 2 dimensions, "
                f"got an array of shape {normals.shape}"
            )
        offsets = np.asarray(offsets, dtype=np.float64)
        if offsets.shape != (normals.shape[0],):
            raise DimensionError(
                f"offsets must have one entry per normal, shape ({normals.shape[0]},), got "
                f"shape {offsets.shape}"
            )
        if not (np.all(np.isfinite(normals)) and np.all(np.isfinite(offsets))):
            raise ShapeError("normals and offsets must be finite")
        lengths = np.linalg.norm(normals, axis=1)
        zero = np.flatnonzero(lengths == 0)
        if zero.size:
            raise ShapeError(
                f"normal {int(zero[0])} is the zero vector; every row needs a direction"
            )
        self._set_planes(normals / lengths[:, None], offsets / lengths)
        self._solve_linear_programs()

    def _set_planes(self, normals: np.ndarray, offsets: np.ndarray) -> None:
        self.normals = normals
        self.offsets = offsets
        self.dim = normals.shape[1]
        self._volume = None
        self._volume_done = False

    def _solve_linear_programs(self) -> None:
        normals, offsets, dim = self.normals, self.offsets, self.dim
        free = [(None, None)] * dim
        # Chebyshev centre: maximise t subject to n_i . x + t <= b_i (unit normals), t >= 0.
        cost = np.zeros(dim + 1)
        cost[-1] = -1.0
        stacked = np.hstack([normals, np.ones((len(offsets), 1))])
        result = linprog(
            cost, A_ub=stacked, b_ub=offsets, bounds=free + [(0, None)], method="highs"
        )
        if result.status == 0:
            center, radius = result.x[:dim], float(result.x[dim])
        elif result.status in (3, 4):
            # Unbounded (or HiGHS cannot tell from infeasible): cap t to tell them apart.
            capped = linprog(
                cost, A_ub=stacked, b_ub=offsets, bounds=free + [(0, 1)], method="highs"
            )
            if capped.status != 0:
                raise ShapeError(self._no_interior("its half-spaces have no common point"))
            center, radius = capped.x[:dim], math.inf
        elif result.status == 2:
            raise ShapeError(self._no_interior("its half-spaces have no common point"))
        else:
            raise ShapeError(f"could not find the polytope's inscribed ball: {result.message}")
        tolerance = 1e-12 * float(np.abs(offsets).max())
        if not radius > tolerance:
            raise ShapeError(
                self._no_interior(f"its largest inscribed ball has radius {radius:.3g}")
            )
        self.chebyshev_center = center
        self.chebyshev_radius = radius

        # Bounds: minimise and maximise each coordinate (the polytope is feasible by now).
        bounds = np.array([np.full(dim, -np.inf), np.full(dim, np.inf)])
        for axis in range(dim):
            for side, sign in ((0, 1.0), (1, -1.0)):
                cost = np.zeros(dim)
                cost[axis] = sign
                result = linprog(cost, A_ub=normals, b_ub=offsets, bounds=free, method="highs")
                if result.status == 0:
                    bounds[side, axis] = result.x[axis]
                elif result.status not in (3, 4):  # 3, 4: unbounded along this side
                    raise ShapeError(
                        f"could not bound the polytope along axis {axis}: {result.message}"
                    )
        self._bounds = bounds

    @staticmethod
    def _no_interior(why: str) -> str:
        return (
            f"polytope has no interior: {why}; check the signs of the normals (they point "
            "outwards) and the offsets"
        )

    def _distance(self, points):
        return (points @ self.normals.T - self.offsets).max(axis=1)

    def _distance_and_gradient(self, points):
        excess = points @ self.normals.T - self.offsets
        active = np.argmax(excess, axis=1)
        return excess[np.arange(points.shape[0]), active], self.normals[active]

    def _exact_volume(self):
        if not self.is_bounded:
            return math.inf
        if not self._volume_done:
            self._volume = self._hull_volume()
            self._volume_done = True
        return self._volume

    def _hull_volume(self) -> float | None:
        """Volume by Qhull, or None (a Monte Carlo estimate then) where that is too costly."""
        # Qhull wants half-spaces as A x + c <= 0 and a strictly interior point.
        halfspaces = np.hstack([self.normals, -self.offsets[:, None]])
        try:
            vertices = HalfspaceIntersection(halfspaces, self.chebyshev_center).intersections
            # The triangulation of the hull grows steeply with the vertex count and dimension.
            if len(vertices) > _max_hull_vertices(self.dim):
                return None
            return float(ConvexHull(vertices).volume)
        except QhullError:  # precision trouble with many nearly coplanar vertices
            return None

    def _leaf(self):
        # The count comes first, so the kernel reads it (Simplex inherits this).
        return library.polytope, [len(self.offsets), *self.normals.ravel(), *self.offsets]

    def __repr__(self):
        if self.normals.size <= 64:
            return (
                f"ConvexPolytope(normals={_floats(self.normals)}, offsets={_floats(self.offsets)})"
            )
        return f"ConvexPolytope(<{len(self.offsets)} half-spaces in {self.dim}-D>)"


class Simplex(ConvexPolytope):
    """The simplex spanned by ``d + 1`` affinely independent vertices.

    Its ``d + 1`` facets are oriented outward, so the distance is exact inside and a lower bound
    outside, as for any :class:`ConvexPolytope`; the inscribed ball, bounds and volume are closed
    forms (no linear programs).

    Parameters
    ----------
    vertices : (d + 1, d) array_like
        The vertices, in any order.
    """

    def __init__(self, vertices):
        vertices = np.asarray(vertices, dtype=np.float64)
        if (
            vertices.ndim != 2
            or vertices.shape[1] < 2
            or vertices.shape[0] != vertices.shape[1] + 1
        ):
            raise DimensionError(
                "vertices must have shape (d + 1, d) with d >= 2, e.g. 3 points in 2D, got an "
                f"array of shape {vertices.shape}"
            )
        if not np.all(np.isfinite(vertices)):
            raise ShapeError("vertices must be finite")
        dim = vertices.shape[1]
        edges = vertices[1:] - vertices[0]
        determinant = float(np.linalg.det(edges))
        size = float(np.ptp(vertices, axis=0).max())
        if not abs(determinant) > 1e-12 * size**dim:
            raise ShapeError(
                "degenerate simplex: its vertices lie (almost) in a common hyperplane "
                f"(|det| = {abs(determinant):.3g}); give d + 1 affinely independent points"
            )
        # Barycentric coordinates lambda_i(x) = g_i . x + c_i; the simplex is lambda_i >= 0.
        inverse = np.linalg.inv(edges.T)
        gradients = np.vstack([-inverse.sum(axis=0), inverse])
        constants = np.eye(dim + 1)[0] - gradients @ vertices[0]
        lengths = np.linalg.norm(gradients, axis=1)
        self._set_planes(-gradients / lengths[:, None], constants / lengths)
        self.vertices = vertices
        self._determinant = determinant
        # Incentre: distances lambda_i / |g_i| are all equal to r, and sum lambda_i = 1.
        self.chebyshev_radius = float(1.0 / lengths.sum())
        self.chebyshev_center = self.chebyshev_radius * (lengths @ vertices)
        self._bounds = np.array([vertices.min(axis=0), vertices.max(axis=0)])

    def _exact_volume(self):
        return abs(self._determinant) / math.factorial(self.dim)

    def __repr__(self):
        return f"Simplex(vertices={_floats(self.vertices)})"


# ---------------------------------------------------------------------- curved shapes
class Ellipsoid(_Analytic):
    """The axis-aligned ellipsoid ``sum_i ((x_i - c_i) / r_i)^2 <= 1``.

    The distance is the safe bound ``f = (|(x - c) / radii| - 1) * min(radii)``: zero on the
    surface, of the right sign and 1-Lipschitz, so ``|f|`` never exceeds the true distance.
    It is only a lower bound on both sides (``exact_inside = exact_outside = False``) and is
    exact when all radii are equal (a ball).

    Parameters
    ----------
    center : (d,) array_like
        Centre.
    radii : (d,) array_like
        Semi-axis lengths along the coordinate axes, positive (a scalar is broadcast).
    """

    exact_inside = False
    exact_outside = False
    convex = True

    def __init__(self, center, radii):
        self.center = _as_point(center, "center")
        self.dim = self.center.shape[0]
        self.radii = as_vector(radii, self.dim, "radii")
        if not np.all(self.radii > 0):
            raise ShapeError(f"radii must all be positive, got {self.radii.tolist()}")
        self._min_radius = float(self.radii.min())
        self._bounds = np.array([self.center - self.radii, self.center + self.radii])

    def _distance(self, points):
        scaled = (points - self.center) / self.radii
        return (np.linalg.norm(scaled, axis=1) - 1.0) * self._min_radius

    def _distance_and_gradient(self, points):
        scaled = (points - self.center) / self.radii
        distance = (np.linalg.norm(scaled, axis=1) - 1.0) * self._min_radius
        # d|y|/dx is proportional to y / radii; at the centre unit_rows picks the first axis.
        return distance, unit_rows(scaled / self.radii)

    def _exact_volume(self):
        return float(ball_volume(self.dim) * np.prod(self.radii))

    def _leaf(self):
        return library.ellipsoid, [*self.center, *self.radii, self._min_radius]

    def __repr__(self):
        return f"Ellipsoid(center={_floats(self.center)}, radii={_floats(self.radii)})"


class Torus(_Analytic):
    """A ring torus in 3D: the points within ``minor_radius`` of a circle of ``major_radius``.

    The circle lies in the plane ``z = center[2]``, around the z axis through ``center``.

    Parameters
    ----------
    center : (3,) array_like
        Centre of the ring.
    major_radius : float
        Radius of the ring's core circle.
    minor_radius : float
        Radius of the tube, ``0 < minor_radius < major_radius``.
    """

    exact_inside = True
    exact_outside = True
    convex = False

    def __init__(self, center, major_radius, minor_radius):
        center = np.asarray(center, dtype=np.float64)
        if center.shape != (3,):
            raise DimensionError(
                f"Torus is 3D only: center must have 3 coordinates, got shape {center.shape}"
            )
        self.center = _as_point(center, "center")
        self.dim = 3
        self.major_radius = _positive(major_radius, "major_radius")
        self.minor_radius = _positive(minor_radius, "minor_radius")
        if not self.minor_radius < self.major_radius:
            raise ShapeError(
                f"minor_radius ({self.minor_radius}) must be < major_radius "
                f"({self.major_radius}) for a ring torus"
            )
        reach = self.major_radius + self.minor_radius
        extent = np.array([reach, reach, self.minor_radius])
        self._bounds = np.array([self.center - extent, self.center + extent])

    def _from_core(self, points):
        """In-plane distance from the axis minus R (n,), and height (n,)."""
        offset = points - self.center
        rho = np.hypot(offset[:, 0], offset[:, 1])
        return offset, rho, rho - self.major_radius, offset[:, 2]

    def _distance(self, points):
        _, _, radial, height = self._from_core(points)
        return np.hypot(radial, height) - self.minor_radius

    def _distance_and_gradient(self, points):
        offset, rho, radial, height = self._from_core(points)
        core = np.hypot(radial, height)
        # Unit vector away from the axis in the ring's plane (any one on the axis itself).
        planar = np.zeros_like(points)
        planar[:, :2] = offset[:, :2]
        planar = _unit_or(planar, rho, np.array([1.0, 0.0, 0.0]))
        # Away from the nearest core point; on the core circle itself, outward in the plane.
        away = radial[:, None] * planar
        away[:, 2] = height
        gradient = _unit_or(away, core, np.zeros(3))
        on_core = core == 0
        gradient[on_core] = planar[on_core]
        return core - self.minor_radius, gradient

    def _exact_volume(self):
        return 2 * math.pi**2 * self.major_radius * self.minor_radius**2

    def _leaf(self):
        return library.torus, [*self.center, self.major_radius, self.minor_radius]

    def __repr__(self):
        return (
            f"Torus(center={_floats(self.center)}, major_radius={self.major_radius!r}, "
            f"minor_radius={self.minor_radius!r})"
        )
