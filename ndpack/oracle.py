"""The distance-oracle protocol: the one abstraction every shape in ndpack meets.

Sign convention
---------------
``distance(x) < 0`` inside the shape, ``> 0`` outside, ``0`` on its boundary.

Exactness rules
---------------
1. Every oracle is *conservative*: its distance ``f`` has the right sign and is 1-Lipschitz,
   so ``|f(x)|`` never exceeds the true Euclidean distance from ``x`` to the boundary. A ball of
   radius ``-f(c)`` around an interior point ``c`` is therefore always inside the shape. This is
   the only property packing validity relies on.
2. ``exact_inside`` says that ``f`` equals the true distance at every interior point;
   ``exact_outside`` the same for exterior points. Where a flag is False, ``f`` is only a lower
   bound of the distance there: spheres stay inside, but may be smaller than the largest that fits.
3. CSG nodes derive their flags from their children (see :mod:`ndpack.shapes.csg`): for example
   inside an intersection the distance stays exact, inside a union it is a lower bound.

Gradient
--------
``gradient(x)`` is the unit vector along which ``f`` grows fastest. At an interior point it points
towards the nearest boundary point, at an exterior point away from it; for an exact oracle the
nearest boundary point is ``x - f(x) * gradient(x)``. Shapes give it analytically where known;
otherwise it comes from central finite differences.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from .errors import BoundsError, DimensionError, OracleError, ParameterError, ShapeError

#: Points sampled for a Monte Carlo volume when none is given.
DEFAULT_VOLUME_SAMPLES = 400_000


@dataclass(frozen=True)
class Volume:
    """A shape's volume (area in 2D) with its standard error.

    Attributes
    ----------
    value : float
        The volume, ``inf`` for unbounded shapes.
    error : float
        One standard error of a Monte Carlo estimate; ``0.0`` when the value is exact.
    """

    value: float
    error: float = 0.0

    @property
    def exact(self) -> bool:
        return self.error == 0.0

    def __float__(self) -> float:
        return float(self.value)


def ball_volume(dim: int, radius=1.0) -> Any:
    """Volume of the ``dim``-ball of the given radius (scalar or array): pi^(d/2) / Gamma(d/2 + 1) r^d."""
    unit = math.pi ** (dim / 2) / math.gamma(dim / 2 + 1)
    return unit * np.asarray(radius, dtype=np.float64) ** dim


def as_points(points, dim: int) -> np.ndarray:
    """Return ``points`` as a C-contiguous ``(n, dim)`` float64 array, or raise a clear error.

    A single point of shape ``(dim,)`` becomes ``(1, dim)``.
    """
    array = np.asarray(points, dtype=np.float64)
    if array.ndim == 1 and array.shape[0] == dim:
        array = array[None, :]
    if array.ndim != 2 or array.shape[1] != dim:
        raise DimensionError(
            f"expected points of shape (n, {dim}) for a {dim}-D shape, got an array of shape "
            f"{array.shape}; pass one row per point with {dim} coordinates"
        )
    if not np.isfinite(array).all():
        bad = int(np.flatnonzero(~np.isfinite(array).all(axis=1))[0])
        raise ParameterError(f"points must be finite; row {bad} is {array[bad].tolist()}")
    return np.ascontiguousarray(array)


def as_vector(values, dim: int, name: str) -> np.ndarray:
    """Return ``values`` as a finite ``(dim,)`` float64 vector (a scalar is broadcast)."""
    array = np.asarray(values, dtype=np.float64)
    if array.ndim == 0:
        array = np.full(dim, float(array))
    if array.shape != (dim,):
        raise DimensionError(f"{name} must have {dim} entries, got shape {array.shape}")
    if not np.all(np.isfinite(array)):
        raise ShapeError(f"{name} must be finite, got {array}")
    return array


def unit_rows(vectors: np.ndarray) -> np.ndarray:
    """Normalise the rows of ``vectors`` (n, d); zero rows become the first axis."""
    norms = np.linalg.norm(vectors, axis=1, keepdims=True)
    out = np.zeros_like(vectors)
    ok = norms[:, 0] > 0
    out[ok] = vectors[ok] / norms[ok]
    out[~ok, 0] = 1.0
    return out


class Oracle:
    """Base class of every distance oracle (shapes, CSG nodes, meshes, plug-ins).

    Subclasses set ``dim`` and ``_bounds`` and implement :meth:`_distance`; they may override
    :meth:`_gradient` or :meth:`_distance_and_gradient` with analytic forms and
    :meth:`_exact_volume` where the volume is known in closed form. The public methods validate
    their input; the underscored ones take a trusted ``(n, dim)`` float64 array and are what the
    packing backends call in their hot loops.

    Attributes
    ----------
    dim : int
        Dimension of the space the shape lives in.
    exact_inside, exact_outside : bool
        Whether the distance is exact (not only a lower bound) inside / outside the shape.
    convex : bool
        Whether the shape is known to be convex (lets offsets keep exactness).
    """

    dim: int
    exact_inside: bool = False
    exact_outside: bool = False
    convex: bool = False
    #: Whether the shape has no scalar kernel, so runs on the NumPy backend alone (a NumPy plug-in).
    numpy_only: bool = False
    #: Whether the shape is the empty set (:class:`ndpack.shapes.empty.Empty`, whose ``reason`` says why).
    is_empty_set: bool = False
    _bounds: np.ndarray

    # ------------------------------------------------------------------ the protocol
    @property
    def bounds(self) -> np.ndarray:
        """(2, dim) float64: lower and upper corner of an axis-aligned box enclosing the shape.

        Entries may be infinite for unbounded shapes (half-spaces, complements).
        """
        return self._bounds

    @property
    def diagonal(self) -> float:
        """The length of the diagonal of :attr:`bounds` (infinite for an unbounded shape): the
        unit of relative figures such as a covering's protrusion."""
        return float(np.linalg.norm(np.ptp(self._bounds, axis=0)))

    @property
    def is_bounded(self) -> bool:
        return bool(np.all(np.isfinite(self._bounds)))

    @property
    def exact(self) -> bool:
        """True when the interior distance is exact (what packing quality depends on)."""
        return self.exact_inside

    def distance(self, points) -> np.ndarray:
        """Signed distance, negative inside.

        Parameters
        ----------
        points : (n, dim) array_like

        Returns
        -------
        (n,) float64
        """
        return self._distance(as_points(points, self.dim))

    def gradient(self, points) -> np.ndarray:
        """Unit direction of steepest increase of the distance, (n, dim) float64."""
        return self._gradient(as_points(points, self.dim))

    def distance_and_gradient(self, points) -> tuple[np.ndarray, np.ndarray]:
        """Both at once: ((n,) distances, (n, dim) unit gradients)."""
        return self._distance_and_gradient(as_points(points, self.dim))

    def contains(self, points) -> np.ndarray:
        """(n,) bool: whether each point is strictly inside."""
        return self.distance(points) < 0

    def nearest_boundary_point(self, points) -> np.ndarray:
        """(n, dim) float64: ``x - f(x) * grad f(x)``; exact where the oracle is exact."""
        points = as_points(points, self.dim)
        distances, gradients = self._distance_and_gradient(points)
        return points - distances[:, None] * gradients

    # ------------------------------------------------------------------ to implement
    def _distance(self, points: np.ndarray) -> np.ndarray:
        raise NotImplementedError

    def _gradient(self, points: np.ndarray) -> np.ndarray:
        return self._finite_difference_gradient(points)

    def _distance_and_gradient(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return self._distance(points), self._gradient(points)

    def _step_inside(self, points: np.ndarray, lower: np.ndarray, upper: np.ndarray, steps: int,
                     margin: float) -> tuple[np.ndarray, np.ndarray]:
        """Points outside stepped across the boundary, each confined to its box: a relaxed projection.

        A point outside steps ``1.5 * (distance + margin)`` against the gradient, clipped to its box
        ``lower``, ``upper``, until it is inside or ``steps`` steps are taken (the ProtoSphere
        driver's start of cells near the boundary: ``RunState._step_in``).

        Parameters
        ----------
        points, lower, upper : (k, d) float64
        steps : int
        margin : float

        Returns
        -------
        points : (k, d) float64 and depth : (k,) float64
            Where each ended, and its depth (minus the signed distance: positive inside).
        """
        trial = points.copy()
        active = np.arange(len(trial))
        for _ in range(steps):
            distance, gradient = self._distance_and_gradient(trial[active])
            outside = distance >= 0
            active, distance, gradient = active[outside], distance[outside], gradient[outside]
            if len(active) == 0:
                break
            trial[active] = np.clip(trial[active] - 1.5 * (distance + margin)[:, None] * gradient,
                                    lower[active], upper[active])
        return trial, -self._distance(trial)

    def _exact_volume(self) -> float | None:
        """Closed-form volume, or None when only a Monte Carlo estimate is possible."""
        return None

    def _kernel_advice(self) -> str:
        """What to do where no compiled backend can run this shape: the end of the message of
        :func:`ndpack.kernels.compiled.compiled_program`."""
        if any(node.numpy_only for node in tree(self)):
            return ("Use backend='numpy', or write the plug-in as a scalar function (ndpack.ScalarFunction) "
                    "so it compiles for every backend")
        return "Use backend='numpy'"

    # ------------------------------------------------------------------ shared machinery
    @property
    def scale(self) -> float:
        """A length typical of the shape and its coordinates, for tolerances and steps."""
        finite = self._bounds[np.isfinite(self._bounds)]
        if finite.size == 0:
            return 1.0
        extent = np.ptp(self._bounds, axis=0) if self.is_bounded else np.zeros(1)
        return float(max(np.abs(finite).max(), extent.max(), 1e-300))

    def _finite_difference_gradient(self, points: np.ndarray) -> np.ndarray:
        # Central differences: 2 * dim evaluations, error O(h^2) on smooth parts. The step follows
        # the shape's size, but stays above float64 resolution at its coordinates.
        extent = float(np.ptp(self._bounds, axis=0).max()) if self.is_bounded else 1.0
        step = max(1e-6 * extent, 1e-10 * self.scale)
        gradient = np.empty_like(points)
        for axis in range(self.dim):
            shifted = points.copy()
            shifted[:, axis] += step
            forward = self._distance(shifted)
            shifted[:, axis] -= 2 * step
            gradient[:, axis] = forward - self._distance(shifted)
        return unit_rows(gradient)

    def volume(self, samples: int | None = None, seed: int = 0) -> Volume:
        """Volume (area in 2D): exact where known, else a Monte Carlo estimate with its error.

        Parameters
        ----------
        samples : int, optional
            Monte Carlo sample count (default 400,000); ignored for exact volumes.
        seed : int
            Seed of the Monte Carlo sampler, for reproducible estimates.
        """
        exact = self._exact_volume()
        if exact is not None:
            return Volume(float(exact), 0.0)
        samples = DEFAULT_VOLUME_SAMPLES if samples is None else int(samples)
        key = (samples, seed)
        cache = self.__dict__.setdefault("_volume_cache", {})
        if key not in cache:
            cache[key] = monte_carlo_volume(self, samples, seed)
        return cache[key]

    def __repr__(self) -> str:
        return f"{type(self).__name__}(dim={self.dim})"

    # ------------------------------------------------------------------ CSG
    # Operands may be other libraries' shapes (manifold3d, trimesh, shapely): see as_oracle. The
    # shapes these methods build subclass Oracle, so their modules register them in OPERATIONS
    # (below) when imported, and this module imports none of them.
    def union(self, *others: Oracle) -> Oracle:
        return _operation("union")(self, *others)

    def intersection(self, *others: Oracle) -> Oracle:
        return _operation("intersection")(self, *others)

    def difference(self, *others: Oracle) -> Oracle:
        return _operation("difference")(self, *others)

    def __ror__(self, other) -> Oracle:
        return _operation("as_oracle")(other).union(self)

    def __rand__(self, other) -> Oracle:
        return _operation("as_oracle")(other).intersection(self)

    def __rsub__(self, other) -> Oracle:
        return _operation("as_oracle")(other).difference(self)

    def complement(self) -> Oracle:
        return _operation("complement")(self)

    def translate(self, offset) -> Oracle:
        return _operation("translate")(self, offset)

    def rotate(self, matrix, center=None) -> Oracle:
        """Rotate (or reflect) by an orthogonal ``(dim, dim)`` matrix about ``center`` (default origin)."""
        return _operation("rotate")(self, matrix, center)

    def scale_by(self, factor: float, center=None) -> Oracle:
        """Scale uniformly by ``factor`` about ``center`` (default origin)."""
        return _operation("scale_by")(self, factor, center)

    def offset(self, amount: float) -> Oracle:
        """Dilate by ``amount`` (> 0) or erode by ``-amount`` (< 0)."""
        return _operation("offset")(self, amount)

    def shell(self, thickness: float) -> Oracle:
        """The layer of the given thickness centred on the boundary."""
        return _operation("shell")(self, thickness)

    def smooth_union(self, other: Oracle, blend: float) -> Oracle:
        """Union with a fillet of width ``blend``; its distance is a lower bound."""
        return _operation("smooth_union")(self, other, blend)

    # Through the methods, so that a subclass's own (the empty set's) serve the operators too.
    def __or__(self, other) -> Oracle:
        return self.union(other)

    def __and__(self, other) -> Oracle:
        return self.intersection(other)

    def __sub__(self, other) -> Oracle:
        return self.difference(other)

    def __invert__(self) -> Oracle:
        return self.complement()


def tree(shape):
    """``shape`` and every shape below it (CSG nodes keep theirs in ``children``, ``child`` or ``a``/``b``)."""
    yield shape
    below = list(getattr(shape, "children", ()))
    below += [getattr(shape, name) for name in ("child", "a", "b") if hasattr(shape, name)]
    for part in below:
        if isinstance(part, Oracle):  # Capsule's a and b are points, not shapes
            yield from tree(part)


def monte_carlo_volume(oracle: Oracle, samples: int, seed: int) -> Volume:
    """Estimate the volume by uniform sampling of the bounds; the error is one standard error."""
    if not oracle.is_bounded:
        return Volume(math.inf, 0.0)
    lower, upper = oracle.bounds
    box_volume = float(np.prod(upper - lower))
    rng = np.random.default_rng(seed)
    inside = 0
    chunk = 65_536
    for start in range(0, samples, chunk):
        count = min(chunk, samples - start)
        points = lower + (upper - lower) * rng.random((count, oracle.dim))
        inside += int(np.count_nonzero(oracle._distance(points) < 0))
    fraction = inside / samples
    # Half a sample of Laplace smoothing keeps the error non-zero for empty or full boxes.
    smoothed = (inside + 0.5) / (samples + 1.0)
    error = box_volume * math.sqrt(smoothed * (1 - smoothed) / samples)
    return Volume(box_volume * fraction, error)


#: What an Oracle's CSG methods and operators build, by name: ``"union"``, ``"intersection"``,
#: ``"difference"``, ``"complement"``, ``"translate"``, ``"rotate"``, ``"scale_by"``,
#: ``"offset"``, ``"shell"``, ``"smooth_union"`` (:mod:`ndpack.shapes.csg`) and ``"as_oracle"``
#: (another library's shape as an ndpack one, :mod:`ndpack.shapes.adapters`). Those modules
#: register their functions (:func:`operation`) when imported, and ``import ndpack`` imports
#: them: the shapes they build subclass Oracle, so this module cannot import them (fogleman/sdf's
#: operators register themselves the same way).
OPERATIONS: dict = {}


def operation(name: str):
    """Decorator: register a function as the operation ``name`` of :data:`OPERATIONS`."""
    def register(function):
        OPERATIONS[name] = function
        return function
    return register


def _operation(name: str):
    try:
        return OPERATIONS[name]
    except KeyError:  # only where the package's __init__ did not run, which Python never skips
        raise RuntimeError(f"no shape operation {name!r} is registered: import ndpack first") from None


def parts(shape: Oracle, others) -> list:
    """``shape`` and ``others`` as ndpack shapes (other libraries' converted), of one dimension."""
    parts = [shape, *map(_operation("as_oracle"), others)]
    check_compatible(*parts)
    return parts


def check_compatible(*oracles: Oracle) -> int:
    """Return the common dimension of ``oracles`` or raise a :class:`DimensionError`."""
    for oracle in oracles:
        if not isinstance(oracle, Oracle):
            raise TypeError(
                f"expected an ndpack shape (an Oracle), got {type(oracle).__name__}; wrap a "
                "function with ndpack.Function(fn, dim=..., bounds=...)"
            )
    dims = {oracle.dim for oracle in oracles}
    if len(dims) != 1:
        names = ", ".join(f"{o!r}" for o in oracles)
        raise DimensionError(f"cannot combine shapes of different dimensions: {names}")
    return dims.pop()


def check_packable(shape: Oracle, samples_per_face: int = 512, seed: int = 0) -> None:
    """Raise a clear error if ``shape`` cannot be packed: unbounded, or bounds that cut it.

    The bounds are checked by sampling each face of the bounding box: no face point may lie
    strictly inside the shape (beyond a relative tolerance of 1e-9).
    """
    if not isinstance(shape, Oracle):
        check_compatible(shape)
    if shape.is_empty_set:
        raise ShapeError(f"there is nothing to pack: {getattr(shape, 'reason', 'the shape is empty')}")
    bounds = shape.bounds
    if bounds.shape != (2, shape.dim):
        raise BoundsError(f"bounds must have shape (2, {shape.dim}), got {bounds.shape}")
    if not shape.is_bounded:
        raise BoundsError(
            f"{shape!r} is unbounded (bounds {bounds.tolist()}); intersect it with a bounded "
            "shape, e.g. shape & ndpack.Box(lower, upper)"
        )
    if np.any(bounds[1] <= bounds[0]):
        raise BoundsError(f"bounds are empty along some axis: lower {bounds[0]}, upper {bounds[1]}")
    rng = np.random.default_rng(seed)
    lower, upper = bounds
    tolerance = 1e-9 * shape.scale
    period = getattr(shape, "period", None)
    faces = []
    for axis in range(shape.dim):
        if period is not None and period.axes[axis]:
            continue  # the faces of a periodic axis wrap around: they cut nothing
        for side in (lower, upper):
            points = lower + (upper - lower) * rng.random((samples_per_face, shape.dim))
            points[:, axis] = side[axis]
            faces.append(points)
    if not faces:
        return
    # One query for every face: a mesh's costs about the same for 512 points as for 6 x 512.
    points = np.concatenate(faces)
    distances = shape._distance(points)
    inside = np.flatnonzero(distances < -tolerance)
    if len(inside):
        start = inside[0] // samples_per_face * samples_per_face  # the first face with a point inside
        worst = start + int(np.argmin(distances[start : start + samples_per_face]))
        raise BoundsError(
            f"the bounds of {shape!r} do not enclose it: the point "
            f"{np.round(points[worst], 6).tolist()} on the bounding box is inside "
            f"(distance {distances[worst]:.3g}); enlarge the bounds"
        )


def check_finite(values: np.ndarray, points: np.ndarray, what: str) -> np.ndarray:
    """Raise an :class:`OracleError` naming the first offending point if ``values`` is not finite."""
    bad = ~np.isfinite(values) if values.ndim == 1 else ~np.isfinite(values).all(axis=1)
    if bad.any():
        first = int(np.flatnonzero(bad)[0])
        raise OracleError(
            f"{what} returned NaN or infinity for {int(bad.sum())} of {len(values)} points, first at "
            f"{points[first].tolist()}; make it return a finite signed distance everywhere "
            "in its bounds"
        )
    return values
