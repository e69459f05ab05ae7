"""Plug-in oracles: a user's vectorised NumPy function used as a shape.

Example::

    @ndpack.plugin(dim=2, bounds=[[-1, -1], [1, 1]])
    def disc(p):
        return np.linalg.norm(p, axis=1) - 1.0

    disc.distance([[0.0, 0.0]])  # array([-1.])
"""

from __future__ import annotations

import operator
from typing import Callable

import numpy as np

from ..errors import BoundsError, DimensionError, OracleError, ParameterError
from ..oracle import Oracle, check_finite, tree, unit_rows

#: Where the points of each ray of :func:`steepest_on_rays` lie, as fractions of its length
#: after its start: evenly (a steep region covering about 1/16 of the ray is met), and closer and
#: closer to its end, at 1 - 2^-k down to 1e-7 (an overstated hole sits just inside the end of
#: the ray that the value sized, where a point meets it once it spans a factor of 2 in 1 - t).
RAY_FRACTIONS = np.union1d(np.arange(1, 17) / 16, 1.0 - 0.5 ** np.arange(5, 24))
#: A slope above ``1 + SLOPE_TOLERANCE`` is not rounding: the function is steeper than a distance.
SLOPE_TOLERANCE = 1e-6
#: Pairs of a ray closer than this fraction of the shape's scale are left out: the rounding of
#: two values (about 1e-16 of the scale) would make up a slope of up to 1e-10 over them.
SHORTEST_PAIR = 1e-6
#: Rays per call of the distance in :func:`steepest_on_rays` (bounds its memory).
RAY_CHUNK = 1 << 14


def _check_values(values, expected: tuple, points: np.ndarray, what: str, hint: str) -> np.ndarray:
    """Turn a user function's result into float64 of the ``expected`` shape, finite, or raise.

    ``what`` names the function in messages, ``hint`` says what it should return.
    """
    try:
        array = np.asarray(values, dtype=np.float64)
    except (TypeError, ValueError) as error:
        raise OracleError(
            f"{what} returned {type(values).__name__}, which is not an array of numbers "
            f"({error}); {hint}"
        ) from None
    if array.shape != expected:
        extra = ""
        if array.ndim == 0:
            extra = " (a single number: it must be vectorised, taking all points at once)"
        raise OracleError(
            f"{what} returned an array of shape {array.shape} for {len(points)} points, expected "
            f"{expected}{extra}; {hint}"
        )
    check_finite(array, points, what)
    return array


class Function(Oracle):
    """A user's vectorised distance function, used as a shape.

    Parameters
    ----------
    fn : callable
        ``fn(points) -> distances`` with ``points`` a ``(n, dim)`` float64 array and distances a
        ``(n,)`` array: negative inside, positive outside, and 1-Lipschitz (see
        :meth:`check_lipschitz`). It receives a copy of the points, so it may modify them.
    dim : int
        Dimension of the space, at least 1.
    bounds : (2, dim) array_like
        Lower and upper corner of a finite box that encloses the shape.
    exact_inside, exact_outside : bool
        Promise that ``fn`` is the true distance inside / outside (not only a lower bound).
    gradient : callable, optional
        ``gradient(points) -> (n, dim)`` direction of steepest increase (normalised here).
        Without it the gradient comes from central finite differences.
    name : str, optional
        Name used in messages; defaults to the function's ``__name__``.

    Notes
    -----
    Exceptions raised inside ``fn`` or ``gradient`` propagate unchanged.
    """

    convex = False
    numpy_only = True  # a NumPy function: no compiled backend runs it (ScalarFunction's do)
    _slope_checked = False  # set by check_plugin_slopes once its slopes were checked

    def __init__(
        self, fn, dim, bounds, exact_inside=False, exact_outside=False, gradient=None, name=None
    ):
        if not callable(fn):
            raise TypeError(
                f"fn must be a callable taking an (n, dim) array of points, got "
                f"{type(fn).__name__}; pass the function itself, e.g. Function(my_fn, ...), "
                "not the result of calling it"
            )
        if gradient is not None and not callable(gradient):
            raise TypeError(
                f"gradient must be a callable taking an (n, dim) array of points, or None, got "
                f"{type(gradient).__name__}"
            )
        if isinstance(dim, bool):  # True is an int, but surely a mistake here
            raise DimensionError(f"dim must be an integer >= 1, got {dim!r}")
        try:
            dim = operator.index(dim)
        except TypeError:
            raise DimensionError(f"dim must be an integer >= 1, got {dim!r}") from None
        if dim < 1:
            raise DimensionError(f"dim must be an integer >= 1, got {dim}")

        try:
            bounds = np.array(bounds, dtype=np.float64)
        except (TypeError, ValueError) as error:
            raise BoundsError(f"bounds must be a (2, {dim}) array of numbers: {error}") from None
        if bounds.shape != (2, dim):
            raise BoundsError(
                f"bounds must have shape (2, {dim}), [lower corner, upper corner], got shape "
                f"{bounds.shape}"
            )
        if not np.all(np.isfinite(bounds)):
            raise BoundsError(f"bounds must be finite, got {bounds.tolist()}")
        if np.any(bounds[0] >= bounds[1]):
            raise BoundsError(
                f"bounds need lower < upper along every axis, got lower {bounds[0].tolist()}, "
                f"upper {bounds[1].tolist()}"
            )

        self.fn = fn
        self.gradient_fn = gradient
        self.dim = dim
        self._bounds = bounds
        self.exact_inside = bool(exact_inside)
        self.exact_outside = bool(exact_outside)
        self.name = str(name) if name is not None else getattr(fn, "__name__", type(fn).__name__)
        if getattr(fn, "__doc__", None):
            self.__doc__ = fn.__doc__  # help() on a decorated function shows its own docstring

    def __call__(self, points) -> np.ndarray:
        """Same as :meth:`distance`, so a decorated function can still be called."""
        return self.distance(points)

    # ------------------------------------------------------------------ oracle
    def _distance(self, points: np.ndarray) -> np.ndarray:
        # A copy, so that a function working in place cannot corrupt the caller's array.
        values = self.fn(points.copy())
        return _check_values(
            values, (len(points),), points, f"the distance function {self.name!r}",
            "return one distance per point, shape (n,)",
        )

    def _gradient(self, points: np.ndarray) -> np.ndarray:
        if self.gradient_fn is None:
            return self._finite_difference_gradient(points)
        values = self.gradient_fn(points.copy())
        values = _check_values(
            values, (len(points), self.dim), points, f"the gradient function of {self.name!r}",
            f"return one gradient per point, shape (n, {self.dim})",
        )
        return unit_rows(values)

    # ------------------------------------------------------------------ checks
    def check_lipschitz(self, samples: int = 2000, seed: int = 0) -> float:
        """Check on random pairs of points that the function is 1-Lipschitz.

        Half the pairs are independent uniform points of the bounds, half are close pairs
        (a step of 1e-3 of the box diagonal), which measure the local slope. Then, from
        ``samples // 2`` more random points ``x``, rays run to where the value says the boundary
        is (``|f(x)|`` along the gradient, towards the boundary), with ``RAY_FRACTIONS`` points on
        each (:func:`steepest_on_rays`): a small region where the function is steep (a small
        hole whose distance is overstated) is rarely hit by random pairs, but the rays of every
        point whose value is set by it run into it.

        Parameters
        ----------
        samples : int
            Number of pairs.
        seed : int
            Seed of the sampler.

        Returns
        -------
        float
            The largest observed ratio ``|f(x) - f(y)| / |x - y|``.

        Raises
        ------
        OracleError
            If some pair has a ratio above ``1 + 1e-6``.
        """
        if isinstance(samples, bool) or int(samples) != samples or samples < 1:
            raise ParameterError(f"samples must be a positive integer, got {samples!r}")
        samples = int(samples)
        rng = np.random.default_rng(seed)
        lower, upper = self._bounds
        first = lower + (upper - lower) * rng.random((samples, self.dim))
        second = lower + (upper - lower) * rng.random((samples, self.dim))
        close = samples // 2
        step = 1e-3 * float(np.linalg.norm(upper - lower))
        directions = unit_rows(rng.standard_normal((close, self.dim)))
        second[:close] = np.clip(first[:close] + step * directions, lower, upper)

        values = self._distance(np.concatenate([first, second]))
        change = np.abs(values[:samples] - values[samples:])
        length = np.linalg.norm(first - second, axis=1)
        moved = length > 0  # clipping can, rarely, bring a point back onto its partner
        ratios = change[moved] / length[moved]
        largest = 0.0
        if ratios.size:
            worst = int(np.argmax(ratios))
            largest = float(ratios[worst])
            self._refuse_steep(largest, first[moved][worst], second[moved][worst])

        starts = lower + (upper - lower) * rng.random((max(samples // 2, 1), self.dim))
        values = self._distance(starts)
        # Towards the boundary: up the gradient from inside, down it from outside.
        towards = -np.sign(values)[:, None] * self._gradient(starts)
        slopes, x, y = steepest_on_rays(self._distance, starts, towards, np.abs(values), self._bounds,
                                        SHORTEST_PAIR * self.scale)
        worst = int(np.argmax(slopes))
        self._refuse_steep(float(slopes[worst]), x[worst], y[worst])
        return max(largest, float(slopes[worst]))

    def _refuse_steep(self, slope: float, x: np.ndarray, y: np.ndarray) -> None:
        """Raise :class:`OracleError` if ``slope``, found between points ``x`` and ``y`` (d,), is above 1."""
        if slope > 1 + SLOPE_TOLERANCE:
            raise OracleError(
                f"the distance function {self.name!r} is not a conservative distance (Lipschitz "
                f"constant at least {slope:.6g}, between {np.round(x, 6).tolist()} and "
                f"{np.round(y, 6).tolist()}); divide it by a bound on its slope (at least {slope:.6g}) "
                "to make it one"
            )

    def __repr__(self) -> str:
        return f"Function({self.name!r}, dim={self.dim})"


def plugin(dim: int, bounds=None, **flags) -> Callable[[Callable], Function]:
    """Decorator that turns a vectorised distance function into a :class:`Function`.

    Parameters
    ----------
    dim : int
    bounds : (2, dim) array_like
        Required; the default only lets a bare ``@plugin`` get a clear error.
    **flags
        ``exact_inside``, ``exact_outside``, ``gradient``, ``name``: passed to :class:`Function`.

    Examples
    --------
    >>> @plugin(dim=2, bounds=[[-1, -1], [1, 1]])
    ... def disc(p):
    ...     return np.linalg.norm(p, axis=1) - 1.0
    >>> disc
    Function('disc', dim=2)
    """
    if callable(dim):
        raise TypeError(
            "plugin needs its arguments: write @ndpack.plugin(dim=..., bounds=...) above the "
            "function, not a bare @ndpack.plugin"
        )
    if bounds is None:
        raise BoundsError(f"plugin needs bounds: a (2, {dim}) box [lower corner, upper corner]")

    def wrap(fn) -> Function:
        return Function(fn, dim, bounds, **flags)

    return wrap


def check_plugin_slopes(shape) -> None:
    """Run :meth:`Function.check_lipschitz` on every plug-in in ``shape``'s tree, once each.

    A plug-in steeper than 1 breaks what packing validity rests on, and verification cannot see
    it (it asks the same function), so :func:`ndpack.pack` checks before packing. The result is
    kept on the plug-in: packing it again costs nothing.
    """
    for node in tree(shape):
        if isinstance(node, Function) and not node._slope_checked:
            node.check_lipschitz()
            node._slope_checked = True


def steepest_on_rays(distance, starts, directions, lengths, bounds=None, shortest=0.0):
    """The steepest slope of ``distance`` along each ray, and the pair of points where it is.

    Each ray holds its start and the points ``x_j = start + t_j * length * direction``, ``t_j``
    in ``RAY_FRACTIONS`` (clipped to ``bounds``); its slope is the largest ``|f(x) - f(y)| /
    |x - y|`` over the pairs (start, ``x_j``) and (``x_{j-1}``, ``x_j``). A 1-Lipschitz function has
    slopes of at most 1; from a sphere's centre to its surface, a larger one means the sphere
    the function sized may reach outside the shape.

    Parameters
    ----------
    distance : callable
        ``(m, d)`` float64 points to ``(m,)`` float64 values.
    starts : (k, d) float64
    directions : (k, d) float64
        Unit rows (a zero row gives a ray of one point, slope 0).
    lengths : (k,) float64
        Non-negative.
    bounds : (2, d) float64, optional
        Points are clipped to this box, where the function is defined.
    shortest : float
        Pairs closer than this are left out (see ``SHORTEST_PAIR``).

    Returns
    -------
    slopes : (k,) float64
    first, second : (k, d) float64
        The pair of each ray where its slope was found.
    """
    starts = np.asarray(starts, dtype=np.float64)
    count, dim = starts.shape
    slopes = np.zeros(count)
    first, second = starts.copy(), starts.copy()
    fractions = np.concatenate([[0.0], RAY_FRACTIONS])
    last = len(RAY_FRACTIONS)
    # Pairs (start, x_j) and (x_{j-1}, x_j): two a point.
    before = np.concatenate([np.zeros(last, int), np.arange(last)])
    after = np.concatenate([np.arange(1, last + 1)] * 2)
    for begin in range(0, count, RAY_CHUNK):
        rows = slice(begin, min(begin + RAY_CHUNK, count))
        steps = (lengths[rows, None] * directions[rows])[:, None, :] * fractions[None, :, None]
        points = starts[rows, None, :] + steps
        if bounds is not None:
            points = np.clip(points, bounds[0], bounds[1])
        values = distance(points.reshape(-1, dim)).reshape(len(steps), last + 1)
        rise = np.abs(values[:, after] - values[:, before])
        length = np.linalg.norm(points[:, after] - points[:, before], axis=2)
        apart = length > max(shortest, 0.0)
        ratio = np.where(apart, rise / np.where(apart, length, 1.0), 0.0)
        worst = np.argmax(ratio, axis=1)
        ray = np.arange(len(steps))
        slopes[rows] = ratio[ray, worst]
        first[rows] = points[ray, before[worst]]
        second[rows] = points[ray, after[worst]]
    return slopes, first, second
